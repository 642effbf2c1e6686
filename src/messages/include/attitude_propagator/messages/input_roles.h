// Every input topic of the node and the bag tools, in one table: its role, the name the node
// subscribes it under (relative to the node's namespace), and the message types it accepts.
// The decoders' type rules, the node's feedback-loop check and the bag tools' topic checks read
// it; docs/node.md's table of topics names the same (test_input_roles.cpp). The core knows the
// roles (Source: a rate or a torque; the bias, the fixes, the field have calls of their own),
// never these names.
#pragma once

#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "attitude_propagator/config/parameters.h"
#include "attitude_propagator/models/propagator.h"

namespace attitude_propagator {

enum class InputRole { Rate, Torque, Bias, Fix, Field };

/// A message type as ROS checks it: (datatype, MD5 sum).
using MessageTypeId = std::pair<std::string, std::string>;

struct InputRoleRow {
  const char* topic;  ///< relative to the node's namespace: imu/data_raw, body_twist, ...
  InputRole role;
  std::optional<Source> source;  ///< the engine's source of a rate or torque topic
  /// Accepted, in the order a message names them: a plain type before its stamped one. A topic
  /// with several takes the type of its first message (TopicType).
  std::vector<MessageTypeId> types;
};

/// Every input topic once: imu/data_raw, body_twist, torque, gyro_bias, orientation_fix,
/// imu/mag.
const std::vector<InputRoleRow>& inputRoleTable();
/// The row of a rate or torque source.
const InputRoleRow& inputRoleOf(Source source);
/// The row of the one topic of `role` other than rates and torques (Bias, Fix, Field).
const InputRoleRow& inputRoleOf(InputRole role);

/// The accepted types of every row of `role`, in the table's order (a tool reading a topic of
/// that role takes any of them).
std::vector<MessageTypeId> typesOf(InputRole role);
/// typesOf(role) as a message names them: "sensor_msgs/Imu, geometry_msgs/Twist or
/// geometry_msgs/TwistStamped".
std::string typesText(InputRole role);

/// Whether a node configured so takes the row's topic: the rates of `rate_input`; the torque
/// with `torque_input` in the dynamic model; the gyro bias when there are rates; the fixes
/// always; the field with `use_mag`.
bool subscribed(const InputRoleRow& row, const NodeConfig& config);

}  // namespace attitude_propagator
