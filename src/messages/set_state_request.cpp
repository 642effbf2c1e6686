#include "attitude_propagator/messages/set_state_request.h"

#include <string>

#include "attitude_propagator/messages/conversions.h"

namespace attitude_propagator {

void applySetState(const SetState::Request& request, const ros::Time& now, WorldConvention world,
                   AttitudeEngine& engine, SetState::Response& response) {
  response.success = false;
  const ros::Time stamp = request.header.stamp.isZero() ? now : request.header.stamp;
  if (stamp.isZero()) {
    response.message = "no ROS time yet (use_sim_time without /clock): give header.stamp";
    return;
  }
  // Given in world_frame's axes, as the state is published.
  const std::string error =
      engine.setState(toStamp(stamp), attitudeFromConvention(world, toEigen(request.orientation)),
                      bodyVectorFromConvention(world, toEigen(request.angular_velocity)));
  response.success = error.empty();
  response.message = error.empty() ? "state set at " + std::to_string(stamp.toSec()) + " s" : error;
}

}  // namespace attitude_propagator
