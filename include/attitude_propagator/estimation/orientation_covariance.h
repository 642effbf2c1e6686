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
// rate P grows by h^2 R per sample (a random walk of the angle), until it saturates at
// kMaxOrientationVariance (pi^2 rad^2, no knowledge of the orientation; limits.h).
#pragma once

#include <Eigen/Core>

namespace attitude_propagator {

/// Right Jacobian of SO(3) at the rotation vector phi:
/// J_r = I - (1 - cos t)/t^2 [phi]x + (t - sin t)/t^3 [phi]x^2, t = |phi|; below t^2 = 1e-10
/// the series I - [phi]x/2 + [phi]x^2/6, exact to round-off there and free of 0/0.
Eigen::Matrix3d rightJacobian(const Eigen::Vector3d& phi);

/// One step of P <- Phi P Phi^T + h^2 J_r R J_r^T for the step h (s) with body rate w_B,
/// passed through clampOrientationCovariance: symmetric, positive semi-definite and at most
/// kMaxOrientationVariance along any axis, whatever P, h, w_B and R are (non-finite input
/// gives the ceiling, "orientation unknown").
Eigen::Matrix3d propagateOrientationCovariance(const Eigen::Matrix3d& P, double h,
                                               const Eigen::Vector3d& w_B,
                                               const Eigen::Matrix3d& R);

/// The nearest (in eigenvalues) covariance of an orientation: symmetrised, eigenvalues clamped
/// to [0, kMaxOrientationVariance], diagonal in [0, kMaxOrientationVariance] exactly. A matrix
/// that is already one is returned unchanged but for the symmetrisation; a non-finite one
/// becomes kMaxOrientationVariance I.
Eigen::Matrix3d clampOrientationCovariance(const Eigen::Matrix3d& P);

/// The same clamp of the attitude block P of a joint covariance [P P_Bb; P_Bb^T P_bb] (P_Bb the
/// attitude error x bias error), keeping the joint matrix a covariance: where P's eigenvalue
/// lambda_i is clamped to c_i, P_Bb <- A P_Bb with A = V diag(sqrt(c_i / lambda_i)) V^T (1 on the
/// directions not clamped, 0 where lambda_i < 0), the congruence diag(A, I) of the joint
/// matrix. It keeps the joint matrix semi-definite and each eigen-direction's correlation
/// coefficients with the bias; P_bb needs no change. P_Bb is left exactly as it is when P is not
/// clamped, and zeroed when P is not finite.
Eigen::Matrix3d clampOrientationCovariance(const Eigen::Matrix3d& P, Eigen::Matrix3d& P_Bb);

/// What is wrong with a rate noise covariance (rad^2/s^2) taken from a message.
enum class RateCovarianceCheck {
  Ok,
  NonFinite,         ///< a NaN or infinite entry
  NotSymmetric,      ///< |R_ij - R_ji| above kCovarianceSymmetryTolerance of the largest entry
  NegativeVariance,  ///< a diagonal entry below zero
  VarianceTooLarge,  ///< a diagonal entry above kMaxRateVariance (limits.h)
  NotACovariance,    ///< |R_ij| > sqrt(R_ii R_jj): a correlation beyond one
};

/// Relative asymmetry tolerated in a message's covariance (drivers that print it with 7
/// significant digits).
constexpr double kCovarianceSymmetryTolerance = 1e-6;

/// Checks a rate covariance before it is used. The node rejects a message that fails (and
/// counts it): NonFinite as non-finite input, every other problem as a bad covariance
/// (Rejection::BadCovariance, `rejected_covariance`); the all-zero matrix (none given) is Ok.
RateCovarianceCheck checkRateCovariance(const Eigen::Matrix3d& R);
const char* rateCovarianceCheckName(RateCovarianceCheck check);

/// The covariance in another frame: C P C^T, C the rotation from the body frame to it.
Eigen::Matrix3d rotateCovariance(const Eigen::Matrix3d& P, const Eigen::Matrix3d& C);

}  // namespace attitude_propagator
