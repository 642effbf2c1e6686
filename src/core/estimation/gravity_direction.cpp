#include "attitude_propagator/estimation/gravity_direction.h"

#include <cmath>

#include "attitude_propagator/estimation/orientation_covariance.h"
#include "attitude_propagator/numerics/quaternion.h"

namespace attitude_propagator {

Eigen::Vector3d bodyUp(const Eigen::Quaterniond& q_WB) {
  return q_WB.conjugate() * Eigen::Vector3d::UnitZ();
}

Eigen::Matrix<double, 3, 2> normalPlane(const Eigen::Vector3d& u) {
  // The coordinate axis least aligned with u keeps the cross product well away from zero.
  Eigen::Index least = 0;
  u.cwiseAbs().minCoeff(&least);
  const Eigen::Vector3d e1 = u.cross(Eigen::Vector3d::Unit(least)).normalized();
  Eigen::Matrix<double, 3, 2> B;
  B.col(0) = e1;
  B.col(1) = u.cross(e1);
  return B;
}

Eigen::Vector3d rotationBetween(const Eigen::Vector3d& from, const Eigen::Vector3d& to) {
  const Eigen::Vector3d axis = from.cross(to);
  const double s = axis.norm();
  const double angle = std::atan2(s, from.dot(to));
  if (s > 1e-12) return axis * (angle / s);
  if (from.dot(to) > 0.0) return Eigen::Vector3d::Zero();
  return angle * normalPlane(from).col(0);  // opposite: any axis normal to `from`
}

GravityDirection::GravityDirection(const Eigen::Vector3d& f_B, const Eigen::Matrix3d& covariance_B,
                                   double gate, double linear_variance)
    : z_B_(f_B.normalized()), gate_(gate) {
  const double f = f_B.norm();
  const double off = (f - kStandardGravity) / kStandardGravity;
  // A unit vector's noise is the force's across it over |f|^2; linear acceleration (|f| != g,
  // or the acceleration seen lately) inflates it.
  direction_covariance_ = covariance_B / (f * f) +
                          (off * off + linear_variance / (kStandardGravity * kStandardGravity)) *
                              Eigen::Matrix3d::Identity();
}

Linearized GravityDirection::linearize(const Eigen::Quaterniond& q_WB) const {
  const Eigen::Vector3d u = bodyUp(q_WB);
  const Eigen::Matrix<double, 3, 2> B = normalPlane(u);
  Linearized m;
  m.r = B.transpose() * rotationBetween(u, z_B_);
  m.H = -B.transpose();
  m.R = B.transpose() * direction_covariance_ * B;
  return m;
}

void GravityDirection::reset(Eigen::Quaterniond& q_WB, ErrorState& e) const {
  // Exp(delta) z = u turns the predicted up onto the measured one: delta = -phi.
  const Eigen::Vector3d u = bodyUp(q_WB);
  q_WB = (q_WB * expMap(-rotationBetween(u, z_B_))).normalized();
  const Eigen::Matrix<double, 3, 2> B = normalPlane(z_B_);
  const Eigen::Matrix3d vertical = z_B_ * z_B_.transpose();
  e.P_B =
      clampOrientationCovariance(B * (B.transpose() * direction_covariance_ * B) * B.transpose() +
                                 vertical * e.P_B * vertical);
  e.P_Bb = vertical * e.P_Bb;
}

}  // namespace attitude_propagator
