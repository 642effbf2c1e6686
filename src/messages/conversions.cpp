#include "attitude_propagator/messages/conversions.h"

#include <cmath>

#include <tf2_eigen/tf2_eigen.h>

namespace attitude_propagator {

Eigen::Vector3d toEigen(const geometry_msgs::Vector3& v) {
  Eigen::Vector3d out;
  tf2::fromMsg(v, out);
  return out;
}

Eigen::Quaterniond toEigen(const geometry_msgs::Quaternion& q) {
  Eigen::Quaterniond out;
  tf2::fromMsg(q, out);
  return out;
}

Eigen::Quaterniond rotationOf(const geometry_msgs::TransformStamped& transform) {
  return toEigen(transform.transform.rotation);
}

void toMsg(const Eigen::Vector3d& v, geometry_msgs::Vector3& out) { tf2::toMsg(v, out); }

void toMsg(const Eigen::Quaterniond& q, geometry_msgs::Quaternion& out) { out = tf2::toMsg(q); }

Eigen::Matrix3d covarianceFromMsg(const boost::array<double, 9>& c) {
  return Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(c.data());
}

void covarianceToMsg(const Eigen::Matrix3d& P, boost::array<double, 9>& out) {
  Eigen::Map<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(out.data()) = P;
}

bool allFinite(const geometry_msgs::Vector3& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

bool allFinite(const boost::array<double, 9>& c) {
  for (double x : c) {
    if (!std::isfinite(x)) return false;
  }
  return true;
}

}  // namespace attitude_propagator
