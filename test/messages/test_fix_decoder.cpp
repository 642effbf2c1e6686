// The fix decoder (fix_decoder.h), rule by rule: each accepted type, the header frame and the
// fix frame's mount (rotations about skew axes, which tell C from Cᵀ and a transform from its
// inverse), the covariance (the pose's rotation block about the header frame's fixed axes, the
// Imu's about its own axes), NED through the node's own /tf_static frames, and every refusal,
// counted once. The truths: tf2's own composition (BufferCore lookups), C R Cᵀ multiplied out
// here, the linear map from a rotation about the header's axes to the body's error measured by
// finite differences, and the node's own output messages read back.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <geometry_msgs/Twist.h>
#include <tf2/buffer_core.h>

#include "../core/engine_fixtures.h"
#include "attitude_propagator/messages/conversions.h"
#include "attitude_propagator/messages/fix_decoder.h"
#include "attitude_propagator/messages/outputs.h"
#include "attitude_propagator/numerics/quaternion.h"
#include "serialized_message.h"

namespace ap = attitude_propagator;

namespace {

using messages_test::Serialized;

Eigen::Quaterniond about(const Eigen::Vector3d& axis, double angle) {
  return Eigen::Quaterniond(Eigen::AngleAxisd(angle, axis.normalized()));
}

// The fix frame's mount (base_link ← camera), the header frame's place (world ← map) and the
// body's true attitude (world ← base_link).
const Eigen::Quaterniond kMount = about(Eigen::Vector3d(1, 2, 3), 0.7);
const Eigen::Quaterniond kMap = about(Eigen::Vector3d(-2, 1, 0.5), 0.4);
const Eigen::Quaterniond kTruth = about(Eigen::Vector3d(0.3, -1, 0.2), 1.1);

const ros::Time kArrival(1700000000, 250000000);
const ros::Time kHeader(1700000000, 100000000);

geometry_msgs::TransformStamped transform(const std::string& parent, const std::string& child,
                                          const Eigen::Quaterniond& q) {
  geometry_msgs::TransformStamped t;
  t.header.frame_id = parent;
  t.child_frame_id = child;
  ap::toMsg(q, t.transform.rotation);
  t.transform.translation.x = 0.2;  // a translation, which a rotation ignores
  return t;
}

/// What the decoder may look up: the static mount and the map. Not the body's attitude.
void addFrames(tf2::BufferCore& buffer) {
  buffer.setTransform(transform("base_link", "camera", kMount), "urdf", true);
  buffer.setTransform(transform("world", "map", kMap), "map_server", true);
}

/// tf2's own composition: `target` ← `source` in a tree that also holds the true attitude.
Eigen::Quaterniond truthLookup(const std::string& target, const std::string& source) {
  tf2::BufferCore buffer;
  addFrames(buffer);
  buffer.setTransform(transform("world", "base_link", kTruth), "truth", true);
  return ap::rotationOf(buffer.lookupTransform(target, source, ros::Time()));
}

ap::FixFrames fixFrames(const std::string& fix_frame = "camera") {
  return {"world", "base_link", fix_frame};
}

/// A covariance with cross terms (symmetric, positive definite, anisotropic).
Eigen::Matrix3d someCovariance() {
  Eigen::Matrix3d R;
  R << 4e-4, 1e-4, -5e-5,  //
      1e-4, 3e-4, 2e-5,    //
      -5e-5, 2e-5, 2e-4;
  return R;
}

/// A 6x6 pose covariance whose position and cross blocks hold other values than its rotation
/// block R (row-major, x y z rotX rotY rotZ).
boost::array<double, 36> poseCovariance(const Eigen::Matrix3d& R) {
  boost::array<double, 36> c{};
  for (int i = 0; i < 6; ++i) {
    for (int j = 0; j < 6; ++j) {
      c[6 * i + j] = i < 3 && j < 3 ? (i == j ? 2.0 : 0.5) : 0.01 * (i + 1) * (j + 1);
    }
  }
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) c[6 * (i + 3) + (j + 3)] = R(i, j);
  }
  return c;
}

geometry_msgs::PoseWithCovarianceStamped poseFix(const std::string& frame,
                                                 const Eigen::Quaterniond& q,
                                                 const Eigen::Matrix3d& R) {
  geometry_msgs::PoseWithCovarianceStamped m;
  m.header.frame_id = frame;
  m.header.stamp = kHeader;
  ap::toMsg(q, m.pose.pose.orientation);
  m.pose.pose.position.x = 3.0;  // a position, which a fix ignores
  m.pose.covariance = poseCovariance(R);
  return m;
}

