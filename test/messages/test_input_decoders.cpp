// The decoders of every input message (input_decoders.h) and the frame source over tf2's
// BufferCore (frame_source.h), rule by rule: frames, covariance, stamps, types, torque frames,
// bias frames and refusals by name. The truths are closed forms written here (a rotation built
// from an angle and an axis, C R Cᵀ multiplied out by Eigen) or tf2's own composition of
// transforms (a BufferCore lookup), never figures the decoders printed.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include <tf2/buffer_core.h>

#include "../core/engine_fixtures.h"
#include "attitude_propagator/messages/conversions.h"
#include "attitude_propagator/messages/frame_source.h"
#include "attitude_propagator/messages/input_decoders.h"
#include "serialized_message.h"

namespace ap = attitude_propagator;

namespace {

using messages_test::Serialized;

const Eigen::Vector3d kMountAxis = Eigen::Vector3d(1, 2, 3).normalized();
constexpr double kMountAngle = 0.7;

/// C_BS: the mount, a rotation about a skew axis, so C and Cᵀ give different results.
Eigen::Matrix3d mountMatrix() {
  return Eigen::AngleAxisd(kMountAngle, kMountAxis).toRotationMatrix();
}

geometry_msgs::TransformStamped transform(const std::string& parent, const std::string& child,
                                          const Eigen::Quaterniond& q, double stamp = 0.0) {
  geometry_msgs::TransformStamped t;
  t.header.frame_id = parent;
  t.header.stamp = ros::Time(stamp);
  t.child_frame_id = child;
  ap::toMsg(q, t.transform.rotation);
  t.transform.translation.x = 0.1;  // a translation, which a rotation of vectors ignores
  return t;
}

/// base_link -> imu_link: the mount, static.
void addMount(tf2::BufferCore& buffer) {
  buffer.setTransform(transform("base_link", "imu_link",
                                Eigen::Quaterniond(Eigen::AngleAxisd(kMountAngle, kMountAxis))),
                      "test", true);
}

ap::DecoderFrames frames(ap::TorqueFrame torque_frame = ap::TorqueFrame::Body) {
  return {"base_link", "world", torque_frame};
}

const ros::Time kArrival(1700000000, 250000000);
const ros::Time kHeader(1700000000, 100000000);

sensor_msgs::Imu imu(const std::string& frame, const ros::Time& stamp = kHeader) {
  sensor_msgs::Imu m;
  m.header.frame_id = frame;
  m.header.stamp = stamp;
  m.angular_velocity.x = 0.3;
  m.angular_velocity.y = -0.2;
  m.angular_velocity.z = 0.5;
  return m;
}

Eigen::Vector3d w_S() { return Eigen::Vector3d(0.3, -0.2, 0.5); }

/// A covariance with cross terms (symmetric, positive definite).
Eigen::Matrix3d R_S() {
  Eigen::Matrix3d R;
  R << 4e-4, 1e-4, -5e-5,  //
      1e-4, 3e-4, 2e-5,    //
      -5e-5, 2e-5, 2e-4;
  return R;
}

geometry_msgs::Twist twist(double x, double y, double z) {
  geometry_msgs::Twist t;
  t.angular.x = x;
  t.angular.y = y;
  t.angular.z = z;
  t.linear.x = 9.0;  // not a rate
  return t;
}

geometry_msgs::TwistStamped twistStamped(const std::string& frame, const ros::Time& stamp) {
  geometry_msgs::TwistStamped t;
  t.header.frame_id = frame;
  t.header.stamp = stamp;
  t.twist = twist(0.3, -0.2, 0.5);
  return t;
}

geometry_msgs::WrenchStamped wrenchStamped(const std::string& frame, const Eigen::Vector3d& tau,
                                           const ros::Time& stamp = kHeader) {
  geometry_msgs::WrenchStamped w;
  w.header.frame_id = frame;
  w.header.stamp = stamp;
  ap::toMsg(tau, w.wrench.torque);
  w.wrench.force.x = 7.0;  // not a torque
  return w;
}

geometry_msgs::Vector3Stamped bias(const std::string& frame, const ros::Time& stamp = kHeader) {
  geometry_msgs::Vector3Stamped b;
  b.header.frame_id = frame;
  b.header.stamp = stamp;
  b.vector.x = 0.01;
  b.vector.y = -0.02;
  b.vector.z = 0.03;
  return b;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// The frame source
// ---------------------------------------------------------------------------------------------

// rotation(target, source) takes a vector in source's axes into target's: C_BS ω_S, not Cᵀ.
// The topics the node subscribes (docs/node.md's table of inputs), as the log names them: the
// message layer names them, never the core.
TEST(InputTopicName, TheNodesTopicsRelativeToItsNamespace) {
  EXPECT_STREQ(ap::inputTopicName(ap::Source::Imu), "imu/data_raw");
  EXPECT_STREQ(ap::inputTopicName(ap::Source::Twist), "body_twist");
  EXPECT_STREQ(ap::inputTopicName(ap::Source::Torque), "torque");
}

TEST(FrameSource, RotationTakesSourceVectorsIntoTargetAxes) {
  tf2::BufferCore buffer;
  addMount(buffer);
  ap::BufferCoreFrames source(buffer);
  const auto q = source.rotation("base_link", "imu_link", ros::Time());
  ASSERT_TRUE(q);
  const Eigen::Vector3d expected = mountMatrix() * w_S();
  EXPECT_LT((*q * w_S() - expected).norm(), 1e-15);
  ASSERT_GT((mountMatrix().transpose() * w_S() - expected).norm(), 0.1);  // C and Cᵀ differ
  const auto back = source.rotation("imu_link", "base_link", ros::Time());
  ASSERT_TRUE(back);
  EXPECT_LT((*back * expected - w_S()).norm(), 1e-15);
}

// A chain of a static and a dynamic transform: what tf2 composes, at the latest time.
TEST(FrameSource, ChainsAsTf2ComposesThem) {
  tf2::BufferCore buffer;
  const Eigen::Quaterniond q_BP(Eigen::AngleAxisd(0.4, Eigen::Vector3d(0, 1, 1).normalized()));
  const Eigen::Quaterniond q_PS(Eigen::AngleAxisd(-1.1, Eigen::Vector3d(3, -1, 2).normalized()));
  buffer.setTransform(transform("base_link", "plate", q_BP), "urdf", true);
  buffer.setTransform(transform("plate", "sensor", q_PS, 5.0), "driver", false);
  ap::BufferCoreFrames source(buffer);
  const auto q = source.rotation("base_link", "sensor", ros::Time());
  ASSERT_TRUE(q);
  const Eigen::Quaterniond by_tf2 =
      ap::rotationOf(buffer.lookupTransform("base_link", "sensor", ros::Time()));
  EXPECT_LT(q->angularDistance(by_tf2), 1e-12);
  EXPECT_LT(q->angularDistance(q_BP * q_PS), 1e-12);  // the composition by hand
}

TEST(FrameSource, UnknownFrameIsNoneWithTfsReason) {
  tf2::BufferCore buffer;
  addMount(buffer);
  ap::BufferCoreFrames source(buffer);
  std::string error;
  EXPECT_FALSE(source.rotation("base_link", "nowhere", ros::Time(), &error));
  EXPECT_NE(error.find("nowhere"), std::string::npos) << error;
}

// ---------------------------------------------------------------------------------------------
// Rates: frames and covariance
// ---------------------------------------------------------------------------------------------

TEST(RateFrames, BodyFrameOrNoFrameTakenAsItIs) {
  ap::InputDecoders decoders(frames());
  for (const std::string frame : {"", "base_link"}) {
    sensor_msgs::Imu m = imu(frame);
    ap::covarianceToMsg(R_S(), m.angular_velocity_covariance);
    const ap::DecodedInput in = decoders.imu(m, kArrival, nullptr);  // no lookup needed
    ASSERT_TRUE(in) << frame;
    EXPECT_EQ(in->source, ap::Source::Imu);
    EXPECT_EQ(in->value, w_S());
    EXPECT_EQ(in->rate_covariance_B, R_S());
    EXPECT_FALSE(in.new_mount);
  }
  EXPECT_EQ(decoders.mountFrame(), "");
}

// ω_B = C_BS ω_S and R_B = C_BS R_S C_BSᵀ, with cross terms, through a skew mount.
TEST(RateFrames, ImuInItsMountFrameIsRotatedIntoTheBody) {
  tf2::BufferCore buffer;
  addMount(buffer);
  ap::BufferCoreFrames tf(buffer);
  ap::InputDecoders decoders(frames());
  sensor_msgs::Imu m = imu("imu_link");
  ap::covarianceToMsg(R_S(), m.angular_velocity_covariance);
  const ap::DecodedInput in = decoders.imu(m, kArrival, &tf);
  ASSERT_TRUE(in);
  const Eigen::Matrix3d C = mountMatrix();
  EXPECT_LT((in->value - C * w_S()).norm(), 1e-15);
  const Eigen::Matrix3d R_B = C * R_S() * C.transpose();
  EXPECT_LT((in->rate_covariance_B - R_B).norm(), 1e-18);
  ASSERT_GT((C.transpose() * R_S() * C - R_B).norm(), 1e-5);  // the test tells C from Cᵀ
  EXPECT_TRUE(in.new_mount);
  EXPECT_LT(in.q_BS.angularDistance(Eigen::Quaterniond(C)), 1e-15);
  EXPECT_EQ(decoders.mountFrame(), "imu_link");
}

// Zero covariance means "none given": it stays zero (the engine uses the configured default).
TEST(RateFrames, NoCovarianceStaysNone) {
  tf2::BufferCore buffer;
  addMount(buffer);
  ap::BufferCoreFrames tf(buffer);
  ap::InputDecoders decoders(frames());
  const ap::DecodedInput in = decoders.imu(imu("imu_link"), kArrival, &tf);
  ASSERT_TRUE(in);
  EXPECT_TRUE(in->rate_covariance_B.isZero(0.0));
}

// The mount is looked up once: later messages in its frame need no frame source.
TEST(RateFrames, MountLookedUpOnceThenKept) {
  tf2::BufferCore buffer;
  addMount(buffer);
  ap::BufferCoreFrames tf(buffer);
  ap::InputDecoders decoders(frames());
  ASSERT_TRUE(decoders.imu(imu("imu_link"), kArrival, &tf).new_mount);
  const ap::DecodedInput again = decoders.imu(imu("imu_link"), kArrival, nullptr);
  ASSERT_TRUE(again);
  EXPECT_FALSE(again.new_mount);
  EXPECT_LT((again->value - mountMatrix() * w_S()).norm(), 1e-15);
}

// Rates in yet another frame: that frame's mount is looked up and replaces the kept one.
TEST(RateFrames, AnotherFrameReplacesTheMount) {
  tf2::BufferCore buffer;
  addMount(buffer);
  const Eigen::Quaterniond q_B2(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitX()));
  buffer.setTransform(transform("base_link", "imu2", q_B2), "test", true);
  ap::BufferCoreFrames tf(buffer);
  ap::InputDecoders decoders(frames());
  ASSERT_TRUE(decoders.imu(imu("imu_link"), kArrival, &tf));
  const ap::DecodedInput in = decoders.imu(imu("imu2"), kArrival, &tf);
  ASSERT_TRUE(in);
  EXPECT_TRUE(in.new_mount);
  EXPECT_EQ(decoders.mountFrame(), "imu2");
  EXPECT_LT((in->value - q_B2.toRotationMatrix() * w_S()).norm(), 1e-15);
}

// A mount on /tf (a dynamic transform) serves as well as one on /tf_static.
TEST(RateFrames, MountOnTfIsFound) {
  tf2::BufferCore buffer;
  buffer.setTransform(transform("base_link", "imu_link", Eigen::Quaterniond(mountMatrix()), 3.0),
                      "driver", false);
  ap::BufferCoreFrames tf(buffer);
  ap::InputDecoders decoders(frames());
  const ap::DecodedInput in = decoders.imu(imu("imu_link"), kArrival, &tf);
  ASSERT_TRUE(in);
  EXPECT_LT((in->value - mountMatrix() * w_S()).norm(), 1e-15);
}

TEST(RateFrames, UnknownFrameRefusedByName) {
  tf2::BufferCore buffer;
  addMount(buffer);
  ap::BufferCoreFrames tf(buffer);
  ap::InputDecoders decoders(frames());
  const ap::DecodedInput in = decoders.imu(imu("nowhere"), kArrival, &tf);
  ASSERT_FALSE(in);
  ASSERT_TRUE(in.refusal);
  EXPECT_EQ(in.refusal->why, ap::Refused::NoTransform);
  EXPECT_EQ(in.refusal->frame, "nowhere");
  EXPECT_NE(in.refusal->detail.find("nowhere"), std::string::npos) << in.refusal->detail;
  EXPECT_STREQ(ap::refusedCounter(in.refusal->why), "dropped_no_tf");
  EXPECT_EQ(decoders.mountFrame(), "");  // nothing kept
  // Without a frame source, a frame that needs a lookup is refused alike.
  EXPECT_EQ(decoders.imu(imu("imu_link"), kArrival, nullptr).refusal->why,
            ap::Refused::NoTransform);
  // A known mount is kept when a message comes in an unknown frame.
  ASSERT_TRUE(decoders.imu(imu("imu_link"), kArrival, &tf));
  EXPECT_FALSE(decoders.imu(imu("nowhere"), kArrival, &tf));
  EXPECT_EQ(decoders.mountFrame(), "imu_link");
}

// A TwistStamped in the mount frame is rotated like an IMU; a plain Twist is a body rate.
TEST(RateFrames, TwistStampedRotatedPlainTwistInTheBody) {
  tf2::BufferCore buffer;
  addMount(buffer);
  ap::BufferCoreFrames tf(buffer);
  ap::InputDecoders decoders(frames());
  const ap::DecodedInput stamped = decoders.twist(twistStamped("imu_link", kHeader), kArrival, &tf);
  ASSERT_TRUE(stamped);
  EXPECT_EQ(stamped->source, ap::Source::Twist);
  EXPECT_LT((stamped->value - mountMatrix() * w_S()).norm(), 1e-15);
  EXPECT_TRUE(stamped->rate_covariance_B.isZero(0.0));
  const ap::DecodedInput plain = decoders.twist(twist(0.3, -0.2, 0.5), kArrival);
  ASSERT_TRUE(plain);
  EXPECT_EQ(plain->value, w_S());
}

// ---------------------------------------------------------------------------------------------
// IMU refusals before the frame
// ---------------------------------------------------------------------------------------------

TEST(ImuDecoder, Rep145NoRateRefused) {
  ap::InputDecoders decoders(frames());
  sensor_msgs::Imu m = imu("nowhere");  // refused before its frame is looked at
  m.angular_velocity_covariance[0] = -1.0;
  const ap::DecodedInput in = decoders.imu(m, kArrival, nullptr);
  ASSERT_TRUE(in.refusal);
  EXPECT_EQ(in.refusal->why, ap::Refused::NoRate);
  EXPECT_STREQ(ap::refusedCounter(ap::Refused::NoRate), "rejected_no_rate");
}

TEST(ImuDecoder, CovarianceThatIsNoneRefusedWithTheCheck) {
  ap::InputDecoders decoders(frames());
  sensor_msgs::Imu m = imu("base_link");
  Eigen::Matrix3d R = R_S();
  R(1, 1) = -1e-4;
  ap::covarianceToMsg(R, m.angular_velocity_covariance);
  const ap::DecodedInput in = decoders.imu(m, kArrival, nullptr);
  ASSERT_TRUE(in.refusal);
  EXPECT_EQ(in.refusal->why, ap::Refused::BadCovariance);
  EXPECT_EQ(in.refusal->check, ap::RateCovarianceCheck::NegativeVariance);
  R = R_S();
  R(0, 1) = 2e-4;  // not symmetric
  ap::covarianceToMsg(R, m.angular_velocity_covariance);
  EXPECT_EQ(decoders.imu(m, kArrival, nullptr).refusal->check,
            ap::RateCovarianceCheck::NotSymmetric);
}

// Non-finite values are the engine's to reject and count: the decoder passes them on.
TEST(ImuDecoder, NonFiniteValuesPassToTheEngine) {
  ap::InputDecoders decoders(frames());
  sensor_msgs::Imu m = imu("base_link");
  m.angular_velocity.y = std::numeric_limits<double>::quiet_NaN();
  const ap::DecodedInput in = decoders.imu(m, kArrival, nullptr);
  ASSERT_TRUE(in);
  EXPECT_TRUE(std::isnan(in->value.y()));
}

// A NaN or infinite covariance is rejected as non-finite, like a NaN rate (docs/node.md, the
// table of bad inputs: `rejected_non_finite`), not as a covariance that is no covariance: the
// decoder passes it on and the engine counts it once, under rejected_non_finite.
TEST(ImuDecoder, NonFiniteCovarianceIsTheEnginesNonFiniteRejection) {
  engine_fixtures::DiscardingSink sink;
  ap::AttitudeEngine engine(ap::engineConfig(ap::validateParameters(ap::Parameters())), sink);
  ap::InputDecoders decoders(frames());
  sensor_msgs::Imu m = imu("base_link");
  m.angular_velocity_covariance[4] = std::numeric_limits<double>::infinity();
  const ap::DecodedInput in = decoders.imu(m, kArrival, nullptr);
  ASSERT_TRUE(in);
  EXPECT_FALSE(in->rate_covariance_B.allFinite());
  engine.submit(*in.value);
  EXPECT_EQ(engine.counters().rejected_non_finite, 1u);
  EXPECT_EQ(engine.counters().rejected_covariance, 0u);
  EXPECT_EQ(engine.counters().accepted, 0u);
}

// ---------------------------------------------------------------------------------------------
// Stamps
// ---------------------------------------------------------------------------------------------

TEST(Stamps, HeaderStampOrArrivalWhenZeroOrNone) {
  ap::InputDecoders decoders(frames());
  EXPECT_EQ(decoders.imu(imu("", kHeader), kArrival, nullptr)->stamp, ap::toStamp(kHeader));
  EXPECT_EQ(decoders.imu(imu("", ros::Time()), kArrival, nullptr)->stamp, ap::toStamp(kArrival));
  EXPECT_EQ(decoders.twist(twistStamped("", ros::Time()), kArrival, nullptr)->stamp,
            ap::toStamp(kArrival));
  EXPECT_EQ(decoders.twist(twistStamped("", kHeader), kArrival, nullptr)->stamp,
            ap::toStamp(kHeader));
  EXPECT_EQ(decoders.twist(twist(1, 2, 3), kArrival)->stamp, ap::toStamp(kArrival));
  EXPECT_EQ(decoders.torque(geometry_msgs::Wrench(), kArrival)->stamp, ap::toStamp(kArrival));
  EXPECT_EQ(
      decoders.torque(wrenchStamped("", Eigen::Vector3d::Zero(), ros::Time()), kArrival, nullptr)
          ->stamp,
      ap::toStamp(kArrival));
  // 1.7e18 ns: the nanoseconds exactly, not through a double.
  EXPECT_EQ(ap::toStamp(kHeader), 1700000000100000000LL);
}

// No stamp and no time (sim time before the first /clock): refused, NoTime.
TEST(Stamps, NoStampAndNoTimeRefused) {
  ap::InputDecoders decoders(frames());
  EXPECT_EQ(decoders.imu(imu("", ros::Time()), ros::Time(), nullptr).refusal->why,
            ap::Refused::NoTime);
  EXPECT_EQ(decoders.twist(twist(1, 2, 3), ros::Time()).refusal->why, ap::Refused::NoTime);
  EXPECT_EQ(decoders.torque(geometry_msgs::Wrench(), ros::Time()).refusal->why,
            ap::Refused::NoTime);
  EXPECT_STREQ(ap::refusedCounter(ap::Refused::NoTime), "dropped_no_time");
  // A stamped message needs no arrival time.
  EXPECT_TRUE(decoders.imu(imu("", kHeader), ros::Time(), nullptr));
}

// ---------------------------------------------------------------------------------------------
// Types: one per topic, the first message's
// ---------------------------------------------------------------------------------------------

TEST(Types, TwistTopicKeepsItsFirstType) {
  ap::InputDecoders decoders(frames());
  EXPECT_EQ(decoders.twistType().datatype(), "");
  const ap::DecodedInput first =
      decoders.twistTopic(Serialized::of(twist(0.3, -0.2, 0.5)), kArrival, nullptr);
  ASSERT_TRUE(first);
  EXPECT_EQ(first->value, w_S());
  EXPECT_EQ(decoders.twistType().datatype(), "geometry_msgs/Twist");
  const ap::DecodedInput later =
      decoders.twistTopic(Serialized::of(twistStamped("", kHeader)), kArrival, nullptr);
  ASSERT_TRUE(later.refusal);
  EXPECT_EQ(later.refusal->why, ap::Refused::WrongType);
  EXPECT_EQ(later.refusal->detail, "geometry_msgs/TwistStamped");
  EXPECT_STREQ(ap::refusedCounter(ap::Refused::WrongType), "rejected_type");
  // The other topic's type is its own.
  EXPECT_TRUE(decoders.torqueTopic(Serialized::of(wrenchStamped("", Eigen::Vector3d::Zero())),
                                   kArrival, nullptr));
  EXPECT_EQ(decoders.torqueType().datatype(), "geometry_msgs/WrenchStamped");
}

TEST(Types, StampedFirstThenPlainRefused) {
  tf2::BufferCore buffer;
  addMount(buffer);
  ap::BufferCoreFrames tf(buffer);
  ap::InputDecoders decoders(frames());
  const ap::DecodedInput first =
      decoders.twistTopic(Serialized::of(twistStamped("imu_link", kHeader)), kArrival, &tf);
  ASSERT_TRUE(first);
  EXPECT_EQ(first->stamp, ap::toStamp(kHeader));
  EXPECT_LT((first->value - mountMatrix() * w_S()).norm(), 1e-15);
  EXPECT_EQ(decoders.twistTopic(Serialized::of(twist(1, 2, 3)), kArrival, &tf).refusal->why,
            ap::Refused::WrongType);
  EXPECT_TRUE(decoders.twistTopic(Serialized::of(twistStamped("", kHeader)), kArrival, &tf));
}

// A type the topic never takes (or the right name with another definition) is refused and does
// not fix the topic's type.
TEST(Types, ForeignTypeRefusedWithoutFixingTheTopic) {
  ap::InputDecoders decoders(frames());
  const ap::DecodedInput foreign =
      decoders.twistTopic(Serialized::of(geometry_msgs::Wrench()), kArrival, nullptr);
  ASSERT_TRUE(foreign.refusal);
  EXPECT_EQ(foreign.refusal->why, ap::Refused::WrongType);
  EXPECT_EQ(foreign.refusal->detail, "geometry_msgs/Wrench");
  Serialized other_definition = Serialized::of(twist(1, 2, 3));
  other_definition.md5 = "0123456789abcdef0123456789abcdef";
  EXPECT_FALSE(decoders.twistTopic(other_definition, kArrival, nullptr));
  EXPECT_EQ(decoders.twistType().datatype(), "");
  EXPECT_TRUE(decoders.twistTopic(Serialized::of(twistStamped("", kHeader)), kArrival, nullptr));
  EXPECT_EQ(decoders.twistType().datatype(), "geometry_msgs/TwistStamped");
}

// evaluate_bag reads body_twist in its own frame: the type and stamp rules, no frame rule.
TEST(Types, ReadingInItsOwnFrame) {
  ap::InputDecoders decoders(frames());
  const ap::Decoded<ap::Reading> r =
      decoders.readTwistTopic(Serialized::of(twistStamped("imu_link", ros::Time())), kArrival);
  ASSERT_TRUE(r);
  EXPECT_EQ(r->value, w_S());
  EXPECT_EQ(r->frame_id, "imu_link");
  EXPECT_EQ(r->stamp, ap::toStamp(kArrival));
  EXPECT_EQ(decoders.readTwistTopic(Serialized::of(twist(1, 2, 3)), kArrival).refusal->why,
            ap::Refused::WrongType);
}

// ---------------------------------------------------------------------------------------------
// Torque frames
// ---------------------------------------------------------------------------------------------

TEST(TorqueFrames, BodyAndFixedFramesNamedByTheHeader) {
  const Eigen::Vector3d tau(0.5, -1.5, 2.0);
  for (const ap::TorqueFrame parameter : {ap::TorqueFrame::Body, ap::TorqueFrame::Fixed}) {
    ap::InputDecoders decoders(frames(parameter));
    const ap::DecodedInput body =
        decoders.torque(wrenchStamped("base_link", tau), kArrival, nullptr);
    ASSERT_TRUE(body);
    EXPECT_EQ(body->source, ap::Source::Torque);
    EXPECT_EQ(body->frame, ap::TorqueFrame::Body);
    EXPECT_EQ(body->value, tau);
    const ap::DecodedInput fixed = decoders.torque(wrenchStamped("world", tau), kArrival, nullptr);
    ASSERT_TRUE(fixed);
    EXPECT_EQ(fixed->frame, ap::TorqueFrame::Fixed);
    EXPECT_EQ(fixed->value, tau);
    // No frame (unstamped, or an empty frame_id): the torque_frame parameter.
    const ap::DecodedInput empty = decoders.torque(wrenchStamped("", tau), kArrival, nullptr);
    ASSERT_TRUE(empty);
    EXPECT_EQ(empty->frame, parameter);
    geometry_msgs::Wrench plain;
    ap::toMsg(tau, plain.torque);
    const ap::DecodedInput unstamped = decoders.torque(plain, kArrival);
    ASSERT_TRUE(unstamped);
    EXPECT_EQ(unstamped->frame, parameter);
    EXPECT_EQ(unstamped->value, tau);
  }
}

// A third frame F: τ_B = C_BF τ_F through tf2's composition of a chain, a body torque.
TEST(TorqueFrames, ThirdFrameRotatedIntoTheBody) {
  tf2::BufferCore buffer;
  addMount(buffer);
  const Eigen::Quaterniond q_BP(Eigen::AngleAxisd(0.9, Eigen::Vector3d(-2, 1, 1).normalized()));
  buffer.setTransform(transform("base_link", "plate", q_BP), "urdf", true);
  buffer.setTransform(transform("plate", "ft_sensor", Eigen::Quaterniond(mountMatrix()), 2.0),
                      "driver", false);
  ap::BufferCoreFrames tf(buffer);
  ap::InputDecoders decoders(frames(ap::TorqueFrame::Fixed));
  const Eigen::Vector3d tau(0.5, -1.5, 2.0);
  const ap::DecodedInput in = decoders.torque(wrenchStamped("ft_sensor", tau), kArrival, &tf);
  ASSERT_TRUE(in);
  EXPECT_EQ(in->frame, ap::TorqueFrame::Body);
  const Eigen::Quaterniond q_BF =
      ap::rotationOf(buffer.lookupTransform("base_link", "ft_sensor", ros::Time()));
  EXPECT_LT((in->value - q_BF * tau).norm(), 1e-14);
  EXPECT_LT((in->value - q_BP.toRotationMatrix() * mountMatrix() * tau).norm(), 1e-14);
  EXPECT_EQ(decoders.mountFrame(), "");  // a torque frame is no rate mount
}

// A torque frame is looked up at each message (a torque sensor may move): the latest transform.
TEST(TorqueFrames, LookedUpAtEachMessage) {
  tf2::BufferCore buffer;
  buffer.setTransform(transform("base_link", "arm", Eigen::Quaterniond(mountMatrix()), 1.0),
                      "driver", false);
  ap::BufferCoreFrames tf(buffer);
  ap::InputDecoders decoders(frames());
  const Eigen::Vector3d tau(0.0, 0.0, 1.0);
  EXPECT_LT((decoders.torque(wrenchStamped("arm", tau), kArrival, &tf)->value - mountMatrix() * tau)
                .norm(),
            1e-15);
  const Eigen::Quaterniond turned(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitX()));
  buffer.setTransform(transform("base_link", "arm", turned, 2.0), "driver", false);
  EXPECT_LT((decoders.torque(wrenchStamped("arm", tau), kArrival, &tf)->value -
             Eigen::Vector3d(0.0, -1.0, 0.0))
                .norm(),
            1e-15);
}

