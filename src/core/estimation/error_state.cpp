#include "attitude_propagator/estimation/error_state.h"

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
