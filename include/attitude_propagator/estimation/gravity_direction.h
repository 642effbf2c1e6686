// The accelerometer as a measurement of the gravity direction (docs/numerics.md §7.3). It measures
// the specific force f_B = C_BW (a_W - g_W), at rest the body's "up" times g (REP-145: gravity
// included). The prediction is u(q) = C_BW e_up; the residual is the rotation vector phi that turns
// u onto z = f_B / |f_B|, in a basis B = [e1 e2] of the plane normal to u: r = B^T phi (2 rows: a
// rotation about u is not observed). To first order u(q (x) Exp(dtheta)) = u + [u]x dtheta, so
// phi = -(I - u u^T) dtheta and H = -B^T. The noise is the force's covariance over |f|^2 in that
// plane, inflated by the linear acceleration seen lately (the engine's estimate of it, over g^2)
// and by ((|f| - g) / g)^2 per axis.
#pragma once

#include "attitude_propagator/estimation/measurement.h"

namespace attitude_propagator {

/// Standard gravity (m/s^2), the magnitude a resting accelerometer reads.
constexpr double kStandardGravity = 9.80665;

/// The unit "up" of the world (ENU z, the core's fixed frame) seen in the body: C_BW e_up.
Eigen::Vector3d bodyUp(const Eigen::Quaterniond& q_WB);

/// The rotation vector (body frame) that turns the unit vector `from` onto the unit vector `to`
/// by the shortest way: axis from x to, angle atan2(|from x to|, from . to); opposite vectors
/// turn about an axis normal to `from`.
Eigen::Vector3d rotationBetween(const Eigen::Vector3d& from, const Eigen::Vector3d& to);

/// Two unit vectors spanning the plane normal to the unit vector u (columns), with u x e1 = e2.
Eigen::Matrix<double, 3, 2> normalPlane(const Eigen::Vector3d& u);

class GravityDirection final : public Measurement {
 public:
  /// f_B: the specific force (m/s^2, body frame), not zero; covariance_B its noise (m^2/s^4);
  /// linear_variance: the linear acceleration's variance per axis (m^2/s^4) the sample is taken
  /// to carry; gate: chi-square with 2 degrees of freedom.
  GravityDirection(const Eigen::Vector3d& f_B, const Eigen::Matrix3d& covariance_B, double gate,
                   double linear_variance = 0.0);
  MeasurementKind kind() const override { return MeasurementKind::Gravity; }
  Linearized linearize(const Eigen::Quaterniond& q_WB) const override;
  double gate() const override { return gate_; }
  /// The least rotation that makes the predicted up the measured one (the heading kept); the
  /// tilt's covariance becomes the measurement's, the heading's stays, the tilt's correlations
  /// with the bias are dropped.
  void reset(Eigen::Quaterniond& q_WB, ErrorState& e) const override;
  /// The direction's noise (rad^2 per axis of the plane normal to z) around z = f / |f|.
  const Eigen::Matrix3d& directionCovariance() const { return direction_covariance_; }

 private:
  Eigen::Vector3d z_B_;
  Eigen::Matrix3d direction_covariance_;
  double gate_;
};

}  // namespace attitude_propagator
