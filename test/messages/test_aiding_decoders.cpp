// The accelerometer in an Imu message and the magnetometer's MagneticField (input_decoders.h):
// the same stamp and frame rules as the rates, REP-145's "none" for the acceleration, and the
// covariance taken into the body as C R Cᵀ. The truths are closed forms written here (a
// rotation built from an angle and an axis, multiplied out by Eigen), never figures the
// decoders printed.
#include <gtest/gtest.h>

#include <string>

#include <tf2/buffer_core.h>

#include "attitude_propagator/messages/aiding_counters.h"
#include "attitude_propagator/messages/conversions.h"
#include "attitude_propagator/messages/frame_source.h"
#include "attitude_propagator/messages/input_decoders.h"

namespace ap = attitude_propagator;

namespace {

const Eigen::Vector3d kMountAxis = Eigen::Vector3d(1, 2, 3).normalized();
constexpr double kMountAngle = 0.7;
const ros::Time kArrival(1700000000, 250000000);
const ros::Time kHeader(1700000000, 100000000);

/// C_BS: a rotation about a skew axis, so C and Cᵀ give different results.
Eigen::Matrix3d mountMatrix() {
  return Eigen::AngleAxisd(kMountAngle, kMountAxis).toRotationMatrix();
}

void addTransform(tf2::BufferCore& buffer, const std::string& parent, const std::string& child,
                  const Eigen::Quaterniond& q) {
  geometry_msgs::TransformStamped t;
  t.header.frame_id = parent;
  t.child_frame_id = child;
  ap::toMsg(q, t.transform.rotation);
  buffer.setTransform(t, "test", true);
}

/// base_link -> imu_link: the mount, static.
void addMount(tf2::BufferCore& buffer, const std::string& child = "imu_link") {
  addTransform(buffer, "base_link", child, Eigen::Quaterniond(mountMatrix()));
}

ap::DecoderFrames frames() { return {"base_link", "world", ap::TorqueFrame::Body}; }

const Eigen::Vector3d kF_S(0.4, -1.2, 9.7);       // m/s^2
const Eigen::Vector3d kM_S(2e-5, -0.5e-5, 4e-5);  // T

/// A covariance with cross terms (symmetric, positive definite).
Eigen::Matrix3d covariance(double scale) {
  Eigen::Matrix3d R;
  R << 4.0, 1.0, -0.5,  //
      1.0, 3.0, 0.2,    //
      -0.5, 0.2, 2.0;
  return scale * R;
}

sensor_msgs::Imu imu(const std::string& frame, const ros::Time& stamp = kHeader) {
  sensor_msgs::Imu m;
  m.header.frame_id = frame;
  m.header.stamp = stamp;
  m.angular_velocity.x = 0.3;
  ap::toMsg(kF_S, m.linear_acceleration);
  return m;
}

sensor_msgs::MagneticField field(const std::string& frame, const ros::Time& stamp = kHeader) {
  sensor_msgs::MagneticField m;
  m.header.frame_id = frame;
  m.header.stamp = stamp;
  ap::toMsg(kM_S, m.magnetic_field);
  return m;
}

}  // namespace

// In the body frame (or no frame) the specific force is taken as it is, at the rate's stamp.
TEST(AccelerometerDecoder, BodyFrameTakenAsItIs) {
  ap::InputDecoders decoders(frames());
  for (const std::string frame : {"", "base_link"}) {
    const ap::DecodedInput in = decoders.imu(imu(frame), kArrival, nullptr);
    ASSERT_TRUE(in) << frame;
    ASSERT_TRUE(in.acceleration.has_value()) << frame;
    EXPECT_EQ(in.acceleration->value_B, kF_S);
    EXPECT_EQ(in.acceleration->stamp, in->stamp);
    EXPECT_EQ(in.acceleration->stamp, ap::toStamp(kHeader));
    EXPECT_TRUE(in.acceleration->covariance_B.isZero(0.0));  // none given: the engine's default
  }
}