TEST(TorqueFrames, UnknownThirdFrameRefusedByName) {
  tf2::BufferCore buffer;
  addMount(buffer);
  ap::BufferCoreFrames tf(buffer);
  ap::InputDecoders decoders(frames());
  const ap::DecodedInput in =
      decoders.torque(wrenchStamped("gripper", Eigen::Vector3d(1, 0, 0)), kArrival, &tf);
  ASSERT_TRUE(in.refusal);
  EXPECT_EQ(in.refusal->why, ap::Refused::NoTransform);
  EXPECT_EQ(in.refusal->frame, "gripper");
  // A non-finite torque is the engine's to reject: no lookup, passed on.
  const ap::DecodedInput nan = decoders.torque(
      wrenchStamped("gripper", Eigen::Vector3d(std::nan(""), 0, 0)), kArrival, nullptr);
  ASSERT_TRUE(nan);
  EXPECT_TRUE(std::isnan(nan->value.x()));
}

// ---------------------------------------------------------------------------------------------
// Gyro bias frames
// ---------------------------------------------------------------------------------------------

TEST(BiasFrames, BodyOrNoFrameTakenAsItIs) {
  ap::InputDecoders decoders(frames());
  for (const std::string frame : {"", "base_link"}) {
    const ap::Decoded<ap::BiasSample> b = decoders.bias(bias(frame), kArrival);
    ASSERT_TRUE(b) << frame;
    EXPECT_EQ(b->b_B, Eigen::Vector3d(0.01, -0.02, 0.03));
    EXPECT_EQ(b->stamp, ap::toStamp(kHeader));
  }
}

