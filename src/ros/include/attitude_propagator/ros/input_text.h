// The log lines about the rate, torque and bias inputs: the warning for each refusal of an
// input decoder (input_decoders.h), why a message was not used with the count of its kind so
// far; the rates' mount once looked up; a gyro bias the engine rejected. Pure: the wrapper
// counts a refusal (countRefusal) and logs the lines, the warnings throttled per kind.
#pragma once

#include <optional>
#include <string>

#include <Eigen/Geometry>

#include "attitude_propagator/messages/input_decoders.h"
#include "attitude_propagator/ros/log_text.h"

namespace attitude_propagator {

/// The warning for `r` on `topic` (imu/data_raw, body_twist, torque, gyro_bias), counted from
/// `c` (the counters after the refusal); `body` is body_frame, `decoders` give each topic's
/// type. Nothing for NoOrientation (fixes only: fix_input.cpp logs them).
std::optional<LogLine> refusalText(const Refusal& r, const std::string& topic,
                                   const EngineCounters& c, const std::string& body,
                                   const InputDecoders& decoders);

/// The rates' mount, looked up: rates in frame `frame` rotated into `body` by `q_BS`.
std::string mountText(const std::string& frame, const std::string& body,
                      const Eigen::Quaterniond& q_BS);

/// A gyro bias the engine rejected (rejected_bias from `c`).
LogLine biasRejectedText(const EngineCounters& c);

}  // namespace attitude_propagator