// A mounted IMU: f_B = C_BS f_S and R_B = C_BS R_S C_BSᵀ, through the rate's own mount.
TEST(AccelerometerDecoder, RotatedMountGivesTheRotatedVectorAndCovariance) {
  tf2::BufferCore buffer;
  addMount(buffer);
  ap::BufferCoreFrames tf(buffer);
  ap::InputDecoders decoders(frames());
  sensor_msgs::Imu m = imu("imu_link");
  ap::covarianceToMsg(covariance(1e-3), m.linear_acceleration_covariance);
  const ap::DecodedInput in = decoders.imu(m, kArrival, &tf);
  ASSERT_TRUE(in);
  ASSERT_TRUE(in.acceleration.has_value());
  const Eigen::Matrix3d C = mountMatrix();
  EXPECT_LT((in.acceleration->value_B - C * kF_S).norm(), 1e-14);
  const Eigen::Matrix3d R_B = C * covariance(1e-3) * C.transpose();
  EXPECT_LT((in.acceleration->covariance_B - R_B).norm(), 1e-17);
  ASSERT_GT((C.transpose() * covariance(1e-3) * C - R_B).norm(), 1e-4);  // tells C from Cᵀ
  // The next message needs no frame source: the kept mount.
  const ap::DecodedInput again = decoders.imu(m, kArrival, nullptr);
  ASSERT_TRUE(again.acceleration.has_value());
  EXPECT_LT((again.acceleration->value_B - C * kF_S).norm(), 1e-14);
}

// REP-145: linear_acceleration_covariance[0] == -1 says there is no acceleration: nothing to
// submit, and the rate is still taken.
TEST(AccelerometerDecoder, Rep145NoAccelerationIsSkippedNotRefused) {
  ap::InputDecoders decoders(frames());
  sensor_msgs::Imu m = imu("base_link");
  m.linear_acceleration_covariance[0] = -1.0;
  const ap::DecodedInput in = decoders.imu(m, kArrival, nullptr);
  ASSERT_TRUE(in);
  EXPECT_FALSE(in.acceleration.has_value());
  EXPECT_FALSE(ap::readImuAcceleration(m, kArrival).has_value());
}

// A refused rate takes its accelerometer with it (no rate, no stamp rule applied for it).
TEST(AccelerometerDecoder, RefusedRateGivesNoAcceleration) {
  ap::InputDecoders decoders(frames());
  sensor_msgs::Imu m = imu("base_link");
  m.angular_velocity_covariance[0] = -1.0;
  const ap::DecodedInput in = decoders.imu(m, kArrival, nullptr);
  EXPECT_FALSE(in);
  EXPECT_FALSE(in.acceleration.has_value());
}

// A zero stamp is the arrival time, for the acceleration as for the rate.
TEST(AccelerometerDecoder, ZeroStampIsTheArrival) {
  ap::InputDecoders decoders(frames());
  const ap::DecodedInput in = decoders.imu(imu("base_link", ros::Time()), kArrival, nullptr);
  ASSERT_TRUE(in.acceleration.has_value());
  EXPECT_EQ(in.acceleration->stamp, ap::toStamp(kArrival));
}

// world_frame: ned changes nothing on the way in: inputs are in REP-103's axes. An FRD sensor
// frame has its own mount on tf (a half turn about forward), which flips y and z, as for rates.
TEST(AccelerometerDecoder, NedWorldFrameWithAnFrdSensorFrame) {
  ap::Parameters p;
  p.world_frame = "ned";
  const ap::NodeConfig config = ap::validateParameters(p);
  tf2::BufferCore buffer;
  addTransform(buffer, "base_link", "imu_frd",
               Eigen::Quaterniond(Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitX())));
  ap::BufferCoreFrames tf(buffer);
  ap::InputDecoders decoders(ap::DecoderFrames::of(config));
  sensor_msgs::Imu m = imu("imu_frd");
  const Eigen::Matrix3d R_S = covariance(1e-3);
  ap::covarianceToMsg(R_S, m.linear_acceleration_covariance);
  const ap::DecodedInput in = decoders.imu(m, kArrival, &tf);
  ASSERT_TRUE(in.acceleration.has_value());
  EXPECT_LT((in.acceleration->value_B - Eigen::Vector3d(kF_S.x(), -kF_S.y(), -kF_S.z())).norm(),
            1e-14);
  // C = diag(1, -1, -1): the x-y and x-z correlations change sign, y-z keeps it.
  Eigen::Matrix3d R_B = R_S;
  R_B(0, 1) = R_B(1, 0) = -R_S(0, 1);
  R_B(0, 2) = R_B(2, 0) = -R_S(0, 2);
  EXPECT_LT((in.acceleration->covariance_B - R_B).norm(), 1e-17);
  // In the body's own frame the acceleration is as given under ned as under enu.
  const ap::DecodedInput body = decoders.imu(imu("base_link"), kArrival, nullptr);
  EXPECT_EQ(body.acceleration->value_B, kF_S);
}

