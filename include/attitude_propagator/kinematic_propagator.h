// Stateful kinematic propagation from timestamped body-rate samples, with the time and
// bad-input policy of DESIGN §6. No ROS: the node forwards stamps and rates to addSample().
#pragma once

#include <cstdint>

#include <Eigen/Geometry>

#include "attitude_propagator/integrator.h"
#include "attitude_propagator/kinematic_step.h"
#include "attitude_propagator/time_policy.h"

namespace attitude_propagator {

struct KinematicConfig {
  Integrator integrator = Integrator::Auto;  ///< Auto resolves to Cf4
  TimePolicy time_policy;
  Eigen::Quaterniond initial_q_WB = Eigen::Quaterniond::Identity();
};

class KinematicPropagator {
 public:
  /// Throws std::invalid_argument for a non-kinematic integrator, a non-positive or
  /// non-finite max_dt or backward_jump, or a zero / non-finite initial orientation.
  explicit KinematicPropagator(const KinematicConfig& config);

  /// Feeds the body rate w_B measured at time t. The first sample anchors time: the state at
  /// its stamp is the initial (or set) state. The orientation then holds at the newest stamp.
  /// A NaN or infinite stamp or rate is RejectedNonFinite, |w_B| > kMaxBodyRate (limits.h)
  /// RejectedOutOfRange; neither changes the state. Never throws.
  StampOutcome addSample(double t, const Eigen::Vector3d& w_B);

  /// Back to the initial orientation, waiting for an anchoring sample.
  void reset();

  /// Pins the state: orientation q_WB (normalised at any finite scale) and body rate w_B hold
  /// at time t (a new anchor). Throws std::invalid_argument, leaving the state unchanged, for
  /// non-finite values, a zero quaternion or |w_B| > kMaxBodyRate.
  void setState(double t, const Eigen::Quaterniond& q_WB, const Eigen::Vector3d& w_B);

  bool anchored() const { return anchored_; }
  /// Stamp the state holds at (0 before the first sample).
  double time() const { return window_.size() > 0 ? window_.newest().t : 0.0; }
  const Eigen::Quaterniond& orientation() const { return q_WB_; }
  /// Body rate of the newest sample.
  Eigen::Vector3d rate() const {
    return window_.size() > 0 ? window_.newest().w_B : Eigen::Vector3d::Zero();
  }
  /// |q| - 1 of the last step before renormalisation.
  double normError() const { return norm_error_; }
  std::uint64_t steps() const { return steps_; }
  Integrator integrator() const { return integrator_; }

 private:
  void anchor(double t, const Eigen::Vector3d& w_B);
  StampOutcome integrate(const RateSample& sample);
  Eigen::Quaterniond cf4FromAnchor(const RateWindow& window) const;

  Integrator integrator_;
  TimePolicy policy_;
  Eigen::Quaterniond initial_q_WB_;
  Eigen::Quaterniond q_WB_;
  Eigen::Quaterniond anchor_q_WB_;  // state at the anchor, for the cf4 start-up restart
  RateWindow window_;
  std::uint64_t samples_since_anchor_ = 0;
  bool anchored_ = false;
  double norm_error_ = 0.0;
  std::uint64_t steps_ = 0;
};

}  // namespace attitude_propagator
