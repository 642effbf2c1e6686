// The bag tools with absolute attitude fixes (--fixes): a coning gyro with a constant bias and
// fixes of the true attitude, against the closed form. propagate_bag estimates the bias and
// stays on the truth where the run without fixes drifts as the bias integrated says; a late fix
// gives the state of the same fix on time (the replay's promise); the summary accounts for
// every fix; evaluate_bag scores the fused outputs against a separate truth.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <regex>
#include <string>
#include <vector>

#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/QuaternionStamped.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/Imu.h>
#include <boost/make_shared.hpp>

#include "attitude_propagator/AttitudeState.h"
#include "attitude_propagator/numerics/coning_motion.h"
#include "attitude_propagator/numerics/quaternion.h"
#include "scene_bags.h"

namespace ap = attitude_propagator;
using namespace bagtest;

namespace {

const ap::ConingMotion kCone;
const Eigen::Vector3d kBias(0.004, -0.002, 0.003);  // rad/s, body frame: 1100 deg/h
constexpr double kRateHz = 200.0;
constexpr double kFixHz = 5.0;
constexpr Stamp kRatePeriod = 5000000;  // ns
constexpr int kRatesPerFix = 40;

geometry_msgs::Quaternion toMsg(const Eigen::Quaterniond& q) {
  geometry_msgs::Quaternion m;
  m.x = q.x(), m.y = q.y(), m.z = q.z(), m.w = q.w();
  return m;
}
/// A fix of the cone's true attitude, stamped at `stamp` and recorded `late` s after it (and
/// 1 us more, after the rate sample of the same record time); frame_id the fixed frame.
geometry_msgs::PoseStamped poseFix(Stamp stamp, const std::string& frame = "world") {
  geometry_msgs::PoseStamped fix;
  fix.header.stamp = rosTime(stamp);
  fix.header.frame_id = frame;
  fix.pose.orientation = toMsg(kCone.attitude(secondsOf(stamp)));
  return fix;
}
ros::Time recordOf(Stamp stamp, double late) {
  return rosTime(stamp + static_cast<Stamp>(std::llround(late * 1e9)) + 1000);
}

/// Rates of the cone plus kBias at 200 Hz for `duration` s on /imu/data_raw (the body's frame);
/// with `fixes`, a fix every 0.2 s up to 1 s before the end on /fix, `late` s after its stamp
/// (the first one on time with `first_on_time`); with `truth`, the true attitude at every fourth
/// rate stamp on /truth.
void writeBiasedCone(const std::string& path, double duration, bool fixes, double late,
                     bool truth = false, bool first_on_time = false) {
  rosbag::Bag bag(path, rosbag::bagmode::Write);
  const int n = static_cast<int>(std::lround(duration * kRateHz));
  const int last_fix = n - static_cast<int>(kRateHz);
  for (int k = 0; k <= n; ++k) {
    const Stamp stamp = kStart + k * kRatePeriod;
    const double t = secondsOf(stamp);
    sensor_msgs::Imu imu;
    imu.header.stamp = rosTime(stamp);
    const Eigen::Vector3d w = kCone.bodyRate(t) + kBias;
    imu.angular_velocity.x = w.x(), imu.angular_velocity.y = w.y(), imu.angular_velocity.z = w.z();
    imu.orientation_covariance[0] = -1.0;
    bag.write("/imu/data_raw", rosTime(stamp), imu);
    if (truth && k % 4 == 0) {
      bag.write("/truth", rosTime(stamp), poseFix(stamp));
    }
    if (fixes && k % kRatesPerFix == 0 && k <= last_fix) {
      bag.write("/fix", recordOf(stamp, first_on_time && k == 0 ? 0.0 : late), poseFix(stamp));
    }
  }
  bag.close();
}

std::vector<ap::AttitudeState> readStates(const std::string& path) {
  rosbag::Bag bag(path, rosbag::bagmode::Read);
  std::vector<ap::AttitudeState> states;
  for (const rosbag::MessageInstance& m : rosbag::View(bag)) {
    if (auto s = m.instantiate<ap::AttitudeState>()) states.push_back(*s);
  }
  return states;
}

using bagtest::toEigen;  // the quaternion, beside this overload
Eigen::Vector3d toEigen(const geometry_msgs::Vector3& v) { return {v.x, v.y, v.z}; }

double errorOf(const ap::AttitudeState& s) {
  const double t = secondsOf(static_cast<Stamp>(s.header.stamp.toNSec()));
  return ap::rotationAngle(toEigen(s.orientation), kCone.attitude(t));
}

std::string setInitialAttitude() {
  const Eigen::Quaterniond q = kCone.attitude(0.0);
  char text[200];
  std::snprintf(text, sizeof text, "initial_orientation=[%.17g, %.17g, %.17g, %.17g]", q.x(), q.y(),
                q.z(), q.w());
  return " --set " + quote(text);
}

// The filter's settings: the rates are exact, so their noise is set small; the bias is
// constant, so its random walk too; the fixes are exact and claim fix_stddev.
constexpr double kFixStddev = 1e-3;
const std::string kBiasSettings =
    " --set estimate_gyro_bias=true --set gyro_bias_stddev=0.01 --set gyro_bias_random_walk=1e-8"
    " --set angular_velocity_stddev=1e-5 --set fix_stddev=0.001 --set integrator=cf4";

// ---------------------------------------------------------------------------------------------
// propagate_bag --fixes
// ---------------------------------------------------------------------------------------------

// 20 s of a coning gyro with a constant bias, fixes of the true attitude at 5 Hz, 100 ms late.
// Without fixes the attitude error at the end is the bias integrated along the true attitude,
// |sum h C_WB(t) b| (to first order in the error, within 3 %). With the fixes the last state's
// gyro_bias is within three standard deviations of the best estimate N fixes can give: a line
// fitted to N exact-to-s attitudes spaced d apart has a slope error of
// s / (d sqrt(N (N^2 - 1) / 12)); the rate noise (1e-5 rad/s) and the bias' random walk add
// less. The attitude error at the end is a hundredth of the drift or less. The first fix, late,
// is too old: the history of rates starts with the first fix (docs/design.md §6.9).
TEST(BagFixes, LateFixesEstimateTheGyroBias) {
  TempDir dir;
  const double duration = 20.0;
  writeBiasedCone(dir.file("in.bag"), duration, true, 0.1);
  const std::string common =
      kPropagate + " " + dir.file("in.bag") + setInitialAttitude() + kBiasSettings;
  const RunResult without = run(common + " -o " + dir.file("plain.bag"));
  ASSERT_EQ(without.status, 0) << without.output;
  const RunResult with = run(common + " --fixes /fix -o " + dir.file("fused.bag"));
  ASSERT_EQ(with.status, 0) << with.output;

  const auto plain = readStates(dir.file("plain.bag"));
  const auto fused = readStates(dir.file("fused.bag"));
  ASSERT_EQ(plain.size(), fused.size());
  ASSERT_FALSE(fused.empty());

  // The drift: the bias turned into the world frame along the true attitude, summed over the
  // sample intervals.
  Eigen::Vector3d drift_W = Eigen::Vector3d::Zero();
  const int n = static_cast<int>(std::lround(duration * kRateHz));
  for (int k = 0; k < n; ++k) {
    const double t = (k + 0.5) / kRateHz;
    drift_W += (kCone.attitude(t) * kBias) / kRateHz;
  }
  const double plain_end = errorOf(plain.back());
  EXPECT_NEAR(plain_end, drift_W.norm(), 0.03 * drift_W.norm());

  const int fixes = static_cast<int>(std::lround((duration - 1.0) * kFixHz)) + 1;
  const double d = 1.0 / kFixHz;
  const double sigma_b = kFixStddev / (d * std::sqrt(fixes * (double(fixes) * fixes - 1.0) / 12.0));
  const Eigen::Vector3d bias = toEigen(fused.back().gyro_bias);
  std::printf(
      "[ fixes    ] drift %.4g rad (predicted %.4g), with fixes %.3g rad; bias error "
      "%.3g rad/s (bound %.3g, reported stddev %.3g)\n",
      plain_end, drift_W.norm(), errorOf(fused.back()), (bias - kBias).norm(), 3.0 * sigma_b,
      toEigen(fused.back().gyro_bias_stddev).norm());
  EXPECT_LE((bias - kBias).norm(), 3.0 * sigma_b);
  EXPECT_LE(errorOf(fused.back()), 0.01 * plain_end);
  EXPECT_NE(with.output.find("fixes: 96 = 95 accepted (0 as resets) + 0 rejected_gate + 1 too_old"),
            std::string::npos)
      << with.output;
  // The summary gives the estimate with its standard deviation, that of the last state.
  char stddev[160];
  const Eigen::Vector3d s = toEigen(fused.back().gyro_bias_stddev);
  std::snprintf(stddev, sizeof(stddev), "standard deviation [%g, %g, %g] rad/s", s.x(), s.y(),
                s.z());
  EXPECT_NE(with.output.find(stddev), std::string::npos) << stddev << "\n" << with.output;
}

// The same fixes on time and 100 ms late (recorded after the 20 rates that follow their stamps):
// the replay gives the same final state, orientation and bias estimate, to round-off. The first
// fix is on time in both: it starts the history of rates a late fix is replayed over.
TEST(BagFixes, LateFixGivesTheStateOfTheFixOnTime) {
  TempDir dir;
  writeBiasedCone(dir.file("on_time.bag"), 6.0, true, 0.0);
  writeBiasedCone(dir.file("late.bag"), 6.0, true, 0.1, false, true);
  const std::string options = setInitialAttitude() + kBiasSettings + " --fixes /fix";
  for (const char* name : {"on_time", "late"}) {
    const RunResult r = run(kPropagate + " " + dir.file(std::string(name) + ".bag") + options +
                            " -o " + dir.file(std::string(name) + ".out.bag"));
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_NE(r.output.find("fixes: 26 = 26 accepted"), std::string::npos) << r.output;
  }
  const auto on_time = readStates(dir.file("on_time.out.bag"));
  const auto late = readStates(dir.file("late.out.bag"));
  ASSERT_EQ(on_time.size(), late.size());
  const ap::AttitudeState &a = on_time.back(), &b = late.back();
  ASSERT_EQ(a.header.stamp, b.header.stamp);
  EXPECT_LE(ap::rotationAngle(toEigen(a.orientation), toEigen(b.orientation)), 1e-12);
  EXPECT_LE((toEigen(a.gyro_bias) - toEigen(b.gyro_bias)).norm(), 1e-12);
  // The fixes did act: the bias estimate is not its prior (zero).
  EXPECT_GT(toEigen(a.gyro_bias).norm(), 0.5 * kBias.norm());
}

// The summary accounts for every fix read: applied, too old, a bad quaternion, waiting at the
// end, and refused before the engine by name (a frame tf does not know, a second type on the
// topic), the terms adding up to the count. --dry-run names the fix topic's role; a missing fix
// topic is refused as a missing rate topic is.
TEST(BagFixes, SummaryAccountsForEveryFix) {
  TempDir dir;
  {
    rosbag::Bag bag(dir.file("in.bag"), rosbag::bagmode::Write);
    for (int k = 0; k <= 600; ++k) {
      const Stamp stamp = kStart + k * kRatePeriod;
      sensor_msgs::Imu imu;
      imu.header.stamp = rosTime(stamp);
      const Eigen::Vector3d w = kCone.bodyRate(secondsOf(stamp));
      imu.angular_velocity.x = w.x(), imu.angular_velocity.y = w.y(),
      imu.angular_velocity.z = w.z();
      bag.write("/imu/data_raw", rosTime(stamp), imu);
    }
    const auto at = [](double t) { return kStart + static_cast<Stamp>(std::llround(t * 1e9)); };
    bag.write("/fix", recordOf(at(0.5), 0.0), poseFix(at(0.5)));             // accepted
    bag.write("/fix", recordOf(at(1.0), 0.05), poseFix(at(1.0)));            // accepted
    bag.write("/fix", recordOf(at(1.5), 0.0), poseFix(at(1.5), "nowhere"));  // no_tf
    geometry_msgs::QuaternionStamped other;                                  // type
    other.header = poseFix(at(2.0)).header;
    other.quaternion = poseFix(at(2.0)).pose.orientation;
    // Another publisher's connection: rosbag keys a plain write's connection by topic alone.
    auto header = boost::make_shared<ros::M_string>();
    (*header)["topic"] = "/fix";
    (*header)["type"] = ros::message_traits::datatype<geometry_msgs::QuaternionStamped>();
    (*header)["md5sum"] = ros::message_traits::md5sum<geometry_msgs::QuaternionStamped>();
    (*header)["message_definition"] =
        ros::message_traits::definition<geometry_msgs::QuaternionStamped>();
    (*header)["callerid"] = "/compass";
    bag.write("/fix", recordOf(at(2.0), 0.0), other, header);
    bag.write("/fix", recordOf(at(0.2), 2.2), poseFix(at(0.2)));  // too_old
    geometry_msgs::PoseStamped doubled = poseFix(at(2.6));        // bad_quaternion
    doubled.pose.orientation.w *= 2.0;
    bag.write("/fix", recordOf(at(2.6), 0.0), doubled);
    bag.write("/fix", recordOf(at(2.9), 0.0), poseFix(at(9.0)));  // pending
    // The body's own frame: the node's output read back as a fix (body_frame)
    bag.write("/fix", recordOf(at(2.8), 0.0), poseFix(at(2.8), "base_link"));
    bag.close();
  }
  const std::string in = dir.file("in.bag");
  const RunResult r = run(kPropagate + " " + in + " --fixes /fix -o " + dir.file("out.bag"));
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("fixes: 8 = 2 accepted (0 as resets) + 0 rejected_gate + 1 too_old + "
                          "1 bad_quaternion + 0 bad_covariance + 0 queue_full + 0 future + 0 "
                          "over_budget + 1 pending at the end + 3 refused (type 1, no_tf 1, "
                          "no_time 0, no_orientation 0, body_frame 1)\n"),
            std::string::npos)
      << r.output;
  // The terms add up (the line says so when they do not).
  std::smatch line;
  const std::string output = r.output;
  ASSERT_TRUE(std::regex_search(output, line, std::regex("fixes: [^\n]*")));
  EXPECT_EQ(line.str().find("not accounted"), std::string::npos) << line.str();
  EXPECT_NE(r.output.find("/fix 8"), std::string::npos) << r.output;  // the messages read

