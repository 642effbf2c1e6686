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

}  // namespace attitude_propagator
