// The rate an IMU message carries, as the engine's input: the one reading of sensor_msgs/Imu
// shared by the node and the bag tools, so both refuse and rotate alike.
#pragma once

#include <optional>

#include <sensor_msgs/Imu.h>

#include <Eigen/Geometry>

#include "attitude_propagator/engine.h"
#include "attitude_propagator/orientation_covariance.h"

namespace attitude_propagator {

/// Why an IMU message's rate is unusable before its frame is looked at: REP-145's "no angular
/// velocity" (angular_velocity_covariance[0] == -1), or a covariance that is not one (not
/// symmetric, negative, too large; `check` says which). Non-finite values pass here: the
/// engine rejects and counts them as such.
struct ImuRefusal {
  Rejection why;
  RateCovarianceCheck check = RateCovarianceCheck::Ok;
};
std::optional<ImuRefusal> refuseImuRate(const sensor_msgs::Imu& msg);

/// The body-frame rate input of a message refuseImuRate() let through: ω_B = q_BS ω_S and
/// R_B = C_BS R_S C_BSᵀ (zero when the message gives none), at `stamp`.
Input imuRateInput(const sensor_msgs::Imu& msg, const Eigen::Quaterniond& q_BS, Stamp stamp);

}  // namespace attitude_propagator
