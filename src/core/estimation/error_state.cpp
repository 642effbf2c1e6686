#include "attitude_propagator/estimation/error_state.h"

#include <Eigen/Cholesky>

#include "attitude_propagator/estimation/measurement.h"
#include "attitude_propagator/limits.h"
#include "attitude_propagator/orientation_covariance.h"
#include "attitude_propagator/quaternion.h"

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

UpdateResult fuseMeasurement(const Measurement& measurement, Eigen::Quaterniond& q_WB,
                             ErrorState& e, bool force) {
  using Matrix6 = Eigen::Matrix<double, 6, 6>;
  using Gain = Eigen::Matrix<double, 6, Eigen::Dynamic, 0, 6, 3>;
  using Jacobian6 = Eigen::Matrix<double, Eigen::Dynamic, 6, 0, 3, 6>;
  const Linearized m = measurement.linearize(q_WB);
  const Eigen::Index n = m.r.size();
  // x = (dtheta_B, db), H = [H_theta 0]: the error state's covariance in one matrix. Without a
  // bias estimate its blocks are zero and stay so.
  Matrix6 P;
  P << e.P_B, e.P_Bb, e.P_Bb.transpose(), e.P_bb;
  Jacobian6 H = Jacobian6::Zero(n, 6);
  H.leftCols<3>() = m.H;
  MeasurementNoise S = m.H * e.P_B * m.H.transpose() + m.R;
  S = 0.5 * (S + S.transpose());
  S.diagonal() = S.diagonal().cwiseMax(kMinInnovationVariance);
  const Eigen::LDLT<MeasurementNoise> ldlt(S);
  UpdateResult result;
  result.d2 = m.r.dot(ldlt.solve(m.r));
  if (!force && !(result.d2 <= measurement.gate())) return result;
  Gain K = ldlt.solve(H * P).transpose();  // P H^T S^-1 (P and S symmetric)
  K.topRows<3>() = measurement.correctionAxes(q_WB) * K.topRows<3>();
  const Eigen::Matrix<double, 6, 1> dx = K * m.r;
  q_WB = (q_WB * expMap(dx.head<3>())).normalized();
  e.bias_B += dx.tail<3>();
  const Matrix6 I_KH = Matrix6::Identity() - K * H;
  P = I_KH * P * I_KH.transpose() + K * m.R * K.transpose();
  P = 0.5 * (P + P.transpose());
  e.P_B = clampOrientationCovariance(P.topLeftCorner<3, 3>());
  e.P_Bb = P.topRightCorner<3, 3>();
  e.P_bb = P.bottomRightCorner<3, 3>();
  result.accepted = true;
  return result;
}

}  // namespace attitude_propagator
