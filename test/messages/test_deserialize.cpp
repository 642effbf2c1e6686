// deserializeInto, the one way the node and the bag tools turn a serialised message into a
// reused one: every field back as written, and a TFMessage whose transform count cannot fit
// in its bytes (a damaged bag) refused before deserialising makes room for that many.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <vector>

#include <ros/serialization.h>
#include <sensor_msgs/Imu.h>
#include <tf2_msgs/TFMessage.h>

#include "attitude_propagator/messages/input_decoders.h"
#include "serialized_message.h"

namespace ap = attitude_propagator;
using messages_test::Serialized;

namespace {

TEST(DeserializeInto, GivesBackTheMessageThroughAReusedBuffer) {
  sensor_msgs::Imu imu;
  imu.header.frame_id = "imu";
  imu.header.stamp = ros::Time(12, 34);
  imu.angular_velocity.z = 0.25;
  std::vector<std::uint8_t> buffer;
  sensor_msgs::Imu out;
  ap::deserializeInto(Serialized::of(imu), buffer, out);
  EXPECT_EQ(out.header.frame_id, "imu");
  EXPECT_EQ(out.header.stamp, ros::Time(12, 34));
  EXPECT_EQ(out.angular_velocity.z, 0.25);
}

TEST(DeserializeInto, ATransformCountBeyondTheBytesIsRefused) {
  tf2_msgs::TFMessage tf;
  tf.transforms.resize(2);
  tf.transforms[1].child_frame_id = "imu";
  Serialized good = Serialized::of(tf);
  std::vector<std::uint8_t> buffer;
  tf2_msgs::TFMessage out;
  ap::deserializeInto(good, buffer, out);
  ASSERT_EQ(out.transforms.size(), 2u);
  EXPECT_EQ(out.transforms[1].child_frame_id, "imu");

  Serialized damaged = good;
  const std::uint32_t count = 0x7fffffff;  // would ask for 2^31 transforms
  std::memcpy(damaged.bytes.data(), &count, 4);
  EXPECT_THROW(ap::deserializeInto(damaged, buffer, out),
               ros::serialization::StreamOverrunException);
  // One transform more than the bytes hold: refused as well (76 bytes at least each).
  const std::uint32_t three = 3;
  std::memcpy(damaged.bytes.data(), &three, 4);
  EXPECT_THROW(ap::deserializeInto(damaged, buffer, out),
               ros::serialization::StreamOverrunException);
}

}  // namespace
