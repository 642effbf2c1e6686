#!/usr/bin/env bash
# The core library (src/core, include/attitude_propagator without ros/) must not include ROS.
# On Debian the ROS headers sit in /usr/include, so the compiler alone would not notice.
cd "$(dirname "${BASH_SOURCE[0]}")/../.." || exit 1
pattern='#include *[<"](ros|tf2|tf2_ros|tf2_eigen|sensor_msgs|geometry_msgs|std_msgs|nodelet|pluginlib|diagnostic_updater|topic_tools|attitude_propagator/ros)/'
hits=$(grep -rnE "$pattern" src/core include/attitude_propagator --include='*.h' --include='*.cpp' \
  | grep -v '^include/attitude_propagator/ros/')
if [ -n "$hits" ]; then
  echo "ROS includes in the core library:"
  echo "$hits"
  exit 1
fi