// The mount frame: refused until the rates' mount is known, then b_B = C_BS b_S.
TEST(BiasFrames, MountFrameOnceTheRatesMountIsKnown) {
  tf2::BufferCore buffer;  // tf knows it, but the rates have not used it yet
  addMount(buffer);
  ap::BufferCoreFrames tf(buffer);
  ap::InputDecoders decoders(frames());
  const ap::Decoded<ap::BiasSample> early = decoders.bias(bias("imu_link"), kArrival);
  ASSERT_TRUE(early.refusal);
  EXPECT_EQ(early.refusal->why, ap::Refused::BiasFrame);
  ASSERT_TRUE(decoders.imu(imu("imu_link"), kArrival, &tf));
  const ap::Decoded<ap::BiasSample> b = decoders.bias(bias("imu_link"), kArrival);
  ASSERT_TRUE(b);
  EXPECT_LT((b->b_B - mountMatrix() * Eigen::Vector3d(0.01, -0.02, 0.03)).norm(), 1e-17);
}

TEST(BiasFrames, AnotherFrameRefusedByName) {
  tf2::BufferCore buffer;
  addMount(buffer);
  ap::BufferCoreFrames tf(buffer);
  ap::InputDecoders decoders(frames());
  ASSERT_TRUE(decoders.imu(imu("imu_link"), kArrival, &tf));
  for (const std::string frame : {"elsewhere", "world"}) {
    const ap::Decoded<ap::BiasSample> b = decoders.bias(bias(frame), kArrival);
    ASSERT_TRUE(b.refusal) << frame;
    EXPECT_EQ(b.refusal->why, ap::Refused::BiasFrame);
    EXPECT_EQ(b.refusal->frame, frame);
  }
  EXPECT_STREQ(ap::refusedCounter(ap::Refused::BiasFrame), "rejected_bias");
}

