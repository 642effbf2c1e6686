// propagate_bag with gravity and the field (use_accel, use_mag): a static IMU tilted by a known
// roll and pitch, its accelerometer in the rate topic's Imu messages, gives the closed-form tilt
// in the output; --mag reads a magnetometer topic; the summary names the accel_* and mag_*
// counters as the node's diagnostics do.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/Imu.h>
#include <sensor_msgs/MagneticField.h>
#include <tf2_msgs/TFMessage.h>

#include "../core/sampling.h"
#include "attitude_propagator/AttitudeState.h"
#include "scene_bags.h"

namespace ap = attitude_propagator;
using namespace bagtest;

namespace {

constexpr double kG = 9.80665;
constexpr double kRoll = 0.3, kPitch = -0.2;
constexpr Stamp kPeriod = 10000000;  // 100 Hz

/// q_WB = Rz(0) Ry(pitch) Rx(roll): REP-103's ZYX angles.
Eigen::Quaterniond tilt() {
  return Eigen::Quaterniond(Eigen::AngleAxisd(kPitch, Eigen::Vector3d::UnitY())) *
         Eigen::AngleAxisd(kRoll, Eigen::Vector3d::UnitX());
}

/// ZYX roll and pitch of q.
Eigen::Vector2d rollPitch(const Eigen::Quaterniond& q) {
  const double x = q.x(), y = q.y(), z = q.z(), w = q.w();
  return {std::atan2(2.0 * (w * x + y * z), 1.0 - 2.0 * (x * x + y * y)),
          std::asin(std::max(-1.0, std::min(1.0, 2.0 * (w * y - z * x))))};
}

/// `n` samples of a static IMU with the tilt: zero rates, f_B = C_BW (0, 0, g) on
/// /imu/data_raw (the body's frame); with `mag`, the earth's field (north and down) in the body
/// on /imu/mag.
void writeStaticTilt(const std::string& path, int n, bool mag) {
  rosbag::Bag bag(path, rosbag::bagmode::Write);
  const Eigen::Vector3d f_B = tilt().conjugate() * Eigen::Vector3d(0.0, 0.0, kG);
  const Eigen::Vector3d m_B = tilt().conjugate() * Eigen::Vector3d(0.0, 2e-5, -4e-5);
  for (int k = 0; k < n; ++k) {
    const Stamp stamp = kStart + k * kPeriod;
    sensor_msgs::Imu imu;
    imu.header.stamp = rosTime(stamp);
    imu.linear_acceleration.x = f_B.x(), imu.linear_acceleration.y = f_B.y();
    imu.linear_acceleration.z = f_B.z();
    imu.orientation_covariance[0] = -1.0;
    bag.write("/imu/data_raw", rosTime(stamp), imu);
    if (mag) {
      sensor_msgs::MagneticField field;
      field.header.stamp = rosTime(stamp);
      field.magnetic_field.x = m_B.x(), field.magnetic_field.y = m_B.y();
      field.magnetic_field.z = m_B.z();
      bag.write("/compass", rosTime(stamp + 1000), field);
    }
  }
  bag.close();
}

/// The earth's field (north and down) in the body with the static tilt.
Eigen::Vector3d earthFieldInBody() {
  return tilt().conjugate() * Eigen::Vector3d(0.0, 2e-5, -4e-5);
}

/// The magnetometer's frame mag_link on base_link, a generic mount q_BM (on /tf_static).
const Eigen::Quaterniond kMagMount(Eigen::AngleAxisd(2.1, Eigen::Vector3d(-1, 3, 2).normalized()));

void writeMagMount(rosbag::Bag& bag) {
  tf2_msgs::TFMessage mount;
  mount.transforms = {mountTransform("base_link", "mag_link", kMagMount, kStart)};
  bag.write("/tf_static", rosTime(kStart), mount);
}

/// `n` rate messages (zero rates; with `tilted`, the static tilt's gravity) on /imu/data_raw in
/// the body's frame and as many field reads on /imu/mag in `frame` ("mag_link": through
/// kMagMount), read_k = field(k) in that frame.
template <class Field>
void writeFieldReads(const std::string& path, int n, bool tilted, const std::string& frame,
                     Field field) {
  rosbag::Bag bag(path, rosbag::bagmode::Write);
  if (frame == "mag_link") writeMagMount(bag);
  const Eigen::Vector3d f_B = tilt().conjugate() * Eigen::Vector3d(0.0, 0.0, kG);
  for (int k = 0; k < n; ++k) {
    const Stamp stamp = kStart + k * kPeriod;
    sensor_msgs::Imu imu;
    imu.header.stamp = rosTime(stamp);
    if (tilted) {
      imu.linear_acceleration.x = f_B.x(), imu.linear_acceleration.y = f_B.y();
      imu.linear_acceleration.z = f_B.z();
    }
    imu.orientation_covariance[0] = -1.0;
    bag.write("/imu/data_raw", rosTime(stamp), imu);
    const Eigen::Vector3d m = field(k);
    sensor_msgs::MagneticField read;
    read.header.stamp = rosTime(stamp);
    read.header.frame_id = frame;
    read.magnetic_field.x = m.x(), read.magnetic_field.y = m.y(), read.magnetic_field.z = m.z();
    bag.write("/imu/mag", rosTime(stamp + 1000), read);
  }
}

/// ZYX yaw of q.
double yaw(const Eigen::Quaterniond& q) {
  return std::atan2(2.0 * (q.w() * q.z() + q.x() * q.y()),
                    1.0 - 2.0 * (q.y() * q.y() + q.z() * q.z()));
}

// The own field the summary gives and the one mag_bias takes, in the body frame.
const Eigen::Vector3d kOwnB(12e-6, -31e-6, 7e-6);
const std::string kOwnBList = "[1.2e-05, -3.1e-05, 7.0e-06]";

}  // namespace

