// The message layer's output encoding against tf2's own composition of transforms: what a tf
// user looks up between the named frames is what the messages say, in every world_frame, with
// reverse_tf, and for the republished IMU at a mount that tells C from Cᵀ.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include <tf2/buffer_core.h>

#include "attitude_propagator/messages/conversions.h"
#include "attitude_propagator/messages/outputs.h"

namespace ap = attitude_propagator;

namespace {

Eigen::Quaterniond about(const Eigen::Vector3d& axis, double angle) {
  return Eigen::Quaterniond(Eigen::AngleAxisd(angle, axis.normalized()));
}

double angleBetween(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b) {
  return a.angularDistance(b);
}

ap::NodeConfig configFor(const std::string& world, bool reverse_tf = false) {
  ap::Parameters p;
  p.world_frame = world;
  p.reverse_tf = reverse_tf;
  return ap::validateParameters(p);
}

ap::EngineState someState() {
  ap::EngineState s;
  s.stamp = 1780000000123456789LL;
  s.q_WB = about(Eigen::Vector3d(0.3, -0.5, 0.8), 1.1);
  s.w_B = Eigen::Vector3d(0.1, -0.2, 0.3);
  s.M_B = Eigen::Vector3d(1.0, 2.0, -3.0);
  s.P_B << 4e-4, 1e-4, 2e-4,  //
      1e-4, 5e-4, 3e-4,       //
      2e-4, 3e-4, 6e-4;
  return s;
}

/// A buffer holding what the node publishes: the transform on /tf and world_frame's named axes
/// on /tf_static.
void publish(const ap::OutputEncoder& encoder, const ap::EngineState& s, tf2::BufferCore& buffer) {
  geometry_msgs::TransformStamped t;
  encoder.transform(s, t);
  buffer.setTransform(t, "node", false);
  for (const auto& frame : encoder.conventionFrames(ros::Time(1.0))) {
    buffer.setTransform(frame, "node", true);
  }
}

Eigen::Quaterniond lookup(const tf2::BufferCore& buffer, const std::string& target,
                          const std::string& source, const ros::Time& stamp) {
  return ap::rotationOf(buffer.lookupTransform(target, source, stamp));
}

}  // namespace

class EveryWorld : public ::testing::TestWithParam<const char*> {};

TEST_P(EveryWorld, StateMessageIsWhatTfGivesBetweenItsFrames) {
  const ap::NodeConfig config = configFor(GetParam());
  const ap::OutputEncoder encoder(config, "kinematic", "cf4");
  const ap::EngineState s = someState();
  ap::AttitudeState msg;
  encoder.state(s, msg);
  const std::string suffix = std::string(GetParam()) == "enu" ? "" : std::string("_") + GetParam();
  EXPECT_EQ(msg.header.frame_id, "world" + suffix);
  EXPECT_EQ(msg.child_frame_id, std::string(GetParam()) == "ned" ? "base_link_frd" : "base_link");
  EXPECT_EQ(ap::toStamp(msg.header.stamp), s.stamp);
  EXPECT_EQ(msg.model, "kinematic");
  EXPECT_EQ(msg.integrator, "cf4");
  tf2::BufferCore buffer;
  publish(encoder, s, buffer);
  const Eigen::Quaterniond from_tf =
      lookup(buffer, msg.header.frame_id, msg.child_frame_id, msg.header.stamp);
  EXPECT_LT(angleBetween(ap::toEigen(msg.orientation), from_tf), 1e-12);
  // The rate and momentum in the child frame's axes: the same vectors as tf carries them.
  const Eigen::Quaterniond q_body_child =
      lookup(buffer, "base_link", msg.child_frame_id, msg.header.stamp);
  EXPECT_LT((q_body_child * ap::toEigen(msg.angular_velocity) - s.w_B).norm(), 1e-15);
  EXPECT_LT((q_body_child * ap::toEigen(msg.angular_momentum) - s.M_B).norm(), 1e-14);
  // The covariance likewise: P_child = C P_B Cᵀ with C the child ← base_link rotation.
  const Eigen::Matrix3d C = q_body_child.conjugate().toRotationMatrix();
  EXPECT_TRUE(
      ap::covarianceFromMsg(msg.orientation_covariance).isApprox(C * s.P_B * C.transpose(), 1e-12));
}

