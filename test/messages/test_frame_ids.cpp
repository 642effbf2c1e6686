// Frame ids as drivers write them (frame_ids.h): tf1's leading '/' removed in every input and
// frame parameter, one warning per frame; spaces and line breaks refused by name. The truths
// are the documented rules: tf2 frame ids carry no leading '/' (tf2's migration guide: "tf2
// does not accept frame_ids with a leading slash"), so `/imu` must be looked up as `imu`;
// the rotations are a mount built here from an angle and an axis.
#include <gtest/gtest.h>

#include <stdexcept>
#include <string>
#include <vector>

#include "attitude_propagator/messages/conversions.h"
#include "attitude_propagator/messages/fix_decoder.h"
#include "attitude_propagator/messages/frame_ids.h"
#include "attitude_propagator/messages/input_decoders.h"

namespace ap = attitude_propagator;

namespace {

const ros::Time kStamp(1700000000, 100000000);
const Eigen::Quaterniond kMount(Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()));

/// Knows one transform, base_link <- imu_link (and the identities), and records every frame it
/// was asked about: a tf2 lookup of a name with '/' would log an error per call.
class RecordingFrames : public ap::FrameSource {
 public:
  std::optional<Eigen::Quaterniond> rotation(const std::string& target, const std::string& source,
                                             const ros::Time&, std::string* error) override {
    asked.push_back(target);
    asked.push_back(source);
    if (target == source) return Eigen::Quaterniond::Identity();
    if (target == "base_link" && source == "imu_link") return kMount;
    if (target == "world" && source == "map") return Eigen::Quaterniond::Identity();
    if (error) *error = "unknown";
    return std::nullopt;
  }
  bool askedWithSlash() const {
    for (const auto& f : asked) {
      if (!f.empty() && f.front() == '/') return true;
    }
    return false;
  }
  std::vector<std::string> asked;
};

ap::DecoderFrames frames() { return {"base_link", "world", ap::TorqueFrame::Body}; }

sensor_msgs::Imu imu(const std::string& frame) {
  sensor_msgs::Imu m;
  m.header.frame_id = frame;
  m.header.stamp = kStamp;
  m.angular_velocity.x = 0.3;
  m.angular_velocity.y = -0.2;
  m.angular_velocity.z = 0.5;
  return m;
}

}  // namespace

TEST(FrameIds, LeadingSlashIsRemovedOnce) {
  EXPECT_EQ(ap::tf2FrameId("/imu"), "imu");
  EXPECT_EQ(ap::tf2FrameId("imu"), "imu");
  EXPECT_EQ(ap::tf2FrameId(""), "");
  EXPECT_EQ(ap::tf2FrameId("/robot1/imu"), "robot1/imu");  // only the leading one
}

TEST(FrameIds, SpacesTabsAndLineBreaksAreRefused) {
  for (const std::string f : {"imu link", "imu\n", "imu\tlink", "imu\r", " imu"}) {
    EXPECT_TRUE(ap::frameIdRefused(f)) << f;
  }
  for (const std::string f : {"imu", "/imu", "robot1/imu_link", ""}) {
    EXPECT_FALSE(ap::frameIdRefused(f)) << f;
  }
}

TEST(FrameIds, OneWarningPerFrameNamingIt) {
  ap::FrameIds ids;
  for (int i = 0; i < 1000; ++i) {
    EXPECT_EQ(*ids.admit("/imu"), "imu");
    EXPECT_EQ(*ids.admit("imu"), "imu");
  }
  EXPECT_EQ(*ids.admit("/mag"), "mag");
  const std::vector<std::string> warnings = ids.takeWarnings();
  ASSERT_EQ(warnings.size(), 2u);
  EXPECT_NE(warnings[0].find("'/imu'"), std::string::npos) << warnings[0];
  EXPECT_NE(warnings[1].find("'/mag'"), std::string::npos) << warnings[1];
  EXPECT_TRUE(ids.takeWarnings().empty());
  ids.admit("/imu");
  EXPECT_TRUE(ids.takeWarnings().empty());  // still once per frame
  EXPECT_EQ(ids.admit("imu link"), nullptr);
}

TEST(FrameIds, RatesInASlashedMountFrameAreLookedUpWithoutIt) {
  ap::InputDecoders decoders(frames());
  RecordingFrames tf;
  for (int i = 0; i < 3; ++i) {
    const ap::DecodedInput in = decoders.imu(imu("/imu_link"), kStamp, &tf);
    ASSERT_TRUE(in) << in.refusal->detail;
    EXPECT_TRUE(in->value.isApprox(kMount * Eigen::Vector3d(0.3, -0.2, 0.5), 1e-15));
  }
  EXPECT_FALSE(tf.askedWithSlash());
  EXPECT_EQ(tf.asked.size(), 2u);  // the mount looked up once
  EXPECT_EQ(decoders.mountFrame(), "imu_link");
  EXPECT_EQ(decoders.takeFrameWarnings().size(), 1u);
}