// The field in the rates' frame goes through the rates' mount; its covariance C R Cᵀ.
TEST(MagneticFieldDecoder, RatesMountFrameUsesTheRatesMount) {
  tf2::BufferCore buffer;
  addMount(buffer);
  ap::BufferCoreFrames tf(buffer);
  ap::InputDecoders decoders(frames());
  ASSERT_TRUE(decoders.imu(imu("imu_link"), kArrival, &tf));
  sensor_msgs::MagneticField m = field("imu_link");
  ap::covarianceToMsg(covariance(1e-14), m.magnetic_field_covariance);
  const ap::DecodedField f = decoders.magneticField(m, kArrival, nullptr);  // no lookup
  ASSERT_TRUE(f);
  const Eigen::Matrix3d C = mountMatrix();
  EXPECT_LT((f->value_B - C * kM_S).norm(), 1e-19);
  EXPECT_LT((f->covariance_B - C * covariance(1e-14) * C.transpose()).norm(), 1e-28);
  EXPECT_EQ(f->stamp, ap::toStamp(kHeader));
  EXPECT_FALSE(f.new_mount);
  EXPECT_TRUE(decoders.magSettled());
}

// A magnetometer on a frame of its own: its mount looked up once and kept; none given, the
// covariance stays zero (mag_stddev in the engine); a zero stamp is the arrival.
TEST(MagneticFieldDecoder, OwnFrameLookedUpOnceThenKept) {
  tf2::BufferCore buffer;
  addMount(buffer, "mag_link");
  ap::BufferCoreFrames tf(buffer);
  ap::InputDecoders decoders(frames());
  const ap::DecodedField first = decoders.magneticField(field("mag_link"), kArrival, &tf);
  ASSERT_TRUE(first);
  EXPECT_TRUE(first.new_mount);
  EXPECT_EQ(decoders.magFrame(), "mag_link");
  EXPECT_LT((first->value_B - mountMatrix() * kM_S).norm(), 1e-19);
  EXPECT_TRUE(first->covariance_B.isZero(0.0));
  const ap::DecodedField next =
      decoders.magneticField(field("mag_link", ros::Time()), kArrival, nullptr);
  ASSERT_TRUE(next);
  EXPECT_FALSE(next.new_mount);
  EXPECT_EQ(next->stamp, ap::toStamp(kArrival));
  EXPECT_LT((next->value_B - mountMatrix() * kM_S).norm(), 1e-19);
}

// In the body frame as it is; an unknown frame refused by name, as the rates' (dropped_no_tf).
TEST(MagneticFieldDecoder, BodyFrameAsItIsUnknownFrameRefused) {
  ap::InputDecoders decoders(frames());
  const ap::DecodedField body = decoders.magneticField(field("base_link"), kArrival, nullptr);
  ASSERT_TRUE(body);
  EXPECT_EQ(body->value_B, kM_S);
  tf2::BufferCore buffer;
  ap::BufferCoreFrames tf(buffer);
  const ap::DecodedField unknown = decoders.magneticField(field("compass"), kArrival, &tf);
  ASSERT_FALSE(unknown);
  EXPECT_EQ(unknown.refusal->why, ap::Refused::NoTransform);
  EXPECT_EQ(unknown.refusal->frame, "compass");
  const ap::DecodedField no_time =
      decoders.magneticField(field("base_link", ros::Time()), ros::Time(), nullptr);
  ASSERT_FALSE(no_time);
  EXPECT_EQ(no_time.refusal->why, ap::Refused::NoTime);
}

// The counters' names: accel_ then mag_, each in AidingCounters::forEach's order.
TEST(AidingCounters, NamedAccelThenMagInTheCoresOrder) {
  ap::EngineCounters c;
  c.accel.aligned = 1;
  c.mag.future = 7;
  std::vector<std::string> names;
  std::uint64_t sum = 0;
  ap::forEachAidingCounter(c, [&](const std::string& name, std::uint64_t value) {
    names.push_back(name);
    sum += name == "accel_aligned" ? value : name == "mag_future" ? 10 * value : 1000 * value;
  });
  ASSERT_EQ(names.size(), 22u);
  EXPECT_EQ(names.front(), "accel_accepted");
  EXPECT_EQ(names[9], "accel_future");
  EXPECT_EQ(names[10], "accel_over_budget");
  EXPECT_EQ(names[11], "mag_accepted");
  EXPECT_EQ(names[20], "mag_future");
  EXPECT_EQ(names.back(), "mag_over_budget");
  EXPECT_EQ(sum, 71u);
}