  const RunResult dry = run(kPropagate + " " + in + " --fixes /fix --dry-run");
  ASSERT_EQ(dry.status, 0) << dry.output;
  EXPECT_TRUE(std::regex_search(dry.output, std::regex("/fix +geometry_msgs/\\w+ +8  fixes")))
      << dry.output;
  const RunResult without = run(kPropagate + " " + in + " -o " + dir.file("plain.bag"));
  ASSERT_EQ(without.status, 0) << without.output;
  EXPECT_EQ(without.output.find("fixes:"), std::string::npos) << without.output;

  const RunResult missing =
      run(kPropagate + " " + in + " --fixes /nothing -o " + dir.file("x.bag"));
  EXPECT_EQ(missing.status, 1) << missing.output;
  EXPECT_NE(missing.output.find("no fix topic '/nothing'"), std::string::npos) << missing.output;
  const RunResult rates =
      run(kPropagate + " " + in + " --fixes /imu/data_raw -o " + dir.file("x.bag"));
  EXPECT_EQ(rates.status, 2) << rates.output;
  std::ifstream x(dir.file("x.bag"));
  EXPECT_FALSE(x.good());
}

// ---------------------------------------------------------------------------------------------
// evaluate_bag --fixes
// ---------------------------------------------------------------------------------------------

