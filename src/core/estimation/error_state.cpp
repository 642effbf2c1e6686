#include "attitude_propagator/estimation/error_state.h"

#include <cmath>

#include <Eigen/LU>

#include "attitude_propagator/estimation/measurement.h"
#include "attitude_propagator/estimation/orientation_covariance.h"
#include "attitude_propagator/limits.h"
#include "attitude_propagator/numerics/quaternion.h"

namespace attitude_propagator {

const char* measurementKindName(MeasurementKind kind) {
  switch (kind) {
    case MeasurementKind::Fix:
      return "fix";
    case MeasurementKind::Gravity:
      return "accel";
    case MeasurementKind::MagneticField:
      return "mag";
  }
  return "unknown";
}

ErrorState moveErrorState(const ErrorState& e, const Eigen::Quaterniond& D) {
  const Eigen::Matrix3d Ct = D.toRotationMatrix().transpose();
  ErrorState moved = e;
  moved.P_B = Ct * e.P_B * Ct.transpose();
  moved.P_Bb = Ct * e.P_Bb;
  return moved;
}

namespace {

/// The update for a residual of N rows, in fixed-size matrices: a measurement's update runs at
/// the sensor's rate, and Eigen's fixed sizes are unrolled where its dynamic ones loop
/// (measured: the gravity update took 1.2 us with dynamic sizes, bench_step_costs).
template <int N>
UpdateResult fuseRows(const Measurement& measurement, const Linearized& m, Eigen::Quaterniond& q_WB,
                      ErrorState& e, bool force) {
  using Matrix6 = Eigen::Matrix<double, 6, 6>;
  const Eigen::Matrix<double, N, 1> r = m.r;
  const Eigen::Matrix<double, N, 3> H_theta = m.H;
  const Eigen::Matrix<double, N, N> R = m.R;
  // x = (dtheta_B, db), H = [H_theta 0]: the error state's covariance in one matrix. Without a
  // bias estimate its blocks are zero and stay so.
  Matrix6 P;
  P << e.P_B, e.P_Bb, e.P_Bb.transpose(), e.P_bb;
  Eigen::Matrix<double, N, 6> H = Eigen::Matrix<double, N, 6>::Zero();
  H.template leftCols<3>() = H_theta;
  Eigen::Matrix<double, N, N> S = H_theta * e.P_B * H_theta.transpose() + R;
  S = 0.5 * (S + S.transpose());
  S.diagonal() = S.diagonal().cwiseMax(kMinInnovationVariance);
  // At most 3 x 3, symmetric positive definite (the floor): its inverse in closed form (Eigen's
  // cofactors for fixed sizes) costs less than a factorisation solved for six right-hand sides.
  const Eigen::Matrix<double, N, N> S_inv = S.inverse();
  UpdateResult result;
  result.d2 = r.dot(S_inv * r);
  if (!force && !(result.d2 <= measurement.gate())) return result;
  if (e.P_bb.isZero(0.0) && e.P_Bb.isZero(0.0)) {
    // No bias estimate: the attitude's own 3 x 3 update (the bias blocks would stay zero).
    Eigen::Matrix<double, 3, N> K = e.P_B * H_theta.transpose() * S_inv;
    K = measurement.correctionAxes(q_WB) * K;
    q_WB = (q_WB * expMap(K * r)).normalized();
    const Eigen::Matrix3d I_KH = Eigen::Matrix3d::Identity() - K * H_theta;
    e.P_B = clampOrientationCovariance(I_KH * e.P_B * I_KH.transpose() + K * R * K.transpose());
    result.accepted = true;
    return result;
  }
  // P H^T S^-1, with H's bias columns zero: P's first three columns times H_theta^T.
  Eigen::Matrix<double, 6, N> K = P.leftCols<3>() * H_theta.transpose() * S_inv;
  K.template topRows<3>() = measurement.correctionAxes(q_WB) * K.template topRows<3>();
  const Eigen::Matrix<double, 6, 1> dx = K * r;
  q_WB = (q_WB * expMap(dx.head<3>())).normalized();
  e.bias_B += dx.tail<3>();
  const Matrix6 I_KH = Matrix6::Identity() - K * H;
  P = I_KH * P * I_KH.transpose() + K * R * K.transpose();
  P = 0.5 * (P + P.transpose());
  // A gain that is not the optimal one (correctionAxes) can raise the attitude block above the
  // cap; its correlations with the bias are scaled with the clamp, not left as they were.
  e.P_Bb = P.topRightCorner<3, 3>();
  e.P_B = clampOrientationCovariance(P.topLeftCorner<3, 3>(), e.P_Bb);
  e.P_bb = P.bottomRightCorner<3, 3>();
  result.accepted = true;
  return result;
}

}  // namespace

void propagateErrorState(ErrorState& e, double h, const Eigen::Vector3d& w_step,
                         const Eigen::Matrix3d& R_B, bool estimate_bias, double random_walk) {
  if (!estimate_bias) {
    e.P_B = propagateOrientationCovariance(e.P_B, h, w_step, R_B);
    return;
  }
  // The error state (dtheta_B, db), numerics.md §7.1: the rate used is the measured one less
  // the estimate, so an error db of the estimate turns the attitude by -h J_r db:
  //   F = [Phi, -G; 0, I], G = h J_r(h w), Q = diag(G R G^T, sigma_rw^2 h I).
  const Eigen::Vector3d phi = h * w_step;
  const Eigen::Matrix3d Phi = expMap(phi).toRotationMatrix().transpose();
  const Eigen::Matrix3d G = h * rightJacobian(phi);
  const Eigen::Matrix3d PhiP_Bb = Phi * e.P_Bb;
  const Eigen::Matrix3d GP_bb = G * e.P_bb;
  const Eigen::Matrix3d cross = PhiP_Bb * G.transpose();
  const Eigen::Matrix3d P_B = Phi * e.P_B * Phi.transpose() - cross - cross.transpose() +
                              GP_bb * G.transpose() + G * R_B * G.transpose();
  e.P_Bb = PhiP_Bb - GP_bb;
  const double q = random_walk;
  e.P_bb += q * q * h * Eigen::Matrix3d::Identity();
  capBiasCovariance(e);
  // Clamped (an attitude variance at its cap, as the heading's after an alignment without the
  // field), the correlations with the bias are scaled with it, not dropped
  // (orientation_covariance.h).
  e.P_B = clampOrientationCovariance(P_B, e.P_Bb);
}

void capBiasCovariance(ErrorState& e) {
  // P_bb -> D P_bb D, P_Bb -> P_Bb D with D = diag(min(1, sigma_max / sigma_i)), a congruence
  // that keeps the joint covariance semi-definite and the correlations that move the estimate.
  const double ceiling = kMaxGyroBiasStddev * kMaxGyroBiasStddev;
  if (!(e.P_bb.diagonal().maxCoeff() > ceiling)) return;
  Eigen::Vector3d d;
  for (int i = 0; i < 3; ++i)
    d(i) = e.P_bb(i, i) > ceiling ? std::sqrt(ceiling / e.P_bb(i, i)) : 1.0;
  e.P_bb = d.asDiagonal() * e.P_bb * d.asDiagonal();
  e.P_bb.diagonal() = e.P_bb.diagonal().cwiseMin(ceiling);  // exactly, past the rounding
  e.P_Bb = e.P_Bb * d.asDiagonal();
}

UpdateResult fuseMeasurement(const Measurement& measurement, Eigen::Quaterniond& q_WB,
                             ErrorState& e, bool force) {
  const Linearized m = measurement.linearize(q_WB);
  switch (m.r.size()) {
    case 1:
      return fuseRows<1>(measurement, m, q_WB, e, force);
    case 2:
      return fuseRows<2>(measurement, m, q_WB, e, force);
    default:
      return fuseRows<3>(measurement, m, q_WB, e, force);
  }
}

}  // namespace attitude_propagator
