#include "attitude_propagator/messages/imu_input.h"

#include "attitude_propagator/messages/conversions.h"

namespace attitude_propagator {

std::optional<ImuRefusal> refuseImuRate(const sensor_msgs::Imu& msg) {
  if (msg.angular_velocity_covariance[0] == -1.0) return ImuRefusal{Rejection::NoRate};
  const RateCovarianceCheck check =
      checkRateCovariance(covarianceFromMsg(msg.angular_velocity_covariance));
  if (check != RateCovarianceCheck::Ok && check != RateCovarianceCheck::NonFinite) {
    return ImuRefusal{Rejection::BadCovariance, check};
  }
  return std::nullopt;
}

Input imuRateInput(const sensor_msgs::Imu& msg, const Eigen::Quaterniond& q_BS, Stamp stamp) {
  Input input;
  input.source = Source::Imu;
  input.stamp = stamp;
  input.value = q_BS * toEigen(msg.angular_velocity);
  const Eigen::Matrix3d R_S = covarianceFromMsg(msg.angular_velocity_covariance);
  input.rate_covariance_B =
      R_S.isZero(0.0) || !R_S.allFinite() ? R_S : rotateCovariance(R_S, q_BS.toRotationMatrix());
  return input;
}

}  // namespace attitude_propagator