sensor_msgs::Imu imuFix(const std::string& frame, const Eigen::Quaterniond& q,
                        const Eigen::Matrix3d& R) {
  sensor_msgs::Imu m;
  m.header.frame_id = frame;
  m.header.stamp = kHeader;
  ap::toMsg(q, m.orientation);
  ap::covarianceToMsg(R, m.orientation_covariance);
  m.angular_velocity_covariance[0] = -1.0;  // no rate: a fix needs none
  return m;
}

}  // namespace

// The pose of the fix frame in a header frame other than the fixed one, through a mount: q_WB is
// what tf2 composes, the header's orientation taken from tf (not its inverse), the mount's too.
TEST(FixDecoder, PoseInAHeaderFrameThroughTheMountIsTheBodysAttitude) {
  tf2::BufferCore buffer;
  addFrames(buffer);
  ap::BufferCoreFrames frames(buffer);
  ap::FixDecoder decoder(fixFrames());
  const Eigen::Quaterniond q_HF = truthLookup("map", "camera");
  const auto fix = decoder.fix(poseFix("map", q_HF, someCovariance()), kArrival, &frames);
  ASSERT_TRUE(fix) << ap::refusedCounter(fix.refusal->why);
  EXPECT_EQ(fix->stamp, ap::toStamp(kHeader));
  EXPECT_LT(fix->q_WB.angularDistance(kTruth), 1e-12);
  EXPECT_NEAR(fix->q_WB.norm(), 1.0, 1e-15);
  EXPECT_EQ(decoder.refusals().total(), 0u);
}

// The rotation block about the header frame's fixed axes: R_B = C_BH R_H C_BHᵀ with
// q_BH = q_WBᶜ q_WH, written out; and the same as the linear map J from a small rotation e_H of
// the message about the header's axes (q_HF' = Exp(e_H) q_HF) to the body error it makes
// (q_WB' = q_WB Exp(e_B)), measured by finite differences through the decoder's attitude alone.
TEST(FixDecoder, PoseCovarianceIsAboutTheHeadersAxesAndComesOutInTheBody) {
  tf2::BufferCore buffer;
  addFrames(buffer);
  ap::BufferCoreFrames frames(buffer);
  ap::FixDecoder decoder(fixFrames());
  const Eigen::Quaterniond q_HF = truthLookup("map", "camera");
  const Eigen::Matrix3d R_H = someCovariance();
  const auto fix = decoder.fix(poseFix("map", q_HF, R_H), kArrival, &frames);
  ASSERT_TRUE(fix);
  const Eigen::Matrix3d C_BH = (kTruth.conjugate() * kMap).toRotationMatrix();
  EXPECT_TRUE(fix->R_B.isApprox(C_BH * R_H * C_BH.transpose(), 1e-12)) << fix->R_B;
  // Not the other way round: the mount and the map are skew, so these differ.
  EXPECT_FALSE(fix->R_B.isApprox(C_BH.transpose() * R_H * C_BH, 1e-3));

  Eigen::Matrix3d J;
  const double eps = 1e-6;
  for (int i = 0; i < 3; ++i) {
    const Eigen::Quaterniond moved = ap::expMap(eps * Eigen::Vector3d::Unit(i)) * q_HF;
    const auto perturbed = decoder.fix(poseFix("map", moved, R_H), kArrival, &frames);
    ASSERT_TRUE(perturbed);
    J.col(i) = ap::logMap(fix->q_WB.conjugate() * perturbed->q_WB) / eps;
  }
  EXPECT_TRUE(fix->R_B.isApprox(J * R_H * J.transpose(), 1e-5)) << J;
}

// Rows and columns 3-5 of the row-major 6x6: entry (i, j) of the block is c[6 (i+3) + (j+3)].
TEST(FixDecoder, OrientationBlockIsRowsAndColumnsThreeToFive) {
  boost::array<double, 36> c{};
  for (int k = 0; k < 36; ++k) c[k] = k;
  const Eigen::Matrix3d block = ap::orientationBlock(c);
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) EXPECT_EQ(block(i, j), 6 * (i + 3) + (j + 3)) << i << j;
  }
}

