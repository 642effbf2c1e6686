#include "attitude_propagator/models/sample_door.h"

#include <cmath>

#include "attitude_propagator/limits.h"

namespace attitude_propagator {

double doorBound(bool torque) { return torque ? kMaxTorque : kMaxBodyRate; }

std::optional<StampOutcome> refusedValue(const Eigen::Vector3d& value, double bound) {
  if (!value.allFinite()) return StampOutcome::RejectedNonFinite;
  // |w| h and |tau| h / I stay far inside the doubles below the bounds, so no step turns NaN.
  if (!(value.norm() <= bound)) return StampOutcome::RejectedOutOfRange;
  return std::nullopt;
}

std::optional<StampOutcome> refusedSample(double t, const Eigen::Vector3d& value, double bound) {
  if (!std::isfinite(t)) return StampOutcome::RejectedNonFinite;
  return refusedValue(value, bound);
}

}  // namespace attitude_propagator
