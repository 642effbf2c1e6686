// The estimation room's state and its one update: the error state beside the attitude (the
// attitude error dtheta_B with covariance P_B, and with estimate_gyro_bias the bias estimate, its
// covariance and the cross-covariance), and the multiplicative EKF update every measurement goes
// through (docs/numerics.md §7.1, §7.3). A measurement is a Measurement (measurement.h); the
// engine decides where in time it is applied, this file what it does there.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace attitude_propagator {

class Measurement;

/// The error state beside the attitude: x = (dtheta_B, db), the true attitude q_WB (x)
/// Exp(dtheta_B), the true bias bias_B + db (numerics.md §7.1).
struct ErrorState {
  Eigen::Matrix3d P_B = Eigen::Matrix3d::Zero();     ///< attitude error, body frame (rad^2)
  Eigen::Matrix3d P_Bb = Eigen::Matrix3d::Zero();    ///< attitude error x bias error
  Eigen::Matrix3d P_bb = Eigen::Matrix3d::Zero();    ///< bias error ((rad/s)^2)
  Eigen::Vector3d bias_B = Eigen::Vector3d::Zero();  ///< estimated bias (rad/s), body frame
};

/// The error state seen from another instant of the same motion: with q_f = q_k (x) D, an error
/// at t_f is the error at t_k turned by D, dtheta_f = C(D)^T dtheta_k; the bias error is the
/// same. moveErrorState(e, D) gives the covariances at t_f from those at t_k; with D^-1 back.
ErrorState moveErrorState(const ErrorState& e, const Eigen::Quaterniond& D);

/// The error state over one rate step of length h with the step's rate w_step and the rate
/// noise R_B per sample (rad^2/s^2), numerics.md §7.1. Without a bias estimate P_B alone
/// (propagateOrientationCovariance); with it P <- F P F^T + Q, F = [Phi, -G; 0, I],
/// G = h J_r(h w), Q = diag(G R_B G^T, random_walk^2 h I), each axis' bias variance capped
/// (capBiasCovariance) and the attitude block clamped with its correlations
/// (clampOrientationCovariance).
void propagateErrorState(ErrorState& e, double h, const Eigen::Vector3d& w_step,
                         const Eigen::Matrix3d& R_B, bool estimate_bias, double random_walk);
/// Caps each axis' bias variance at kMaxGyroBiasStddev^2, its correlations scaled alike.
void capBiasCovariance(ErrorState& e);

/// What one update did.
struct UpdateResult {
  bool accepted = false;  ///< within the gate (or forced), and applied
  double d2 = 0.0;        ///< the squared Mahalanobis distance r^T S^-1 r of the innovation
};

/// The multiplicative EKF update with `measurement` at the attitude q_WB (both at the
/// measurement's stamp): the innovation r, its covariance S = H P H^T + R (diagonal floored at
/// kMinInnovationVariance), the gain K = P H^T S^-1 with its attitude rows turned into the
/// measurement's correction axes (a heading corrects heading only), the state q <- q (x)
/// Exp(dx_theta), bias += dx_b, and P in the Joseph form, valid for any gain. Unless `force`,
/// an innovation with r^T S^-1 r beyond the measurement's gate changes nothing.
UpdateResult fuseMeasurement(const Measurement& measurement, Eigen::Quaterniond& q_WB,
                             ErrorState& e, bool force = false);

}  // namespace attitude_propagator