// PoseStamped and QuaternionStamped carry no covariance: zero, the engine's fix_stddev.
TEST(FixDecoder, PoseAndQuaternionWithoutCovarianceGiveNone) {
  tf2::BufferCore buffer;
  addFrames(buffer);
  ap::BufferCoreFrames frames(buffer);
  ap::FixDecoder decoder(fixFrames());
  geometry_msgs::PoseStamped pose;
  pose.header.frame_id = "map";
  pose.header.stamp = kHeader;
  ap::toMsg(truthLookup("map", "camera"), pose.pose.orientation);
  const auto from_pose = decoder.fix(pose, kArrival, &frames);
  ASSERT_TRUE(from_pose);
  EXPECT_LT(from_pose->q_WB.angularDistance(kTruth), 1e-12);
  EXPECT_TRUE(from_pose->R_B.isZero(0.0));

  geometry_msgs::QuaternionStamped quaternion;
  quaternion.header.stamp = kHeader;  // empty frame: the fixed frame
  ap::toMsg(truthLookup("world", "camera"), quaternion.quaternion);
  const auto from_quaternion = decoder.fix(quaternion, kArrival, &frames);
  ASSERT_TRUE(from_quaternion);
  EXPECT_LT(from_quaternion->q_WB.angularDistance(kTruth), 1e-12);
  EXPECT_TRUE(from_quaternion->R_B.isZero(0.0));
}

// An Imu gives its own frame's orientation in the fixed frame (REP-145), its covariance about
// its own axes: R_B = C_BF R_F C_BFᵀ with C_BF the mount; an empty frame is fix_frame.
TEST(FixDecoder, ImuGivesItsOwnFramesOrientationInTheFixedFrame) {
  tf2::BufferCore buffer;
  addFrames(buffer);
  ap::BufferCoreFrames frames(buffer);
  ap::FixDecoder decoder(fixFrames("base_link"));  // fix_frame does not name the Imu's frame
  const Eigen::Matrix3d R_F = someCovariance();
  const auto fix =
      decoder.fix(imuFix("camera", truthLookup("world", "camera"), R_F), kArrival, &frames);
  ASSERT_TRUE(fix);
  EXPECT_LT(fix->q_WB.angularDistance(kTruth), 1e-12);
  const Eigen::Matrix3d C_BF = kMount.toRotationMatrix();
  EXPECT_TRUE(fix->R_B.isApprox(C_BF * R_F * C_BF.transpose(), 1e-12));
  EXPECT_FALSE(fix->R_B.isApprox(C_BF.transpose() * R_F * C_BF, 1e-3));

  ap::FixDecoder in_camera(fixFrames("camera"));
  const auto unframed = in_camera.fix(
      imuFix("", truthLookup("world", "camera"), Eigen::Matrix3d::Zero()), kArrival, &frames);
  ASSERT_TRUE(unframed);
  EXPECT_LT(unframed->q_WB.angularDistance(kTruth), 1e-12);
  EXPECT_TRUE(unframed->R_B.isZero(0.0));  // all zero: none given
}

// The node's own imu/data, read back as a fix, is the state it was written from: the
// orientation of the sensor's frame and its covariance in that frame's axes.
TEST(FixDecoder, TheNodesImuOutputReadBackIsItsState) {
  ap::Parameters p;
  const ap::OutputEncoder encoder(ap::validateParameters(p), "kinematic", "cf4");
  ap::EngineState s;
  s.stamp = ap::toStamp(kHeader);
  s.q_WB = kTruth;
  s.P_B = someCovariance();
  sensor_msgs::Imu input;
  input.header.frame_id = "camera";
  sensor_msgs::Imu out;
  encoder.imu(input, s, kMount, out);
  tf2::BufferCore buffer;
  addFrames(buffer);
  ap::BufferCoreFrames frames(buffer);
  ap::FixDecoder decoder(fixFrames());
  const auto fix = decoder.fix(out, kArrival, &frames);
  ASSERT_TRUE(fix);
  EXPECT_EQ(fix->stamp, s.stamp);
  EXPECT_LT(fix->q_WB.angularDistance(s.q_WB), 1e-12);
  EXPECT_TRUE(fix->R_B.isApprox(s.P_B, 1e-12));
}

