// Our bag writer (src/tools/bag_writer.h) against rosbag's own readers: a bag of several chunks
// and connections (one latched), uncompressed and with LZ4, must pass `rosbag check` with no
// migration, read back through rosbag::View with every message, stamp and record time as
// written, be described by `rosbag info` with the counts written, and survive `rosbag reindex`
// (the index rebuilt from the chunks alone reads the same messages). The truth is the list of
// messages given to the writer; rosbag's tools are Debian's python3-rosbag (skipped, saying so,
// when it is not installed).
#include <algorithm>
#include <cstdint>
#include <string>
#include <vector>

#include <geometry_msgs/TwistStamped.h>
#include <gtest/gtest.h>
#include <ros/serialization.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/Imu.h>
#include <std_msgs/String.h>
#include <tf2_msgs/TFMessage.h>

#include "../../src/tools/bag_writer.h"
#include "scene_bags.h"

namespace {

using attitude_propagator::tools::BagOutput;
using bagtest::chunkData;
using bagtest::quote;
using bagtest::run;
using bagtest::TempDir;

/// rosbag's command-line tools through Debian's python (the python3 first on PATH may lack ROS).
std::string rosbagCommand(const std::string& arguments) {
  return "PATH=/usr/bin:$PATH rosbag " + arguments;
}

bool haveRosbag() { return run("PATH=/usr/bin:$PATH command -v rosbag").status == 0; }

template <class M>
std::vector<std::uint8_t> serialised(const M& msg) {
  std::vector<std::uint8_t> bytes(ros::serialization::serializationLength(msg));
  ros::serialization::OStream out(bytes.data(), bytes.size());
  ros::serialization::serialize(out, msg);
  return bytes;
}

/// What was given to the writer, one entry per message.
struct Expected {
  std::string topic, datatype, md5sum;
  ros::Time time;
  ros::Time stamp;  // the header stamp (zero for unstamped messages)
  std::vector<std::uint8_t> bytes;
};

constexpr std::uint32_t kSmallChunk = 8 * 1024;  // bytes: a few dozen messages per chunk
constexpr int kMessages = 600;

/// Writes a bag of kMessages messages on four connections: /imu (sensor_msgs/Imu), /twist
/// (geometry_msgs/TwistStamped), /note (std_msgs/String, of varying length) and, latched, one
/// /tf_static (tf2_msgs/TFMessage). Record times increase by 1 ms from 1700000000 s + 1 ns (all
/// distinct, so rosbag's time order is the writing order); header stamps lag them by 0.5 ms.
std::vector<Expected> writeBag(const std::string& path, BagOutput::Compression compression) {
  BagOutput out(path, path, compression, kSmallChunk);
  std::vector<Expected> expected;
  out.latch("/tf_static");
  const ros::Time start(1700000000, 1);
  for (int i = 0; i < kMessages; ++i) {
    const ros::Time time = start + ros::Duration(0, 1000000 * i);
    const ros::Time stamp = time - ros::Duration(0, 500000);
    if (i == 0) {
      tf2_msgs::TFMessage tf;
      tf.transforms.resize(1);
      tf.transforms[0].header.stamp = stamp;
      tf.transforms[0].header.frame_id = "base_link";
      tf.transforms[0].child_frame_id = "imu_link";
      tf.transforms[0].transform.rotation.w = 1.0;
      out.write("/tf_static", time, tf);
      expected.push_back({"/tf_static", ros::message_traits::datatype<tf2_msgs::TFMessage>(),
                          ros::message_traits::md5sum<tf2_msgs::TFMessage>(), time, ros::Time(),
                          serialised(tf)});
    } else if (i % 3 == 0) {
      geometry_msgs::TwistStamped twist;
      twist.header.stamp = stamp;
      twist.header.seq = i;
      twist.twist.angular.x = 0.25 * i;
      out.write("/twist", time, twist);
      expected.push_back({"/twist", ros::message_traits::datatype<geometry_msgs::TwistStamped>(),
                          ros::message_traits::md5sum<geometry_msgs::TwistStamped>(), time, stamp,
                          serialised(twist)});
    } else if (i % 7 == 0) {
      std_msgs::String note;
      note.data = std::string(i % 50, static_cast<char>('a' + i % 26));
      out.write("/note", time, note);
      expected.push_back({"/note", ros::message_traits::datatype<std_msgs::String>(),
                          ros::message_traits::md5sum<std_msgs::String>(), time, ros::Time(),
                          serialised(note)});
    } else {
      sensor_msgs::Imu imu;
      imu.header.stamp = stamp;
      imu.header.frame_id = "imu_link";
      imu.angular_velocity.x = 1e-3 * i;
      imu.angular_velocity.z = -2.0 / (i + 1);
      imu.orientation.w = 1.0;
      out.write("/imu", time, imu);
      expected.push_back({"/imu", ros::message_traits::datatype<sensor_msgs::Imu>(),
                          ros::message_traits::md5sum<sensor_msgs::Imu>(), time, stamp,
                          serialised(imu)});
    }
  }
  out.close();
  return expected;
}

ros::Time headerStamp(const rosbag::MessageInstance& m) {
  if (auto imu = m.instantiate<sensor_msgs::Imu>()) return imu->header.stamp;
  if (auto twist = m.instantiate<geometry_msgs::TwistStamped>()) return twist->header.stamp;
  return ros::Time();
}

/// Reads `path` with rosbag::View and compares every message with what was written: topic,
/// type, record time, header stamp and bytes, exactly and in order.
void expectReadsAsWritten(const std::string& path, const std::vector<Expected>& expected) {
  rosbag::Bag bag(path, rosbag::bagmode::Read);
  rosbag::View view(bag);
  ASSERT_EQ(view.size(), expected.size()) << path;
  std::size_t i = 0;
  for (const rosbag::MessageInstance& m : view) {
    const Expected& e = expected[i];
    EXPECT_EQ(m.getTopic(), e.topic) << path << " message " << i;
    EXPECT_EQ(m.getDataType(), e.datatype) << path << " message " << i;
    EXPECT_EQ(m.getMD5Sum(), e.md5sum) << path << " message " << i;
    EXPECT_EQ(m.getTime(), e.time) << path << " message " << i;
    EXPECT_EQ(headerStamp(m), e.stamp) << path << " message " << i;
    std::vector<std::uint8_t> bytes(m.size());
    ros::serialization::OStream out(bytes.data(), bytes.size());
    m.write(out);
    EXPECT_EQ(bytes, e.bytes) << path << " message " << i;
    ++i;
  }
  // The latched topic's connection header says so, as `rosbag record` writes it.
  for (const rosbag::ConnectionInfo* c : view.getConnections()) {
    const auto latching = c->header->find("latching");
    const bool latched = latching != c->header->end() && latching->second == "1";
    EXPECT_EQ(latched, c->topic == "/tf_static") << path << " " << c->topic;
  }
}

std::size_t countOf(const std::vector<Expected>& expected, const std::string& topic) {
  return std::count_if(expected.begin(), expected.end(),
                       [&](const Expected& e) { return e.topic == topic; });
}

class BagWriter : public ::testing::TestWithParam<BagOutput::Compression> {};

TEST_P(BagWriter, RosbagReadsEveryMessageAsWritten) {
  TempDir dir;
  const std::string path = dir.file("written.bag");
  const std::vector<Expected> expected = writeBag(path, GetParam());
  // Several chunks, walked independently of rosbag and of the writer.
  EXPECT_GE(chunkData(path).size(), 5u);
  expectReadsAsWritten(path, expected);
}

TEST_P(BagWriter, RosbagCheckNeedsNoMigration) {
  if (!haveRosbag()) GTEST_SKIP() << "rosbag's command-line tool is not installed (python3-rosbag)";
  TempDir dir;
  const std::string path = dir.file("written.bag");
  writeBag(path, GetParam());
  const auto check = run(rosbagCommand("check " + quote(path)));
  EXPECT_EQ(check.status, 0) << check.output;
  EXPECT_NE(check.output.find("does not need any migrations"), std::string::npos) << check.output;
}

TEST_P(BagWriter, RosbagInfoCountsWhatWasWritten) {
  if (!haveRosbag()) GTEST_SKIP() << "rosbag's command-line tool is not installed (python3-rosbag)";
  TempDir dir;
  const std::string path = dir.file("written.bag");
  const std::vector<Expected> expected = writeBag(path, GetParam());
  const auto info = run(rosbagCommand("info --yaml " + quote(path)));
  ASSERT_EQ(info.status, 0) << info.output;
  const std::string& text = info.output;
  EXPECT_NE(text.find("version: 2.0\n"), std::string::npos) << text;
  EXPECT_NE(text.find("indexed: True\n"), std::string::npos) << text;
  EXPECT_NE(text.find("messages: " + std::to_string(kMessages) + "\n"), std::string::npos) << text;
  const bool lz4 = GetParam() == BagOutput::Compression::Lz4;
  EXPECT_NE(text.find(std::string("compression: ") + (lz4 ? "lz4" : "none") + "\n"),
            std::string::npos)
      << text;
  // start and end: the first and last record times (1700000000 s + 1 ns, + 599 ms).
  EXPECT_NE(text.find("start: 1700000000.000000\n"), std::string::npos) << text;
  EXPECT_NE(text.find("end: 1700000000.599000\n"), std::string::npos) << text;
  for (const std::string topic : {"/imu", "/twist", "/note", "/tf_static"}) {
    const std::string entry = "- topic: " + topic + "\n";
    const auto at = text.find(entry);
    ASSERT_NE(at, std::string::npos) << topic << "\n" << text;
    const auto count = text.find("messages: ", at);
    ASSERT_NE(count, std::string::npos) << text;
    EXPECT_EQ(text.substr(count, text.find('\n', count) - count),
              "messages: " + std::to_string(countOf(expected, topic)))
        << topic << "\n"
        << text;
  }
}

TEST_P(BagWriter, RosbagReindexRebuildsTheSameIndex) {
  if (!haveRosbag()) GTEST_SKIP() << "rosbag's command-line tool is not installed (python3-rosbag)";
  TempDir dir;
  const std::string path = dir.file("written.bag");
  const std::vector<Expected> expected = writeBag(path, GetParam());
  const std::string copy = dir.file("copy.bag");
  ASSERT_EQ(run("cp " + quote(path) + " " + quote(copy)).status, 0);
  const auto reindex = run(rosbagCommand("reindex -q " + quote(copy)));
  ASSERT_EQ(reindex.status, 0) << reindex.output;
  expectReadsAsWritten(copy, expected);
  const auto check = run(rosbagCommand("check " + quote(copy)));
  EXPECT_EQ(check.status, 0) << check.output;
}

INSTANTIATE_TEST_SUITE_P(Compression, BagWriter,
                         ::testing::Values(BagOutput::Compression::None,
                                           BagOutput::Compression::Lz4),
                         [](const auto& info) {
                           return info.param == BagOutput::Compression::Lz4 ? "lz4" : "none";
                         });

}  // namespace
