#include "attitude_propagator/numerics/quaternion.h"

#include <cmath>
#include <limits>
#include <stdexcept>

namespace attitude_propagator {

std::optional<Eigen::Quaterniond> safeNormalized(const Eigen::Quaterniond& q) {
  const Eigen::Vector4d& c = q.coeffs();
  if (!c.allFinite()) return std::nullopt;
  const double n2 = c.squaredNorm();
  if (n2 >= std::numeric_limits<double>::min() && n2 <= std::numeric_limits<double>::max()) {
    return Eigen::Quaterniond(Eigen::Vector4d(c / std::sqrt(n2)));  // as Eigen's normalized()
  }
  const double largest = c.cwiseAbs().maxCoeff();
  if (!(largest > 0.0)) return std::nullopt;
  const Eigen::Vector4d scaled = c / largest;  // each |component| <= 1, the largest exactly 1
  return Eigen::Quaterniond(Eigen::Vector4d(scaled / scaled.norm()));
}

Eigen::Vector3d logMap(const Eigen::Quaterniond& q) {
  // q and -q are one rotation: take w >= 0 so that the angle is in [0, pi].
  const double sign = q.w() < 0.0 ? -1.0 : 1.0;
  const double w = sign * q.w();
  const Eigen::Vector3d u = sign * q.vec();
  const double s = u.norm();
  // angle = 2 atan2(|u|, w), accurate at both ends, unlike acos(w) near 0 or asin(|u|) near pi.
  if (s < 1e-12) {
    // theta / sin(theta/2) -> 2 / w (1 + s^2/(6 w^2)) as s -> 0.
    return (2.0 / w) * (1.0 + s * s / (6.0 * w * w)) * u;
  }
  return (2.0 * std::atan2(s, w) / s) * u;
}

double rotationAngle(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b) {
  const Eigen::Quaterniond d = a.conjugate() * b;
  return 2.0 * std::atan2(d.vec().norm(), std::abs(d.w()));
}

Eigen::Vector4d wxyz(const Eigen::Quaterniond& q) {
  return Eigen::Vector4d(q.w(), q.x(), q.y(), q.z());
}

Eigen::Matrix4d leftMatrix(const Eigen::Quaterniond& q) {
  const double w = q.w(), x = q.x(), y = q.y(), z = q.z();
  Eigen::Matrix4d m;
  m << w, -x, -y, -z,  //
      x, w, -z, y,     //
      y, z, w, -x,     //
      z, -y, x, w;
  return m;
}

Eigen::Matrix4d rightMatrix(const Eigen::Quaterniond& q) {
  const double w = q.w(), x = q.x(), y = q.y(), z = q.z();
  Eigen::Matrix4d m;
  m << w, -x, -y, -z,  //
      x, w, z, -y,     //
      y, -z, w, x,     //
      z, y, -x, w;
  return m;
}

Eigen::Quaterniond pureQuaternion(const Eigen::Vector3d& v) {
  return Eigen::Quaterniond(0.0, v.x(), v.y(), v.z());
}

Eigen::Vector3d reflect(const Eigen::Vector3d& n, const Eigen::Vector3d& v) {
  if (!(std::abs(n.squaredNorm() - 1.0) < 1e-9)) {
    throw std::invalid_argument("reflect: the mirror normal n must be a unit vector");
  }
  return (pureQuaternion(n) * pureQuaternion(v) * pureQuaternion(n)).vec();
}

}  // namespace attitude_propagator
