// Covariance of the orientation error propagated through the kinematic steps, for the
// `orientation_covariance` of sensor_msgs/Imu (REP-145) and of AttitudeState.
//
// Error model: the true orientation is q_WB (x) Exp(dtheta_B), dtheta_B a small rotation
// vector in the body frame with covariance P. A step of length h with the measured body rate
// w_B (noise covariance R, rad^2/s^2, per sample) maps
//   q_WB <- q_WB (x) Exp(h w_B)
//   dtheta_B <- Phi dtheta_B + J_r(h w_B) h n,   Phi = Exp(h w_B)^T (as a rotation matrix),
// the standard right-invariant error propagation on SO(3) (Forster et al., "On-Manifold
// Preintegration", IEEE T-RO 2017, eqs. 7-8 and 59), so
//   P <- Phi P Phi^T + h^2 J_r R J_r^T.
// With a constant rate and zero R the error ellipsoid simply turns with the body; with zero
// rate P grows by h^2 R per sample (a random walk of the angle).
#pragma once

#include <Eigen/Core>

namespace attitude_propagator {

/// Right Jacobian of SO(3) at the rotation vector phi:
/// J_r = I - (1 - cos t)/t^2 [phi]x + (t - sin t)/t^3 [phi]x^2, t = |phi|; below t^2 = 1e-10
/// the series I - [phi]x/2 + [phi]x^2/6, exact to round-off there and free of 0/0.
Eigen::Matrix3d rightJacobian(const Eigen::Vector3d& phi);

/// One step of P <- Phi P Phi^T + h^2 J_r R J_r^T for the step h (s) with body rate w_B.
/// The result is symmetrised so round-off cannot make it drift from symmetry.
Eigen::Matrix3d propagateOrientationCovariance(const Eigen::Matrix3d& P, double h,
                                               const Eigen::Vector3d& w_B,
                                               const Eigen::Matrix3d& R);

/// The covariance in another frame: C P C^T, C the rotation from the body frame to it.
Eigen::Matrix3d rotateCovariance(const Eigen::Matrix3d& P, const Eigen::Matrix3d& C);

}  // namespace attitude_propagator
