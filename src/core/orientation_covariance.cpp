#include "attitude_propagator/orientation_covariance.h"

#include <cmath>

#include <Eigen/Geometry>

#include "attitude_propagator/quaternion.h"

namespace attitude_propagator {

namespace {

Eigen::Matrix3d skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0.0, -v.z(), v.y(),  //
      v.z(), 0.0, -v.x(),   //
      -v.y(), v.x(), 0.0;
  return m;
}

// Below this squared angle the closed-form coefficients (1 - cos t)/t^2 and (t - sin t)/t^3
// lose all their digits to cancellation; the series 1/2 - t^2/24 and 1/6 - t^2/120 are exact
// to round-off there (next terms ~ t^4/720 < 1e-22).
constexpr double kSmallAngleSquared = 1e-10;

}  // namespace

Eigen::Matrix3d rightJacobian(const Eigen::Vector3d& phi) {
  const double t2 = phi.squaredNorm();
  double a;  // (1 - cos t) / t^2
  double b;  // (t - sin t) / t^3
  if (t2 < kSmallAngleSquared) {
    a = 0.5 - t2 / 24.0;
    b = 1.0 / 6.0 - t2 / 120.0;
  } else {
    const double t = std::sqrt(t2);
    a = (1.0 - std::cos(t)) / t2;
    b = (t - std::sin(t)) / (t2 * t);
  }
  const Eigen::Matrix3d K = skew(phi);
  return Eigen::Matrix3d::Identity() - a * K + b * K * K;
}

Eigen::Matrix3d propagateOrientationCovariance(const Eigen::Matrix3d& P, double h,
                                               const Eigen::Vector3d& w_B,
                                               const Eigen::Matrix3d& R) {
  const Eigen::Vector3d phi = h * w_B;
  const Eigen::Matrix3d Phi = expMap(phi).toRotationMatrix().transpose();
  const Eigen::Matrix3d G = h * rightJacobian(phi);
  const Eigen::Matrix3d next = Phi * P * Phi.transpose() + G * R * G.transpose();
  return 0.5 * (next + next.transpose());
}

Eigen::Matrix3d rotateCovariance(const Eigen::Matrix3d& P, const Eigen::Matrix3d& C) {
  return C * P * C.transpose();
}

}  // namespace attitude_propagator
