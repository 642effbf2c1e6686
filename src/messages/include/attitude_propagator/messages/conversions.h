// Conversions between ROS messages and the core's Eigen types: the one place where message
// field order (x, y, z, w) meets Eigen's, built on tf2_eigen's toMsg/fromMsg.
#pragma once

#include <boost/array.hpp>

#include <ros/time.h>

#include <geometry_msgs/Quaternion.h>
#include <geometry_msgs/TransformStamped.h>
#include <geometry_msgs/Vector3.h>
#include <Eigen/Geometry>

#include "attitude_propagator/time/source_timeline.h"

namespace attitude_propagator {

Eigen::Vector3d toEigen(const geometry_msgs::Vector3& v);
/// Not normalised: the caller decides what a zero or non-unit quaternion means.
Eigen::Quaterniond toEigen(const geometry_msgs::Quaternion& q);
/// The rotation part of a transform.
Eigen::Quaterniond rotationOf(const geometry_msgs::TransformStamped& transform);

void toMsg(const Eigen::Vector3d& v, geometry_msgs::Vector3& out);
void toMsg(const Eigen::Quaterniond& q, geometry_msgs::Quaternion& out);

/// Row-major 3x3 covariance as in sensor_msgs/Imu and AttitudeState.
Eigen::Matrix3d covarianceFromMsg(const boost::array<double, 9>& c);
void covarianceToMsg(const Eigen::Matrix3d& P, boost::array<double, 9>& out);

bool allFinite(const geometry_msgs::Vector3& v);
bool allFinite(const boost::array<double, 9>& c);

/// ROS time and the engine's stamps (integer nanoseconds).
inline Stamp toStamp(const ros::Time& time) { return static_cast<Stamp>(time.toNSec()); }
inline ros::Time toRosTime(Stamp stamp) {
  ros::Time time;
  time.fromNSec(static_cast<std::uint64_t>(stamp));
  return time;
}

}  // namespace attitude_propagator
