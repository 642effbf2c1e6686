#include "attitude_propagator/messages/input_roles.h"

#include <stdexcept>

#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <geometry_msgs/QuaternionStamped.h>
#include <geometry_msgs/Twist.h>
#include <geometry_msgs/TwistStamped.h>
#include <geometry_msgs/Vector3Stamped.h>
#include <geometry_msgs/Wrench.h>
#include <geometry_msgs/WrenchStamped.h>
#include <ros/message_traits.h>
#include <sensor_msgs/Imu.h>
#include <sensor_msgs/MagneticField.h>

namespace attitude_propagator {

namespace {

template <class... M>
std::vector<MessageTypeId> typesOf() {
  return {{ros::message_traits::datatype<M>(), ros::message_traits::md5sum<M>()}...};
}

}  // namespace

const std::vector<InputRoleRow>& inputRoleTable() {
  using R = InputRole;
  namespace g = geometry_msgs;
  static const std::vector<InputRoleRow> table = {
      {"imu/data_raw", R::Rate, Source::Imu, typesOf<sensor_msgs::Imu>()},
      {"body_twist", R::Rate, Source::Twist, typesOf<g::Twist, g::TwistStamped>()},
      {"torque", R::Torque, Source::Torque, typesOf<g::Wrench, g::WrenchStamped>()},
      {"gyro_bias", R::Bias, std::nullopt, typesOf<g::Vector3Stamped>()},
      {"orientation_fix", R::Fix, std::nullopt,
       typesOf<g::PoseWithCovarianceStamped, g::PoseStamped, g::QuaternionStamped,
               sensor_msgs::Imu>()},
      {"imu/mag", R::Field, std::nullopt, typesOf<sensor_msgs::MagneticField>()},
  };
  return table;
}

const InputRoleRow& inputRoleOf(Source source) {
  for (const InputRoleRow& row : inputRoleTable()) {
    if (row.source == source) return row;
  }
  throw std::logic_error("inputRoleOf: a source without a topic");
}

const InputRoleRow& inputRoleOf(InputRole role) {
  for (const InputRoleRow& row : inputRoleTable()) {
    if (row.role == role && !row.source) return row;
  }
  throw std::logic_error("inputRoleOf: not a role of one topic");
}

std::vector<MessageTypeId> typesOf(InputRole role) {
  std::vector<MessageTypeId> types;
  for (const InputRoleRow& row : inputRoleTable()) {
    if (row.role == role) types.insert(types.end(), row.types.begin(), row.types.end());
  }
  return types;
}

std::string typesText(InputRole role) {
  const std::vector<MessageTypeId> types = typesOf(role);
  std::string out;
  for (std::size_t i = 0; i < types.size(); ++i) {
    if (i > 0) out += i + 1 == types.size() ? " or " : ", ";
    out += types[i].first;
  }
  return out;
}

bool subscribed(const InputRoleRow& row, const NodeConfig& config) {
  switch (row.role) {
    case InputRole::Rate:
      return config.rate_input == (row.source == Source::Imu ? RateInput::Imu : RateInput::Twist);
    case InputRole::Torque:
      return config.model == Model::Dynamic && config.torque_input;
    case InputRole::Bias:
      return config.rate_input != RateInput::None;
    case InputRole::Fix:
      return true;
    case InputRole::Field:
      return config.parameters.use_mag;
  }
  return false;
}

}  // namespace attitude_propagator
