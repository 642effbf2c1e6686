// The input-role table (input_roles.h) against its readers: the decoders accept exactly a row's
// types, the core's sources name their rows, a node configured so takes the topics the table
// says, and docs/node.md's table of topics names every row's topic with its types.
#include <gtest/gtest.h>

#include <fstream>
#include <set>
#include <sstream>
#include <string>

#include <geometry_msgs/Twist.h>
#include <geometry_msgs/TwistStamped.h>
#include <geometry_msgs/Wrench.h>
#include <geometry_msgs/WrenchStamped.h>
#include <ros/message_traits.h>
#include <sensor_msgs/Imu.h>
#include <sensor_msgs/MagneticField.h>

#include "attitude_propagator/messages/fix_decoder.h"
#include "attitude_propagator/messages/input_roles.h"

namespace ap = attitude_propagator;

namespace {

std::string joined(const std::vector<ap::MessageTypeId>& types) {
  std::string out;
  for (std::size_t i = 0; i < types.size(); ++i) {
    if (i > 0) out += i + 1 == types.size() ? " or " : ", ";
    out += types[i].first;
  }
  return out;
}

TEST(InputRoles, EveryTopicOnceAndEachSourceNamesItsRow) {
  std::set<std::string> topics;
  for (const ap::InputRoleRow& row : ap::inputRoleTable()) {
    EXPECT_TRUE(topics.insert(row.topic).second) << row.topic;
    EXPECT_FALSE(row.types.empty()) << row.topic;
    if (row.source) {
      EXPECT_STREQ(ap::inputTopicName(*row.source), row.topic);
    }
  }
  EXPECT_EQ(topics.size(), 6u);
  EXPECT_EQ(ap::inputRoleOf(ap::Source::Imu).role, ap::InputRole::Rate);
  EXPECT_EQ(ap::inputRoleOf(ap::Source::Twist).role, ap::InputRole::Rate);
  EXPECT_EQ(ap::inputRoleOf(ap::Source::Torque).role, ap::InputRole::Torque);
  EXPECT_STREQ(ap::inputRoleOf(ap::InputRole::Fix).topic, "orientation_fix");
}

TEST(InputRoles, TheDecodersAcceptARowsTypesInItsOrder) {
  ap::InputDecoders decoders(ap::DecoderFrames{"base_link", "world", ap::TorqueFrame::Body});
  EXPECT_EQ(decoders.twistType().accepted(), joined(ap::inputRoleOf(ap::Source::Twist).types));
  EXPECT_EQ(decoders.torqueType().accepted(), joined(ap::inputRoleOf(ap::Source::Torque).types));
  ap::FixDecoder fixes(ap::FixFrames{"world", "base_link", ""});
  EXPECT_EQ(fixes.type().accepted(), joined(ap::inputRoleOf(ap::InputRole::Fix).types));
}

TEST(InputRoles, TypesTextNamesARolesTypesInTheTablesOrder) {
  EXPECT_EQ(ap::typesText(ap::InputRole::Rate),
            "sensor_msgs/Imu, geometry_msgs/Twist or geometry_msgs/TwistStamped");
  EXPECT_EQ(ap::typesText(ap::InputRole::Bias), "geometry_msgs/Vector3Stamped");
  // TopicType::accepting keeps a row's order: the first is the plain type, the second the
  // stamped one.
  const ap::TopicType torque = ap::TopicType::accepting(ap::inputRoleOf(ap::Source::Torque).types);
  EXPECT_EQ(torque.plainType(), "geometry_msgs/Wrench");
  EXPECT_EQ(torque.stampedType(), "geometry_msgs/WrenchStamped");
}

// A tool reading a topic of a role takes every type of every row of that role, as ROS names and
// checks them (datatype and MD5 sum from the message traits), in the table's order.
TEST(InputRoles, TypesOfARoleAreEveryTypeOfItsRowsAsRosChecksThem) {
  auto id = [](auto message) {
    using M = decltype(message);
    return ap::MessageTypeId{ros::message_traits::datatype<M>(), ros::message_traits::md5sum<M>()};
  };
  EXPECT_EQ(ap::typesOf(ap::InputRole::Rate),
            (std::vector<ap::MessageTypeId>{id(sensor_msgs::Imu{}), id(geometry_msgs::Twist{}),
                                            id(geometry_msgs::TwistStamped{})}));
  EXPECT_EQ(ap::typesOf(ap::InputRole::Torque),
            (std::vector<ap::MessageTypeId>{id(geometry_msgs::Wrench{}),
                                            id(geometry_msgs::WrenchStamped{})}));
  EXPECT_EQ(ap::typesOf(ap::InputRole::Field),
            (std::vector<ap::MessageTypeId>{id(sensor_msgs::MagneticField{})}));
}

// n-1, n, n+1 of each condition: a node takes exactly the topics of its configuration.
TEST(InputRoles, ANodeTakesTheTopicsOfItsConfiguration) {
  auto taken = [](const ap::NodeConfig& c) {
    std::set<std::string> out;
    for (const ap::InputRoleRow& row : ap::inputRoleTable()) {
      if (ap::subscribed(row, c)) out.insert(row.topic);
    }
    return out;
  };
  ap::NodeConfig c;
  EXPECT_EQ(taken(c), (std::set<std::string>{"imu/data_raw", "gyro_bias", "orientation_fix"}));
  c.rate_input = ap::RateInput::Twist;
  EXPECT_EQ(taken(c), (std::set<std::string>{"body_twist", "gyro_bias", "orientation_fix"}));
  c.rate_input = ap::RateInput::None;
  EXPECT_EQ(taken(c), (std::set<std::string>{"orientation_fix"}));
  c.torque_input = true;  // the kinematic model takes no torque
  EXPECT_EQ(taken(c), (std::set<std::string>{"orientation_fix"}));
  c.model = ap::Model::Dynamic;
  EXPECT_EQ(taken(c), (std::set<std::string>{"torque", "orientation_fix"}));
  c.parameters.use_mag = true;
  EXPECT_EQ(taken(c), (std::set<std::string>{"torque", "orientation_fix", "imu/mag"}));
}

// docs/node.md's "Topics" table: the row of each input topic names each of its types, in full
// or after the package's slash ("geometry_msgs/Twist or TwistStamped").
TEST(InputRoles, NodeMdsTableOfTopicsNamesEveryRowsTypes) {
  std::ifstream in(std::string(AP_PACKAGE_ROOT) + "/docs/node.md");
  ASSERT_TRUE(in) << "docs/node.md";
  std::stringstream text;
  text << in.rdbuf();
  for (const ap::InputRoleRow& row : ap::inputRoleTable()) {
    const std::string start = std::string("| `") + row.topic + "` |";
    const std::size_t at = text.str().find(start);
    ASSERT_NE(at, std::string::npos) << row.topic;
    const std::string line = text.str().substr(at, text.str().find('\n', at) - at);
    for (const ap::MessageTypeId& type : row.types) {
      const std::string name = type.first.substr(type.first.find('/') + 1);
      EXPECT_NE(line.find(name), std::string::npos) << row.topic << ": " << type.first;
    }
  }
}

}  // namespace
