// The door every rate and torque sample passes before it touches anything (limits.h): one rule,
// used by the engine before an input counts in its source's order, and by both propagators,
// which may also be driven alone.
#pragma once

#include <Eigen/Core>
#include <optional>

#include "attitude_propagator/time/time_policy.h"

namespace attitude_propagator {

/// Largest norm a sample may carry: kMaxTorque for a torque, kMaxBodyRate for a body rate.
double doorBound(bool torque);

/// Why a sample's value is refused: RejectedNonFinite when a component is NaN or infinite,
/// RejectedOutOfRange when its norm is above `bound`; empty when it may enter.
std::optional<StampOutcome> refusedValue(const Eigen::Vector3d& value, double bound);

/// The same for a sample at core time t: a NaN or infinite t is RejectedNonFinite too.
std::optional<StampOutcome> refusedSample(double t, const Eigen::Vector3d& value, double bound);

}  // namespace attitude_propagator