// No initial_orientation: the tilt starts from the first accelerometer sample; the last state's
// roll and pitch are the closed form's within 1e-3 rad, and the summary counts the alignment.
TEST(BagAiding, StaticTiltedImuGivesTheClosedFormTilt) {
  TempDir dir;
  writeStaticTilt(dir.file("in.bag"), 200, false);
  const RunResult r = run(kPropagate + " " + dir.file("in.bag") + " --set use_accel=true -o " +
                          dir.file("out.bag") + " --no-progress");
  ASSERT_EQ(r.status, 0) << r.output;
  const auto states = readOutputBag(dir.file("out.bag")).states;
  ASSERT_EQ(states.size(), 200u);
  const Eigen::Vector2d rp = rollPitch(toEigen(states.back().orientation));
  EXPECT_NEAR(rp.x(), kRoll, 1e-3);
  EXPECT_NEAR(rp.y(), kPitch, 1e-3);
  EXPECT_NE(r.output.find("accel: 200 read: accel_accepted "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("accel_aligned 1,"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("  mag:"), std::string::npos) << r.output;  // use_mag off
}

// --mag names the magnetometer topic: read with use_mag, counted as mag_*; the tilt holds.
TEST(BagAiding, MagTopicIsReadAndCounted) {
  TempDir dir;
  writeStaticTilt(dir.file("in.bag"), 200, true);
  const RunResult r =
      run(kPropagate + " " + dir.file("in.bag") + " --set use_accel=true --set use_mag=true" +
          " --mag /compass -o " + dir.file("out.bag") + " --no-progress");
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("/compass 200"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("mag: 200 read: mag_accepted "), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("mag_invalid 0,"), r.output.find("mag_invalid")) << r.output;
  // One field read 200 times fixes no sphere: no mag_bias is suggested.
  EXPECT_NE(r.output.find("mag_bias from the reads: none (200 reads fix no sphere"),
            std::string::npos)
      << r.output;
  const auto states = readOutputBag(dir.file("out.bag")).states;
  ASSERT_FALSE(states.empty());
  const Eigen::Vector2d rp = rollPitch(toEigen(states.back().orientation));
  EXPECT_NEAR(rp.x(), kRoll, 1e-3);
  EXPECT_NEAR(rp.y(), kPitch, 1e-3);
  // use_mag without the topic in the bag: refused as any missing input topic is.
  const RunResult missing = run(kPropagate + " " + dir.file("in.bag") +
                                " --set use_mag=true --mag /nothing -o " + dir.file("x.bag"));
  EXPECT_NE(missing.status, 0) << missing.output;
}

// The summary's mag_bias (printFieldFit): the centre of the sphere the field reads lie on
// (HardIronFit), here 600 reads of a 48 uT field turned evenly every way about a generic own
// field. It is fitted to the reads as read, so the line is the same whatever mag_bias is given,
// and it says the sphere is determined.
TEST(BagAiding, SummaryGivesTheSphereTheFieldReadsLieOn) {
  TempDir dir;
  writeFieldReads(dir.file("in.bag"), 600, false, "",
                  [](int k) -> Eigen::Vector3d { return kOwnB + 48e-6 * evenDirection(k, 600); });
  const std::string line = "mag_bias from the reads: [1.2e-05, -3.1e-05, 7e-06] T, stddev [";
  for (const std::string bias : {std::string(), " --set 'mag_bias=" + kOwnBList + "'"}) {
    const RunResult r = run(kPropagate + " " + dir.file("in.bag") + " --set use_mag=true" + bias +
                            " -o " + dir.file("out.bag") + " --no-progress");
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find(line), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("field 4.8e-05 T"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find(": determined (give it as mag_bias)"), std::string::npos) << r.output;
  }
}

// A magnetometer on its own mount (mag_link, generic q_BM): its own field is fixed in its frame,
// own_M = q_BM^-1 own_B. The summary fits the reads as the engine gets them, in the body, so it
// gives own_B, not own_M's numbers; and mag_bias is taken off in the body: given own_B, a
// static tilted body keeps the heading the earth's field gives (yaw 0, the field north), given
// own_M's numbers (the sensor frame's) it does not.
TEST(BagAiding, MountedMagnetometersOwnFieldIsGivenAndTakenInTheBodyFrame) {
  TempDir dir;
  const Eigen::Vector3d own_M = kMagMount.conjugate() * kOwnB;
  writeFieldReads(dir.file("sphere.bag"), 600, false, "mag_link",
                  [&](int k) -> Eigen::Vector3d { return own_M + 48e-6 * evenDirection(k, 600); });
  const RunResult fit = run(kPropagate + " " + dir.file("sphere.bag") + " --set use_mag=true -o " +
                            dir.file("sphere_out.bag") + " --no-progress");
  ASSERT_EQ(fit.status, 0) << fit.output;
  EXPECT_NE(fit.output.find("mag_bias from the reads: [1.2e-05, -3.1e-05, 7e-06] T, stddev ["),
            std::string::npos)
      << fit.output;

  writeFieldReads(dir.file("tilt.bag"), 300, true, "mag_link", [&](int) -> Eigen::Vector3d {
    return own_M + kMagMount.conjugate() * earthFieldInBody();
  });
  auto finalYaw = [&](const std::string& bias) {
    const RunResult r = run(kPropagate + " " + dir.file("tilt.bag") +
                            " --set use_accel=true --set use_mag=true --set 'mag_bias=" + bias +
                            "' -o " + dir.file("tilt_out.bag") + " --no-progress");
    EXPECT_EQ(r.status, 0) << r.output;
    const auto states = readOutputBag(dir.file("tilt_out.bag")).states;
    return states.empty() ? NAN : yaw(toEigen(states.back().orientation));
  };
  EXPECT_NEAR(finalYaw(kOwnBList), 0.0, 1e-3);
  char sensor_frame[96];
  std::snprintf(sensor_frame, sizeof sensor_frame, "[%.9g, %.9g, %.9g]", own_M.x(), own_M.y(),
                own_M.z());
  EXPECT_GT(std::abs(finalYaw(sensor_frame)), 0.05);
}

// evaluate_bag takes the same settings: with use_accel each method's engine gets the rate
// messages' accelerometer (here all zero: a scene bag's Imu carries none, so each sample is
// counted invalid, and the rates alone are scored as before), and the report gives each
// method's accel_* counters; use_mag without the --mag topic in the bag is refused.
TEST(BagAiding, EvaluateBagReportsTheAccelCounters) {
  TempDir dir;
  SceneBag scene;
  scene.motion = coning();
  scene.duration = 5.0;
  const Written w = writeSceneBag(dir.file("in.bag"), scene);
  const std::string common = kEvaluateCore + " " + dir.file("in.bag") +
                             " --truth /truth --offset 0 --mount 0 0 0 1 --calibration 2"
                             " --integrators cf4 --rate-samples instantaneous --no-progress"
                             " --csv " +
                             dir.file("eval");
  const RunResult r = run(common + " --set use_accel=true --set initial_orientation_stddev=0.0" +
                          " --set 'initial_orientation=[0, 0, 0, 1]'");
  ASSERT_EQ(r.status, 0) << r.output;
  const std::string line = "accel: " + std::to_string(w.rate_stamps.size()) +
                           " read; per method: cf4/instantaneous (accel_accepted 0,";
  EXPECT_NE(r.output.find(line), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("accel_invalid " + std::to_string(w.rate_stamps.size())),
            std::string::npos)
      << r.output;
  const RunResult missing = run(common + " --set use_mag=true --mag /compass");
  EXPECT_NE(missing.status, 0) << missing.output;
  EXPECT_NE(missing.output.find("/compass"), std::string::npos) << missing.output;
}