// Each method run with the fixes and scored against the separate truth (/truth): rows for every
// method, each far below the same method's error without fixes (the bias drift). The truth
// being the fixes themselves is a usage error naming both.
TEST(BagFixes, EvaluateBagScoresTheFusedOutput) {
  TempDir dir;
  writeBiasedCone(dir.file("in.bag"), 20.0, true, 0.1, true);
  const std::string common = kEvaluateCore + " " + dir.file("in.bag") + setInitialAttitude() +
                             kBiasSettings +
                             " --offset 0 --mount 0 0 0 1 --integrators cf4,rk4 "
                             "--rate-samples instantaneous --no-progress --truth /truth";
  const RunResult plain = run(common + " --csv " + dir.file("plain"));
  ASSERT_EQ(plain.status, 0) << plain.output;
  const RunResult fused = run(common + " --fixes /fix --csv " + dir.file("fused"));
  ASSERT_EQ(fused.status, 0) << fused.output;
  EXPECT_NE(fused.output.find("fixes /fix (geometry_msgs/PoseStamped): 96"), std::string::npos)
      << fused.output;
  EXPECT_NE(fused.output.find("cf4/instantaneous 95/0/1/0/0"), std::string::npos) << fused.output;
  const auto plain_rows = readCsv(dir.file("plain.csv"));
  const auto fused_rows = readCsv(dir.file("fused.csv"));
  ASSERT_EQ(fused_rows.size(), 2u);
  ASSERT_EQ(plain_rows.size(), 2u);
  for (std::size_t i = 0; i < fused_rows.size(); ++i) {
    ASSERT_EQ(field(fused_rows[i], "method"), field(plain_rows[i], "method"));
    const double with = std::stod(field(fused_rows[i], "rms_error_rad"));
    const double without = std::stod(field(plain_rows[i], "rms_error_rad"));
    std::printf("[ fixes    ] %s RMS error %.3g rad without fixes, %.3g with\n",
                field(fused_rows[i], "method").c_str(), without, with);
    EXPECT_LT(with, 0.01 * without) << fused.output;
  }

  const RunResult same = run(kEvaluateCore + " " + dir.file("in.bag") +
                             " --truth /fix --fixes fix --csv " + dir.file("same"));
  EXPECT_EQ(same.status, 2) << same.output;
  EXPECT_NE(same.output.find("--fixes fix and the truth /fix"), std::string::npos) << same.output;
  std::ifstream csv(dir.file("same.csv"));
  EXPECT_FALSE(csv.good());
}

