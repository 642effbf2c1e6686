#include "attitude_propagator/kinematic_propagator.h"

#include <cmath>
#include <optional>
#include <stdexcept>
#include <string>

#include "attitude_propagator/limits.h"
#include "attitude_propagator/quaternion.h"

namespace attitude_propagator {

namespace {

Integrator resolveKinematic(Integrator requested) {
  if (requested == Integrator::Auto) return Integrator::Cf4;
  if (!supportsKinematic(requested)) {
    throw std::invalid_argument("integrator: '" + integratorName(requested) +
                                "' does not apply to the kinematic model; accepted: auto euler "
                                "rk4 exp exp2 cf4");
  }
  return requested;
}

void checkPolicy(const TimePolicy& policy) {
  if (!(std::isfinite(policy.max_dt) && policy.max_dt > 0.0)) {
    throw std::invalid_argument("max_dt: must be a positive number of seconds");
  }
  if (!(std::isfinite(policy.backward_jump) && policy.backward_jump > 0.0)) {
    throw std::invalid_argument("backward jump threshold: must be a positive number of seconds");
  }
}

/// q normalised at any finite scale (safeNormalized), or std::invalid_argument.
Eigen::Quaterniond checkedUnit(const Eigen::Quaterniond& q, const std::string& what) {
  const std::optional<Eigen::Quaterniond> unit = safeNormalized(q);
  if (!unit) {
    throw std::invalid_argument(what + ": must be a finite, non-zero quaternion [x, y, z, w]");
  }
  return *unit;
}

}  // namespace

KinematicPropagator::KinematicPropagator(const KinematicConfig& config)
    : integrator_(resolveKinematic(config.integrator)),
      policy_(config.time_policy),
      initial_q_WB_(checkedUnit(config.initial_q_WB, "initial_orientation")),
      q_WB_(initial_q_WB_),
      anchor_q_WB_(initial_q_WB_) {
  checkPolicy(policy_);
}

StampOutcome KinematicPropagator::addSample(double t, const Eigen::Vector3d& w_B) {
  if (!std::isfinite(t) || !w_B.allFinite()) return StampOutcome::RejectedNonFinite;
  // The door bound of limits.h: |w| h stays far inside the doubles, so no step turns NaN.
  if (!(w_B.norm() <= kMaxBodyRate)) return StampOutcome::RejectedOutOfRange;
  if (!anchored_) {
    anchor(t, w_B);
    return StampOutcome::Anchored;
  }
  switch (classifyStamp(time(), t, policy_)) {
    case StampClass::Stale:
      return StampOutcome::DroppedStale;
    case StampClass::BackwardJump:
      q_WB_ = initial_q_WB_;
      anchor(t, w_B);
      return StampOutcome::ResetBackwardJump;
    case StampClass::Gap:
      anchor(t, w_B);  // the orientation is held across the gap
      return StampOutcome::HeldGap;
    case StampClass::Forward:
      break;
  }
  return integrate({t, w_B});
}

void KinematicPropagator::reset() {
  q_WB_ = initial_q_WB_;
  anchor_q_WB_ = initial_q_WB_;
  window_.clear();
  samples_since_anchor_ = 0;
  anchored_ = false;
  norm_error_ = 0.0;
  steps_ = 0;
}

void KinematicPropagator::setState(double t, const Eigen::Quaterniond& q_WB,
                                   const Eigen::Vector3d& w_B) {
  if (!std::isfinite(t) || !w_B.allFinite()) {
    throw std::invalid_argument("set_state: stamp and angular velocity must be finite");
  }
  if (!(w_B.norm() <= kMaxBodyRate)) {
    throw std::invalid_argument("set_state: angular velocity above kMaxBodyRate = 1e5 rad/s");
  }
  q_WB_ = checkedUnit(q_WB, "set_state orientation");
  anchor(t, w_B);
}

void KinematicPropagator::anchor(double t, const Eigen::Vector3d& w_B) {
  window_.clear();
  window_.push({t, w_B});
  anchor_q_WB_ = q_WB_;
  samples_since_anchor_ = 1;
  anchored_ = true;
  steps_ = 0;
}

// The step is committed only when finite: a finite rate can still overflow (|w| h beyond the
// double range), and the state must never become NaN. The window is restored otherwise.
StampOutcome KinematicPropagator::integrate(const RateSample& sample) {
  const bool evicted = window_.push(sample);
  const bool restart =
      integrator_ == Integrator::Cf4 && samples_since_anchor_ + 1 == RateWindow::kCapacity;
  const Eigen::Quaterniond q =
      restart ? cf4FromAnchor(window_) : kinematicStep(integrator_, q_WB_, window_);
  const double n = q.norm();
  if (!std::isfinite(n) || n == 0.0) {
    window_.undoPush(evicted);
    return StampOutcome::RejectedNonFinite;
  }
  ++samples_since_anchor_;
  ++steps_;
  norm_error_ = n - 1.0;
  q_WB_ = Eigen::Quaterniond(q.coeffs() / n);
  return StampOutcome::Advanced;
}

// The first intervals after an anchor had fewer than four samples, so cf4 ran at lower order
// there; the constant error that leaves would dominate the fourth-order tail (REFERENCE §2:
// global order about 3.2). Once the fourth sample is in, integrate again from the anchor with
// the cubic through all four.
Eigen::Quaterniond KinematicPropagator::cf4FromAnchor(const RateWindow& window) const {
  Eigen::Quaterniond q = anchor_q_WB_;
  for (std::size_t i = 0; i + 2 < RateWindow::kCapacity; ++i) {
    q = kinematicStep(Integrator::Cf4, q, window, i).normalized();
  }
  return kinematicStep(Integrator::Cf4, q, window, RateWindow::kCapacity - 2);
}

}  // namespace attitude_propagator