// world_frame ned: a fix given as AttitudeState gives it, header world_ned and fix frame
// base_link_frd, both on the node's /tf_static, is the state's attitude; a covariance written
// about world_ned's axes comes back as P_B.
TEST(FixDecoder, NedFixThroughTheNodesConventionFramesIsTheState) {
  ap::Parameters p;
  p.world_frame = "ned";
  p.fix_frame = "base_link_frd";
  const ap::NodeConfig config = ap::validateParameters(p);
  const ap::OutputEncoder encoder(config, "kinematic", "cf4");
  ap::EngineState s;
  s.stamp = ap::toStamp(kHeader);
  s.q_WB = kTruth;
  s.P_B = someCovariance();
  ap::AttitudeState state;
  encoder.state(s, state);
  ASSERT_EQ(state.header.frame_id, "world_ned");
  ASSERT_EQ(state.child_frame_id, "base_link_frd");
  tf2::BufferCore buffer;
  for (const auto& t : encoder.conventionFrames(ros::Time(1.0))) {
    buffer.setTransform(t, "node", true);
  }
  ap::BufferCoreFrames frames(buffer);
  ap::FixDecoder decoder(ap::FixFrames::of(config));

  geometry_msgs::QuaternionStamped q;
  q.header = state.header;
  q.quaternion = state.orientation;
  const auto fix = decoder.fix(q, kArrival, &frames);
  ASSERT_TRUE(fix) << fix.refusal->frame;
  EXPECT_LT(fix->q_WB.angularDistance(s.q_WB), 1e-12);

  // AttitudeState's covariance is about FRD's axes; the pose's about world_ned's.
  const Eigen::Matrix3d C_HF = ap::toEigen(state.orientation).toRotationMatrix();
  const Eigen::Matrix3d P_F = ap::covarianceFromMsg(state.orientation_covariance);
  const auto pose = decoder.fix(
      poseFix("world_ned", ap::toEigen(state.orientation), C_HF * P_F * C_HF.transpose()), kArrival,
      &frames);
  ASSERT_TRUE(pose);
  EXPECT_LT(pose->q_WB.angularDistance(s.q_WB), 1e-12);
  EXPECT_TRUE(pose->R_B.isApprox(s.P_B, 1e-12)) << pose->R_B;
}

// The stamp rule: zero means the arrival time; none at all is NoTime, counted once.
TEST(FixDecoder, ZeroStampIsArrivalAndNoTimeIsRefused) {
  ap::FixDecoder decoder(fixFrames("base_link"));
  geometry_msgs::QuaternionStamped q;
  q.quaternion.w = 1.0;
  const auto at_arrival = decoder.fix(q, kArrival, nullptr);
  ASSERT_TRUE(at_arrival);
  EXPECT_EQ(at_arrival->stamp, ap::toStamp(kArrival));
  const auto none = decoder.fix(q, ros::Time(), nullptr);
  ASSERT_FALSE(none);
  EXPECT_EQ(none.refusal->why, ap::Refused::NoTime);
  EXPECT_EQ(decoder.refusals().no_time, 1u);
  EXPECT_EQ(decoder.refusals().total(), 1u);
  EXPECT_STREQ(ap::fixRefusedCounter(ap::Refused::NoTime), "fixes_refused_no_time");
}

// An unknown header frame, an unknown fix frame, no frame source: NoTransform naming the frame,
// counted once each.
TEST(FixDecoder, UnknownFramesAreRefusedByName) {
  tf2::BufferCore buffer;
  addFrames(buffer);
  ap::BufferCoreFrames frames(buffer);
  ap::FixDecoder decoder(fixFrames());
  const auto header = decoder.fix(poseFix("nowhere", kTruth, someCovariance()), kArrival, &frames);
  ASSERT_FALSE(header);
  EXPECT_EQ(header.refusal->why, ap::Refused::NoTransform);
  EXPECT_EQ(header.refusal->frame, "nowhere");
  EXPECT_FALSE(header.refusal->detail.empty());  // tf's words
  EXPECT_EQ(decoder.refusals().no_tf, 1u);

  ap::FixDecoder lost(fixFrames("lost_camera"));
  const auto mount = lost.fix(poseFix("world", kTruth, someCovariance()), kArrival, &frames);
  ASSERT_FALSE(mount);
  EXPECT_EQ(mount.refusal->frame, "lost_camera");
  EXPECT_EQ(lost.refusals().no_tf, 1u);

  const auto no_source = decoder.fix(poseFix("map", kTruth, someCovariance()), kArrival, nullptr);
  ASSERT_FALSE(no_source);
  EXPECT_EQ(no_source.refusal->frame, "map");
  EXPECT_EQ(decoder.refusals().no_tf, 2u);
  EXPECT_EQ(decoder.refusals().total(), 2u);
  EXPECT_STREQ(ap::fixRefusedCounter(ap::Refused::NoTransform), "fixes_refused_no_tf");
}