// The scores start at the first applied fix: the engines start 0.1 rad off the truth, the
// first fix (stamped 0, recorded 0.1 s late) is too old and the second (stamped 0.2 s) is
// applied when recorded, at 0.3 s; the first state after it is the rate sample at 0.305 s, so
// the truth samples at 0, 0.02, ..., 0.30 s (16) are not scored, and the start-up error
// (0.1 rad) is not among the scores: the largest is a tenth of it or less.
TEST(BagFixes, EvaluateBagScoresFromTheFirstAppliedFix) {
  TempDir dir;
  writeBiasedCone(dir.file("in.bag"), 20.0, true, 0.1, true);
  const Eigen::Quaterniond off =
      kCone.attitude(0.0) * Eigen::Quaterniond(Eigen::AngleAxisd(0.1, Eigen::Vector3d::UnitX()));
  char initial[200];
  std::snprintf(initial, sizeof initial,
                " --set 'initial_orientation=[%.17g, %.17g, %.17g, %.17g]'", off.x(), off.y(),
                off.z(), off.w());
  const RunResult r = run(kEvaluateCore + " " + dir.file("in.bag") + initial + kBiasSettings +
                          " --offset 0 --mount 0 0 0 1 --integrators cf4 --rate-samples "
                          "instantaneous --no-progress --truth /truth --fixes /fix --csv " +
                          dir.file("fused"));
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("scored from the first state after the first applied fix (16 truth "
                          "samples before it not scored"),
            std::string::npos)
      << r.output;
  const auto rows = readCsv(dir.file("fused.csv"));
  ASSERT_EQ(rows.size(), 1u);
  EXPECT_EQ(std::stod(field(rows[0], "compared")) + 16.0, 20.0 * kRateHz / 4.0 + 1.0) << r.output;
  EXPECT_LE(std::stod(field(rows[0], "max_error_rad")), 0.01) << r.output;
}

}  // namespace
