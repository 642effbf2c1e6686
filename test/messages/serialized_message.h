// A message serialised as a topic_tools::ShapeShifter or a rosbag::MessageInstance holds it,
// for the decoders' topic() entry points in the message layer's tests.
#pragma once

#include <algorithm>
#include <cstdint>
#include <string>
#include <vector>

#include <ros/message_traits.h>
#include <ros/serialization.h>

namespace messages_test {

/// A message serialised as a topic_tools::ShapeShifter or a rosbag::MessageInstance holds it:
/// its type, MD5 sum and bytes.
struct Serialized {
  std::string datatype, md5;
  std::vector<std::uint8_t> bytes;
  template <class M>
  static Serialized of(const M& msg) {
    Serialized s{ros::message_traits::datatype<M>(), ros::message_traits::md5sum<M>(), {}};
    s.bytes.resize(ros::serialization::serializationLength(msg));
    ros::serialization::OStream out(s.bytes.data(), s.bytes.size());
    ros::serialization::serialize(out, msg);
    return s;
  }
  const std::string& getDataType() const { return datatype; }
  const std::string& getMD5Sum() const { return md5; }
  std::uint32_t size() const { return static_cast<std::uint32_t>(bytes.size()); }
  template <class Stream>
  void write(Stream& stream) const {
    std::copy(bytes.begin(), bytes.end(), stream.advance(bytes.size()));
  }
};

}  // namespace messages_test
