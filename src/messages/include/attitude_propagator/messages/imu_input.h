// What an IMU message's rate covariance says before anything else is read: REP-145's "no
// rate" and covariances that are not ones. The decoder (input_decoders.h: readImu,
// InputDecoders::imu) applies it first. And the IMU message an input carries to the engine's
// sink, for the node and propagate_bag alike to republish on imu/data.
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

/// An IMU message kept with its input (Input::payload) until the engine applies it, which in
/// the dynamic model may be after later messages arrived, with the rates' mount q_BS: what
/// imu/data republishes with the state at the input's stamp (OutputEncoder::imu).
struct ImuPayload {
  sensor_msgs::Imu::ConstPtr msg;
  Eigen::Quaterniond q_BS = Eigen::Quaterniond::Identity();
};

}  // namespace attitude_propagator