TEST(FrameIds, SlashedBodyFrameIsTheBody) {
  ap::InputDecoders decoders(frames());
  RecordingFrames tf;
  const ap::DecodedInput in = decoders.imu(imu("/base_link"), kStamp, &tf);
  ASSERT_TRUE(in);
  EXPECT_TRUE(in->value.isApprox(Eigen::Vector3d(0.3, -0.2, 0.5), 0.0));
  EXPECT_TRUE(tf.asked.empty());

  geometry_msgs::WrenchStamped torque;
  torque.header.stamp = kStamp;
  torque.header.frame_id = "/world";
  torque.wrench.torque.x = 1.0;
  const ap::DecodedInput t = decoders.torque(torque, kStamp, &tf);
  ASSERT_TRUE(t);
  EXPECT_EQ(t->frame, ap::TorqueFrame::Fixed);

  geometry_msgs::Vector3Stamped bias;
  bias.header.stamp = kStamp;
  bias.header.frame_id = "/base_link";
  EXPECT_TRUE(decoders.bias(bias, kStamp));
  EXPECT_TRUE(tf.asked.empty());
  EXPECT_EQ(decoders.takeFrameWarnings().size(), 2u);  // /base_link, /world
}

TEST(FrameIds, FrameWithASpaceRefusedNamingTheRule) {
  ap::InputDecoders decoders(frames());
  RecordingFrames tf;
  const ap::DecodedInput in = decoders.imu(imu("imu link"), kStamp, &tf);
  ASSERT_FALSE(in);
  EXPECT_EQ(in.refusal->why, ap::Refused::NoTransform);
  EXPECT_EQ(in.refusal->frame, "imu link");
  EXPECT_EQ(in.refusal->detail, ap::kFrameIdRule);
  geometry_msgs::Vector3Stamped bias;
  bias.header.frame_id = "base_link\n";
  const auto b = decoders.bias(bias, kStamp);
  ASSERT_FALSE(b);
  EXPECT_EQ(b.refusal->why, ap::Refused::BiasFrame);
  EXPECT_EQ(b.refusal->detail, ap::kFrameIdRule);
  EXPECT_TRUE(tf.asked.empty());
}

TEST(FrameIds, FixInSlashedFramesIsLookedUpWithoutThem) {
  ap::FixDecoder decoder({"world", "base_link", ""});
  RecordingFrames tf;
  geometry_msgs::QuaternionStamped q;
  q.header.stamp = kStamp;
  q.header.frame_id = "/map";
  q.quaternion.w = 1.0;
  const ap::Decoded<ap::Fix> fix = decoder.fix(q, kStamp, &tf);
  ASSERT_TRUE(fix) << fix.refusal->detail;
  EXPECT_FALSE(tf.askedWithSlash());
  EXPECT_EQ(decoder.takeFrameWarnings().size(), 1u);
  q.header.frame_id = "map frame";
  const ap::Decoded<ap::Fix> refused = decoder.fix(q, kStamp, &tf);
  ASSERT_FALSE(refused);
  EXPECT_EQ(refused.refusal->detail, ap::kFrameIdRule);
  EXPECT_EQ(decoder.refusals().no_tf, 1u);
}

TEST(FrameIds, FrameParametersLoseTheSlashWithAWarningNamingThem) {
  ap::Parameters p;
  p.body_frame = "/imu";
  p.fixed_frame = "/odom";
  const std::vector<std::string> warnings = ap::tf2FrameParameters(p);
  EXPECT_EQ(p.body_frame, "imu");
  EXPECT_EQ(p.fixed_frame, "odom");
  EXPECT_EQ(p.fix_frame, "");  // empty: body_frame, as it was
  ASSERT_EQ(warnings.size(), 2u);
  EXPECT_NE(warnings[1].find("body_frame"), std::string::npos) << warnings[1];
  EXPECT_NE(warnings[1].find("'/imu'"), std::string::npos) << warnings[1];
  EXPECT_NO_THROW(ap::validateParameters(p));
}

TEST(FrameIds, FrameParameterWithASpaceRefusedNamingIt) {
  ap::Parameters p;
  p.body_frame = "base link";
  try {
    ap::tf2FrameParameters(p);
    FAIL() << "accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("body_frame"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("spaces"), std::string::npos) << e.what();
  }
}

// Every message published carries fixed_frame or body_frame: a frame parameter longer than
// kMaxFrameParameterBytes is refused naming it and the bound; one of exactly that many (after
// its leading '/') is accepted.
TEST(FrameIds, FrameParameterLongerThanTheBoundRefusedNamingIt) {
  ap::Parameters p;
  p.fixed_frame = "/" + std::string(ap::kMaxFrameParameterBytes, 'w');
  EXPECT_NO_THROW(ap::tf2FrameParameters(p));
  EXPECT_EQ(p.fixed_frame.size(), ap::kMaxFrameParameterBytes);
  for (const std::size_t bytes : {ap::kMaxFrameParameterBytes + 1, std::size_t{100000}}) {
    ap::Parameters q;
    q.fix_frame = std::string(bytes, 'f');
    try {
      ap::tf2FrameParameters(q);
      FAIL() << "accepted " << bytes;
    } catch (const std::invalid_argument& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("fix_frame"), std::string::npos) << what.substr(0, 300);
      EXPECT_NE(what.find("at most " + std::to_string(ap::kMaxFrameParameterBytes) + " bytes"),
                std::string::npos)
          << what.substr(0, 300);
      EXPECT_LT(what.size(), 1000u);  // the frame itself quoted by the one text rule
    }
  }
}
