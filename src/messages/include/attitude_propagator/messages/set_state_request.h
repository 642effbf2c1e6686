// The ~set_state service's request applied to the engine: its stamp (zero: now) and its state,
// given in world_frame's axes as the state is published, and the answer.
#pragma once

#include <ros/time.h>

#include "attitude_propagator/SetState.h"
#include "attitude_propagator/engine.h"
#include "attitude_propagator/numerics/world_convention.h"

namespace attitude_propagator {

/// Sets the state `request` asks for in `engine` at ROS time `now` (its stamp when the
/// request's is zero) and answers: success with "state set at T s", or the engine's refusal,
/// or with no time at all (sim time before the first /clock) asks for a stamp.
void applySetState(const SetState::Request& request, const ros::Time& now, WorldConvention world,
                   AttitudeEngine& engine, SetState::Response& response);

}  // namespace attitude_propagator
