// What an IMU message's rate covariance says before anything else is read: REP-145's "no
// rate" and covariances that are not ones. The decoder (input_decoders.h: readImu,
// InputDecoders::imu) applies it first.
#pragma once

#include <optional>

#include <sensor_msgs/Imu.h>

#include "attitude_propagator/engine.h"
#include "attitude_propagator/estimation/orientation_covariance.h"

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

}  // namespace attitude_propagator