// REP-145: orientation_covariance[0] == -1 says the Imu carries no orientation.
TEST(FixDecoder, ImuWithoutOrientationIsRefused) {
  ap::FixDecoder decoder(fixFrames("base_link"));
  sensor_msgs::Imu m = imuFix("base_link", kTruth, Eigen::Matrix3d::Zero());
  m.orientation_covariance[0] = -1.0;
  const auto fix = decoder.fix(m, kArrival, nullptr);
  ASSERT_FALSE(fix);
  EXPECT_EQ(fix.refusal->why, ap::Refused::NoOrientation);
  EXPECT_EQ(decoder.refusals().no_orientation, 1u);
  EXPECT_EQ(decoder.refusals().total(), 1u);
}

// A header frame that is body_frame would be joined to fixed_frame by the node's own output
// (node.md: it must not pass through body_frame): refused and counted, even when tf holds the
// body's attitude; an Imu in the body's frame is the body's orientation, not a header frame.
TEST(FixDecoder, HeaderFrameThatIsTheBodyIsRefused) {
  tf2::BufferCore buffer;
  addFrames(buffer);
  buffer.setTransform(transform("world", "base_link", kTruth), "the node", false);
  ap::BufferCoreFrames frames(buffer);
  ap::FixDecoder decoder(fixFrames());
  for (const auto& q : {kTruth, Eigen::Quaterniond::Identity()}) {
    const auto fix = decoder.fix(poseFix("base_link", q, someCovariance()), kArrival, &frames);
    ASSERT_FALSE(fix);
    EXPECT_EQ(fix.refusal->why, ap::Refused::FixBodyFrame);
    EXPECT_EQ(fix.refusal->frame, "base_link");
  }
  EXPECT_EQ(decoder.refusals().body_frame, 2u);
  EXPECT_EQ(decoder.refusals().total(), 2u);
  EXPECT_STREQ(ap::fixRefusedCounter(ap::Refused::FixBodyFrame), "fixes_refused_body_frame");
  EXPECT_TRUE(decoder.fix(imuFix("base_link", kTruth, Eigen::Matrix3d::Zero()), kArrival, &frames));
}

// Each type through the topic gives what the direct call gives; the first fixes the type,
// another accepted one later and one not accepted are WrongType, counted once each.
TEST(FixDecoder, TopicTakesItsFirstTypeOnly) {
  tf2::BufferCore buffer;
  addFrames(buffer);
  ap::BufferCoreFrames frames(buffer);
  const auto pose = poseFix("map", truthLookup("map", "camera"), someCovariance());
  geometry_msgs::PoseStamped stamped;
  stamped.header = pose.header;
  stamped.pose = pose.pose.pose;
  geometry_msgs::QuaternionStamped quaternion;
  quaternion.header = pose.header;
  quaternion.quaternion = pose.pose.pose.orientation;
  const auto imu = imuFix("camera", truthLookup("world", "camera"), someCovariance());
  const std::vector<Serialized> each{Serialized::of(pose), Serialized::of(stamped),
                                     Serialized::of(quaternion), Serialized::of(imu)};
  for (std::size_t first = 0; first < each.size(); ++first) {
    ap::FixDecoder decoder(fixFrames());
    const auto fix = decoder.topic(each[first], kArrival, &frames);
    ASSERT_TRUE(fix) << each[first].datatype;
    EXPECT_EQ(decoder.type().datatype(), each[first].datatype);
    EXPECT_LT(fix->q_WB.angularDistance(kTruth), 1e-12) << each[first].datatype;
    EXPECT_EQ(fix->R_B.isZero(0.0), first == 1 || first == 2) << each[first].datatype;
    const auto other = decoder.topic(each[(first + 1) % each.size()], kArrival, &frames);
    ASSERT_FALSE(other);
    EXPECT_EQ(other.refusal->why, ap::Refused::WrongType);
    EXPECT_EQ(other.refusal->detail, each[(first + 1) % each.size()].datatype);
    EXPECT_FALSE(decoder.topic(Serialized::of(geometry_msgs::Twist()), kArrival, &frames));
    EXPECT_EQ(decoder.refusals().type, 2u);
    EXPECT_EQ(decoder.refusals().total(), 2u);
  }
  ap::FixDecoder decoder(fixFrames());
  EXPECT_EQ(decoder.type().accepted(),
            "geometry_msgs/PoseWithCovarianceStamped, geometry_msgs/PoseStamped, "
            "geometry_msgs/QuaternionStamped or sensor_msgs/Imu");
}

