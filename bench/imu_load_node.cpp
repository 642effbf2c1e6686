// bench_imu_load_node: the node benchmark's load generator as a separate process (messages
// reach attitude_propagator_node over TCP). Exits when all rates are done.
#include <ros/ros.h>

#include "imu_load_generator.h"

int main(int argc, char** argv) {
  ros::init(argc, argv, "imu_load_generator");
  ros::NodeHandle nh;
  ros::NodeHandle pnh("~");
  attitude_propagator_bench::ImuLoadGenerator generator(nh, pnh);
  ros::AsyncSpinner spinner(1);
  spinner.start();
  while (ros::ok() && !generator.done()) ros::WallDuration(0.1).sleep();
  return 0;
}
