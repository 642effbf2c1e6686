#include "attitude_propagator/estimation/aiding.h"

#include <algorithm>
#include <cmath>

#include "attitude_propagator/estimation/gravity_direction.h"

namespace attitude_propagator {

const char* aidingOutcomeName(AidingOutcome outcome) {
  switch (outcome) {
    case AidingOutcome::Accepted:
      return "accepted";
    case AidingOutcome::Aligned:
      return "aligned";
    case AidingOutcome::Recovered:
      return "recovered";
    case AidingOutcome::Waiting:
      return "waiting";
    case AidingOutcome::RejectedGate:
      return "rejected_gate";
    case AidingOutcome::RejectedMagnitude:
      return "rejected_magnitude";
    case AidingOutcome::NotAligned:
      return "not_aligned";
    case AidingOutcome::TooOld:
      return "too_old";
    case AidingOutcome::Invalid:
      return "invalid";
    case AidingOutcome::QueueFull:
      return "queue_full";
    case AidingOutcome::Future:
      return "future";
    case AidingOutcome::OverBudget:
      return "over_budget";
    case AidingOutcome::Off:
      return "off";
  }
  return "unknown";
}

const std::array<AidingCounterInfo, 11>& aidingCounterTable() {
  using C = AidingCounters;
  static const std::array<AidingCounterInfo, 11> table{{
      {"accepted", "fused at its stamp (the rates since integrated again when it was late)", true,
       &C::accepted},
      {"aligned", "gravity: the first one, the tilt set from it (no initial_orientation)", true,
       &C::aligned},
      {"recovered",
       "applied as a reset after a run of gate rejections (the estimate was what was wrong)", true,
       &C::recovered},
      {"rejected_gate", "its innovation beyond the chi-square gate", false, &C::rejected_gate},
      {"rejected_magnitude",
       "gravity: |f| off g (the body accelerates); field: |m| or the dip off the field learned",
       false, &C::rejected_magnitude},
      {"not_aligned", "field: the tilt not known yet", false, &C::not_aligned},
      {"too_old", "stamped before the history kept (fix_history) or the anchor", false,
       &C::too_old},
      {"invalid", "non-finite, zero, or a covariance that is not one", false, &C::invalid},
      {"queue_full", "stamped ahead of the rates, and dropped: the waiting queue was full", false,
       &C::queue_full},
      {"future", "stamped more than max_future ahead of ROS time", false, &C::future},
      {"over_budget",
       "late, and its replay would exceed what one second may replay (design.md §6.9)", false,
       &C::over_budget},
  }};
  return table;
}

void AidingCounters::count(AidingOutcome outcome) {
  switch (outcome) {
    case AidingOutcome::Accepted:
      ++accepted;
      break;
    case AidingOutcome::Aligned:
      ++aligned;
      break;
    case AidingOutcome::Recovered:
      ++recovered;
      break;
    case AidingOutcome::RejectedGate:
      ++rejected_gate;
      break;
    case AidingOutcome::RejectedMagnitude:
      ++rejected_magnitude;
      break;
    case AidingOutcome::NotAligned:
      ++not_aligned;
      break;
    case AidingOutcome::TooOld:
      ++too_old;
      break;
    case AidingOutcome::Invalid:
      ++invalid;
      break;
    case AidingOutcome::QueueFull:
      ++queue_full;
      break;
    case AidingOutcome::Future:
      ++future;
      break;
    case AidingOutcome::OverBudget:
      ++over_budget;
      break;
    case AidingOutcome::Waiting:  // counted when the rates reach it
    case AidingOutcome::Off:
      break;
  }
}

double LinearVariance::fieldTiltVariance() const {
  // The filtered tilt is off by less than one sample's lean: the even spread, not the direction's.
  return spread / (kStandardGravity * kStandardGravity);
}

LinearVariance LinearAcceleration::observe(Stamp stamp, const Eigen::Vector3d& residual,
                                           double noise_trace, double window, double force) {
  if (!(window > 0.0)) return {};
  // Exponential window over the stamps, a = 1 - exp(-dt / window): a sample far off the average
  // (a bump) is the gate's to judge, a lasting acceleration (a turn) is the average's.
  const double dt = last_ ? std::max(0.0, static_cast<double>(stamp - *last_) * 1e-9) : 0.0;
  const double a = 1.0 - std::exp(-dt / window);
  mean_ += a * (residual.squaredNorm() - mean_);
  const double g2 = kStandardGravity * kStandardGravity;
  if (force > 0.0) {
    // The magnitude owes nothing to the estimate: its average starts from the first sample.
    const double sample = force * force - g2;
    magnitude_ += (last_ ? a : 1.0) * (sample - magnitude_);
  }
  if (!last_ || stamp > *last_) last_ = stamp;
  const double horizontal = force > 0.0 ? std::abs(magnitude_) : 0.0;
  LinearVariance v;
  // The sensor's noise adds its trace to both sides' means. The unexplained part, three axes'
  // sum, is spread over them; the magnitude goes whole into each axis.
  v.direction = std::max(0.0, std::max((mean_ - noise_trace) / 3.0, horizontal - noise_trace));
  v.spread = std::max(0.0, std::max(mean_, horizontal) - noise_trace) / 3.0;
  return v;
}

void TiltDisagreement::observe(Stamp stamp, const Eigen::Vector3d& up_W, double window) {
  const double dt = last_ ? std::max(0.0, static_cast<double>(stamp - *last_) * 1e-9) : 0.0;
  ++count_;
  // The plain mean of the first samples, the exponential window once it weighs less.
  const double fading = window > 0.0 ? 1.0 - std::exp(-dt / window) : 1.0;
  const double a = std::max(1.0 / static_cast<double>(count_), fading);
  mean_ += a * (up_W.head<2>() - mean_);
  if (!last_ || stamp > *last_) last_ = stamp;
}

bool RejectionRun::rejected(Stamp stamp, double seconds) {
  if (!since_ || stamp < *since_) since_ = stamp;
  if (static_cast<double>(stamp - *since_) * 1e-9 < seconds) return false;
  since_.reset();
  return true;
}

}  // namespace attitude_propagator