// Another publisher's type registered with the master (ROS 1 refuses its connection: its
// messages never arrive) is named once the topic has a type; the topic's own type, "*" and a
// topic with no message yet name nothing.
TEST(FixDecoder, AnotherTypeRegisteredOnTheTopicIsNamedOnceItHasAType) {
  tf2::BufferCore buffer;
  addFrames(buffer);
  ap::BufferCoreFrames frames(buffer);
  ap::FixDecoder decoder(fixFrames());
  const std::string quaternion = "geometry_msgs/QuaternionStamped";
  EXPECT_FALSE(decoder.type().otherRegistered(quaternion));  // no message yet
  ASSERT_TRUE(
      decoder.topic(Serialized::of(poseFix("map", truthLookup("map", "camera"), someCovariance())),
                    kArrival, &frames));
  EXPECT_EQ(decoder.type().otherRegistered(quaternion), quaternion);
  EXPECT_FALSE(decoder.type().otherRegistered("geometry_msgs/PoseWithCovarianceStamped"));
  EXPECT_FALSE(decoder.type().otherRegistered("*"));
  EXPECT_FALSE(decoder.type().otherRegistered(""));
}

// A bad quaternion or covariance is the engine's to refuse: the decoder hands it on (a bad
// covariance unrotated), the engine refuses and counts it once, the decoder counts nothing.
TEST(FixDecoder, BadQuaternionsAndCovariancesAreRefusedByTheEngineOnce) {
  tf2::BufferCore buffer;
  addFrames(buffer);
  ap::BufferCoreFrames frames(buffer);
  ap::FixDecoder decoder(fixFrames());
  engine_fixtures::DiscardingSink sink;
  ap::AttitudeEngine engine(ap::engineConfig(ap::validateParameters(ap::Parameters{})), sink);
  const Eigen::Quaterniond q_HF = truthLookup("map", "camera");
  const double nan = std::numeric_limits<double>::quiet_NaN();

  auto submit = [&](const geometry_msgs::PoseWithCovarianceStamped& m) {
    const auto fix = decoder.fix(m, kArrival, &frames);
    EXPECT_TRUE(fix);
    return fix ? engine.submitFix(fix->stamp, fix->q_WB, fix->R_B) : ap::FixOutcome::Waiting;
  };
  auto bad_q = poseFix("map", q_HF, someCovariance());
  bad_q.pose.pose.orientation.x = nan;
  EXPECT_EQ(submit(bad_q), ap::FixOutcome::BadQuaternion);
  const Eigen::Quaterniond longer(1.1 * q_HF.coeffs());
  EXPECT_EQ(submit(poseFix("map", longer, someCovariance())), ap::FixOutcome::BadQuaternion);
  EXPECT_EQ(engine.counters().fixes_bad_quaternion, 2u);

  // A negative variance, which a rotation would spread over the other entries.
  Eigen::Matrix3d negative;
  negative << 1e-4, 0.0, 0.0,  //
      0.0, -1e-6, 0.0,         //
      0.0, 0.0, 1e-4;
  const auto handed = decoder.fix(poseFix("map", q_HF, negative), kArrival, &frames);
  ASSERT_TRUE(handed);
  EXPECT_EQ(handed->R_B, negative);  // as given: unrotated
  EXPECT_EQ(submit(poseFix("map", q_HF, negative)), ap::FixOutcome::BadCovariance);
  Eigen::Matrix3d non_finite = someCovariance();
  non_finite(1, 2) = non_finite(2, 1) = nan;
  EXPECT_EQ(submit(poseFix("map", q_HF, non_finite)), ap::FixOutcome::BadCovariance);
  EXPECT_EQ(engine.counters().fixes_bad_covariance, 2u);
  EXPECT_EQ(engine.counters().fixes_accepted, 0u);
  EXPECT_EQ(decoder.refusals().total(), 0u);
}

