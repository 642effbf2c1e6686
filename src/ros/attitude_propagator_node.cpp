// attitude_propagator_node: the wrapper in a process of its own.
#include <memory>
#include <stdexcept>

#include <ros/ros.h>

#include "attitude_propagator/ros/attitude_propagator_ros.h"
#include "attitude_propagator/ros/log_text.h"

int main(int argc, char** argv) {
  try {
    ros::init(argc, argv, "attitude_propagator");
  } catch (const ros::InvalidNameException& e) {
    // __name:=, __ns: or a remapping that is no ROS name (a space, a leading digit).
    ROS_FATAL(
        "attitude_propagator: refusing to start: invalid node name, namespace or "
        "remapping on the command line: %s",
        attitude_propagator::logText(e.what(), 4 * attitude_propagator::kLogTextBytes).c_str());
    return 1;
  }
  // Held here, not as temporaries: destroying the last NodeHandle shuts ROS down, and with it
  // the console the error below must reach.
  ros::NodeHandle nh;
  ros::NodeHandle pnh("~");
  std::unique_ptr<attitude_propagator::AttitudePropagatorRos> node;
  try {
    node = std::make_unique<attitude_propagator::AttitudePropagatorRos>(nh, pnh);
  } catch (const std::exception& e) {
    ROS_FATAL("attitude_propagator: refusing to start: %s", e.what());
    return 1;
  }
  ros::spin();
  return 0;
}