// The republished IMU message: the orientation of its own frame in world_frame's fixed axes,
// through a mount about a skew axis, as tf composes it; its covariance in its own frame.
TEST_P(EveryWorld, ImuMessageIsItsFramesOrientationAsTfComposesIt) {
  const ap::NodeConfig config = configFor(GetParam());
  const ap::OutputEncoder encoder(config, "kinematic", "cf4");
  const ap::EngineState s = someState();
  const Eigen::Quaterniond q_BS = about(Eigen::Vector3d(1, 2, 3), 0.7);
  sensor_msgs::Imu input;
  input.header.frame_id = "imu_link";
  input.angular_velocity.x = 0.25;
  sensor_msgs::Imu out;
  encoder.imu(input, s, q_BS, out);
  EXPECT_EQ(out.header.frame_id, "imu_link");
  EXPECT_EQ(out.angular_velocity.x, 0.25);  // the input's own fields kept
  tf2::BufferCore buffer;
  publish(encoder, s, buffer);
  geometry_msgs::TransformStamped mount;
  mount.header.frame_id = "base_link";
  mount.child_frame_id = "imu_link";
  ap::toMsg(q_BS, mount.transform.rotation);
  buffer.setTransform(mount, "urdf", true);
  ap::AttitudeState state;
  encoder.state(s, state);
  const Eigen::Quaterniond from_tf =
      lookup(buffer, state.header.frame_id, "imu_link", out.header.stamp);
  EXPECT_LT(angleBetween(ap::toEigen(out.orientation), from_tf), 1e-12);
  // C_BS P_S C_BSᵀ = P_B: the covariance rotated back to the body is the body's.
  const Eigen::Matrix3d C_BS = q_BS.toRotationMatrix();
  const Eigen::Matrix3d P_S = ap::covarianceFromMsg(out.orientation_covariance);
  EXPECT_TRUE((C_BS * P_S * C_BS.transpose()).isApprox(s.P_B, 1e-12));
}

// AttitudeState's gyro_bias is the bias in use, the configured one (the gyro_bias parameter, or
// the engine's, which the bias topic moves) plus the estimate, in the child frame's axes as tf
// carries a vector there; its standard deviation likewise (per axis, so without sign).
TEST_P(EveryWorld, GyroBiasIsTheBiasInUseInTheChildFramesAxes) {
  ap::Parameters p;
  p.world_frame = GetParam();
  p.gyro_bias = {0.01, -0.02, 0.03};
  const ap::NodeConfig config = ap::validateParameters(p);
  ap::EngineState s = someState();
  s.gyro_bias_estimate_B = Eigen::Vector3d(1e-3, 2e-3, -4e-3);
  s.gyro_bias_stddev_B = Eigen::Vector3d(1e-4, 2e-4, 3e-4);
  const ap::OutputEncoder encoder(config, "kinematic", "cf4");
  ap::AttitudeState msg;
  encoder.state(s, msg);
  tf2::BufferCore buffer;
  publish(encoder, s, buffer);
  const Eigen::Quaterniond q_child_body =
      lookup(buffer, msg.child_frame_id, "base_link", msg.header.stamp);
  const Eigen::Vector3d b_B = Eigen::Vector3d(0.01, -0.02, 0.03) + s.gyro_bias_estimate_B;
  EXPECT_LT((ap::toEigen(msg.gyro_bias) - q_child_body * b_B).norm(), 1e-15);
  const Eigen::Vector3d stddev = (q_child_body * s.gyro_bias_stddev_B).cwiseAbs();
  EXPECT_LT((ap::toEigen(msg.gyro_bias_stddev) - stddev).norm(), 1e-15);

  // With an engine, the configured part is the engine's: here the bias topic's sample.
  struct Sink : ap::EngineSink {
    void publishState(const ap::EngineState&) override {}
    void inputApplied(const ap::Input&, const ap::EngineState&) override {}
    void note(const ap::EngineNote&) override {}
  } sink;
  ap::AttitudeEngine engine(ap::engineConfig(config), sink);
  ASSERT_TRUE(engine.submitBias(1, Eigen::Vector3d(0.5, 0.25, -0.125)));
  ap::Input rate;
  rate.stamp = 2;
  engine.submit(rate);  // the sample takes effect with the rates stamped after it
  ap::EngineState t = engine.state();
  ap::AttitudeState from_engine;
  ap::OutputEncoder(config, engine).state(t, from_engine);
  EXPECT_LT((ap::toEigen(from_engine.gyro_bias) - q_child_body * Eigen::Vector3d(0.5, 0.25, -0.125))
                .norm(),
            1e-15);
  EXPECT_EQ(ap::toEigen(from_engine.gyro_bias_stddev), Eigen::Vector3d::Zero());
}