TEST(BiasFrames, UnstampedFromNow) {
  ap::InputDecoders decoders(frames());
  EXPECT_EQ(decoders.bias(bias("", ros::Time()), kArrival)->stamp, ap::toStamp(kArrival));
  // Zero before the first /clock: from the start.
  const ap::Decoded<ap::BiasSample> start = decoders.bias(bias("", ros::Time()), ros::Time());
  ASSERT_TRUE(start);
  EXPECT_EQ(start->stamp, 0);
}

// ---------------------------------------------------------------------------------------------
// Counting: each refusal once, in its own counter
// ---------------------------------------------------------------------------------------------

TEST(Refusals, EachCountedOnceInItsNamedCounter) {
  engine_fixtures::DiscardingSink sink;
  ap::AttitudeEngine engine(ap::engineConfig(ap::validateParameters(ap::Parameters())), sink);
  auto count = [](const ap::EngineCounters& c, const std::string& name) -> std::uint64_t {
    if (name == "rejected_no_rate") return c.rejected_no_rate;
    if (name == "rejected_covariance") return c.rejected_covariance;
    if (name == "rejected_type") return c.rejected_type;
    if (name == "dropped_no_tf") return c.dropped_no_tf;
    if (name == "dropped_no_time") return c.dropped_no_time;
    if (name == "rejected_bias") return c.rejected_bias;
    ADD_FAILURE() << name;
    return 0;
  };
  const std::vector<std::string> all = {"rejected_no_rate", "rejected_covariance", "rejected_type",
                                        "dropped_no_tf",    "dropped_no_time",     "rejected_bias"};
  for (const ap::Refused why :
       {ap::Refused::NoRate, ap::Refused::BadCovariance, ap::Refused::WrongType,
        ap::Refused::NoTransform, ap::Refused::NoTime, ap::Refused::BiasFrame}) {
    const ap::EngineCounters before = engine.counters();
    ap::countRefusal(engine, why);
    const ap::EngineCounters after = engine.counters();
    for (const std::string& name : all) {
      EXPECT_EQ(count(after, name) - count(before, name), name == ap::refusedCounter(why) ? 1u : 0u)
          << ap::refusedCounter(why) << " moved " << name;
    }
    // An input refused is an input received; a bias sample is not an input.
    EXPECT_EQ(after.received - before.received, why == ap::Refused::BiasFrame ? 0u : 1u);
  }
}

TEST(DecoderFrames, FromTheNodesParameters) {
  ap::Parameters p;
  p.body_frame = "imu_body";
  p.fixed_frame = "odom";
  p.torque_frame = "fixed";
  const ap::DecoderFrames f = ap::DecoderFrames::of(ap::validateParameters(p));
  EXPECT_EQ(f.body, "imu_body");
  EXPECT_EQ(f.fixed, "odom");
  EXPECT_EQ(f.torque_frame, ap::TorqueFrame::Fixed);
}