// fix_frame: empty (body_frame) by default, a tf2 frame id otherwise, never the fixed frame.
TEST(FixFrames, FromTheParameters) {
  ap::Parameters p;
  const ap::FixFrames defaults = ap::FixFrames::of(ap::validateParameters(p));
  EXPECT_EQ(defaults.fixed, "world");
  EXPECT_EQ(defaults.body, "base_link");
  EXPECT_EQ(defaults.fix, "");
  p.fix_frame = "camera";
  EXPECT_EQ(ap::FixFrames::of(ap::validateParameters(p)).fix, "camera");
  for (const char* refused : {"/camera", "world"}) {
    p.fix_frame = refused;
    try {
      ap::validateParameters(p);
      ADD_FAILURE() << "fix_frame '" << refused << "' accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_EQ(std::string(e.what()).rfind("fix_frame", 0), 0u) << e.what();
    }
  }
}

// Messages lost before the node, from each publisher's header.seq: a gap of k is k lost; a seq
// at or before the last (a restarted publisher, a sender leaving seq 0) none; publishers apart.
TEST(SequenceGaps, CountsEachPublishersGapsOnly) {
  ap::SequenceGaps gaps;
  EXPECT_EQ(gaps.observe("/a", 7), 0u);  // the first heard: nothing known before it
  EXPECT_EQ(gaps.observe("/a", 8), 0u);
  EXPECT_EQ(gaps.observe("/b", 0), 0u);
  EXPECT_EQ(gaps.observe("/a", 12), 3u);  // 9, 10, 11
  EXPECT_EQ(gaps.observe("/b", 0), 0u);   // a sender that does not number
  EXPECT_EQ(gaps.observe("/a", 2), 0u);   // restarted
  EXPECT_EQ(gaps.observe("/a", 3), 0u);
  EXPECT_EQ(gaps.observe("/a", 0xFFFFFFFFu), 0xFFFFFFFFull - 4);
  EXPECT_EQ(gaps.lost(), 3u + 0xFFFFFFFFull - 4);
}

TEST(SequenceGaps, RemembersABoundedNumberOfPublishers) {
  ap::SequenceGaps gaps;
  for (std::size_t i = 0; i <= ap::SequenceGaps::kMaxPublishers; ++i)
    gaps.observe("/p" + std::to_string(i), 1);
  // /p0 was forgotten (heard from longest ago): its next seq is a first again.
  EXPECT_EQ(gaps.observe("/p0", 5), 0u);
  EXPECT_EQ(gaps.observe("/p2", 5), 3u);
}

TEST(SequenceGaps, HeaderSeqIsTheSerialisedMessagesFirstField) {
  geometry_msgs::PoseStamped m;
  m.header.seq = 0x01020304u;
  const std::vector<std::uint8_t> bytes = messages_test::Serialized::of(m).bytes;
  EXPECT_EQ(ap::headerSeq(bytes.data(), bytes.size()), std::optional<std::uint32_t>(0x01020304u));
  EXPECT_FALSE(ap::headerSeq(bytes.data(), 3));
}

// Each refusal of a fix is counted under the name docs/design.md §7.5's table gives it; the
// refusals of rates, torques and bias samples are not a fix's.
TEST(FixDecoder, EachRefusalOfAFixHasTheCounterTheDocsName) {
  EXPECT_STREQ(ap::fixRefusedCounter(ap::Refused::NoTransform), "fixes_refused_no_tf");
  EXPECT_STREQ(ap::fixRefusedCounter(ap::Refused::WrongType), "fixes_refused_type");
  EXPECT_STREQ(ap::fixRefusedCounter(ap::Refused::NoTime), "fixes_refused_no_time");
  EXPECT_STREQ(ap::fixRefusedCounter(ap::Refused::NoOrientation), "fixes_refused_no_orientation");
  EXPECT_STREQ(ap::fixRefusedCounter(ap::Refused::FixBodyFrame), "fixes_refused_body_frame");
  for (const ap::Refused other :
       {ap::Refused::NoRate, ap::Refused::BadCovariance, ap::Refused::BiasFrame}) {
    EXPECT_STREQ(ap::fixRefusedCounter(other), "?");
  }
}