TEST_P(EveryWorld, ReverseTfPublishesTheInverseFromTheBody) {
  const ap::OutputEncoder encoder(configFor(GetParam(), true), "kinematic", "cf4");
  const ap::EngineState s = someState();
  geometry_msgs::TransformStamped t;
  encoder.transform(s, t);
  EXPECT_EQ(t.header.frame_id, "base_link");
  EXPECT_EQ(t.child_frame_id, "world");
  // tf's tree keeps REP-103's axes: world ← base_link is the engine's attitude either way.
  tf2::BufferCore buffer;
  publish(encoder, s, buffer);
  EXPECT_LT(angleBetween(lookup(buffer, "world", "base_link", t.header.stamp), s.q_WB), 1e-12);
}

INSTANTIATE_TEST_SUITE_P(Worlds, EveryWorld, ::testing::Values("enu", "nwu", "ned"));

// NED written out: a level body facing north reads as the identity; its /tf_static frames are
// world → world_ned and base_link → base_link_frd, nothing for enu.
TEST(OutputFrames, NedNamesItsAxesOnTfStaticAndEnuNamesNone) {
  EXPECT_TRUE(ap::OutputEncoder(configFor("enu"), "k", "i").conventionFrames(ros::Time(1)).empty());
  const auto frames = ap::OutputEncoder(configFor("ned"), "k", "i").conventionFrames(ros::Time(1));
  ASSERT_EQ(frames.size(), 2u);
  EXPECT_EQ(frames[0].header.frame_id, "world");
  EXPECT_EQ(frames[0].child_frame_id, "world_ned");
  EXPECT_EQ(frames[1].header.frame_id, "base_link");
  EXPECT_EQ(frames[1].child_frame_id, "base_link_frd");
  const auto nwu = ap::OutputEncoder(configFor("nwu"), "k", "i").conventionFrames(ros::Time(1));
  ASSERT_EQ(nwu.size(), 1u);
  EXPECT_EQ(nwu[0].child_frame_id, "world_nwu");

  ap::EngineState s;
  s.q_WB = about(Eigen::Vector3d::UnitZ(), M_PI / 2);  // FLU forward along ENU north
  ap::AttitudeState msg;
  ap::OutputEncoder(configFor("ned"), "k", "i").state(s, msg);
  EXPECT_LT(angleBetween(ap::toEigen(msg.orientation), Eigen::Quaterniond::Identity()), 1e-15);
}

// The feedback-loop rule: an output resolving to an input's name is named with both roles; the
// standalone launch's `imu_topic:=/imu/data` is the case (the output imu/data resolves to it).
TEST(FeedbackLoop, AnOutputNamedAsAnInputIsNamedWithBoth) {
  const std::vector<ap::NamedTopic> outputs{{"imu/data", "/imu/data"},
                                            {"attitude_state", "/attitude_state"}};
  const std::vector<ap::NamedTopic> inputs{{"imu/data_raw", "/imu/data"},
                                           {"gyro_bias", "/gyro_bias"}};
  const auto loop = ap::feedbackLoop(outputs, inputs);
  ASSERT_TRUE(loop);
  EXPECT_EQ(*loop,
            "output imu/data and input imu/data_raw are both /imu/data: the node would read what "
            "it publishes (a feedback loop); remap one of them");
  const std::vector<ap::NamedTopic> apart{{"imu/data_raw", "/imu/data_raw"},
                                          {"gyro_bias", "/gyro_bias"}};
  EXPECT_FALSE(ap::feedbackLoop(outputs, apart));
  EXPECT_TRUE(ap::feedbackLoop(outputs, {{"orientation_fix", "/attitude_state"}}));
}
