// Promises of the bag tools stated in docs/bag_tools.md, each against a truth of its own (the
// scene's closed form, the documented rule), with the input checked to be the case it claims:
// the delay model subtracts each reading's own lag from the lag it estimates, the fixes' world
// is never aligned away, and split parts that share one record time are parts, not overlaps.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <geometry_msgs/PoseStamped.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/Imu.h>

#include "attitude_propagator/numerics/quaternion.h"
#include "scene_bags.h"

namespace ap = attitude_propagator;
using namespace bagtest;

namespace {

using Row = std::vector<std::pair<std::string, std::string>>;

/// evaluate_bag_core over `inputs` (paths joined by spaces, quoted), its CSV rows by method.
std::map<std::string, Row> evaluateRows(const TempDir& dir, const std::string& inputs,
                                        const std::string& arguments, RunResult& result) {
  result = run(kEvaluateCore + " " + inputs + " --csv " + dir.file("eval") + " --no-progress " +
               arguments);
  std::map<std::string, Row> rows;
  if (result.status != 0) return rows;
  for (const Row& row : readCsv(dir.file("eval.csv"))) rows[field(row, "method")] = row;
  return rows;
}

double number(const Row& row, const std::string& column) { return std::stod(field(row, column)); }

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

/// The mean of `rate` over [a, b] by composite Simpson's rule on 200 panels: the scene's
/// averaged sample computed here apart from the scene's own code.
Eigen::Vector3d meanRate(const std::function<Eigen::Vector3d(double)>& rate, double a, double b) {
  constexpr int kPanels = 200;
  const double step = (b - a) / kPanels;
  Eigen::Vector3d sum = rate(a) + rate(b);
  for (int i = 1; i < kPanels; ++i) sum += (i % 2 ? 4.0 : 2.0) * rate(a + i * step);
  return sum * step / 3.0 / (b - a);
}

// ---------------------------------------------------------------------------------------------
// The delay model: each reading's own lag
// ---------------------------------------------------------------------------------------------

// With --truth-clock same, the lag D found (minus the offset) holds the sensor's lag d and, for
// a reading that misreads interval averages as instants, half an interval: an averaged sample
// stands for the middle of the interval it closes. So on averaged rates of a tumbling body
// (|w| varies: the offset is observable) D = d + h/2; the instantaneous reading runs with all of
// it, the interval-average reading with D less its own lag h/2, that is d: the scene's latency
// (1.1 ms), or the group delay of its Butterworth filter at ODR/4 (0.71 samples). Both are
// compared at offset 0, and the interval-average reading, the model the scene was written by,
// meets the truth to within what a delay error of 0.1 ms can explain.
TEST(DelayModel, EachReadingRunsWithTheLagLessItsOwn) {
  struct Case {
    double delay, lowpass;
  };
  for (const Case c : {Case{1.1e-3, 0.0}, Case{0.0, 0.25}}) {
    TempDir dir;
    SceneBag scene;
    scene.motion = tumbling();
    scene.duration = 10.0;
    scene.averaged = true;
    scene.rate_delay = c.delay;
    scene.lowpass = c.lowpass;
    const Written w = writeSceneBag(dir.file("in.bag"), scene);
    const double h = 1.0 / scene.rate_hz;
    const double d = c.lowpass > 0.0 ? butterworthDelay(c.lowpass) / scene.rate_hz : c.delay;
    SCOPED_TRACE("sensor lag " + std::to_string(d * 1e3) + " ms");

    // The case claimed: samples h apart, each without the filter the mean rate over the
    // interval of length h ending d before its stamp; |w| not constant.
    ASSERT_GT(w.rate_stamps.size(), 100u);
    EXPECT_EQ(w.rate_stamps[1] - w.rate_stamps[0], stampAt(h) - stampAt(0.0));
    if (c.lowpass == 0.0) {
      rosbag::Bag bag(dir.file("in.bag"), rosbag::bagmode::Read);
      int checked = 0;
      for (const rosbag::MessageInstance& m :
           rosbag::View(bag, rosbag::TopicQuery("/imu/data_raw"))) {
        const auto imu = m.instantiate<sensor_msgs::Imu>();
        ASSERT_TRUE(imu);
        const double t = secondsOf(static_cast<Stamp>(imu->header.stamp.toNSec()));
        const Eigen::Vector3d read(imu->angular_velocity.x, imu->angular_velocity.y,
                                   imu->angular_velocity.z);
        EXPECT_LT((read - meanRate(scene.motion.rate, t - d - h, t - d)).norm(), 1e-12) << t;
        if (++checked == 50) break;
      }
    }
    EXPECT_GT(std::abs(scene.motion.rate(0.0).norm() - scene.motion.rate(0.7).norm()), 1e-2);

    RunResult r;
    const auto rows = evaluateRows(dir, dir.file("in.bag"),
                                   "--truth /truth --truth-clock same --integrators cf4", r);
    ASSERT_EQ(r.status, 0) << r.output;
    ASSERT_EQ(rows.size(), 2u) << r.output;
    const Row& instantaneous = rows.at("cf4/instantaneous");
    const Row& averaged = rows.at("cf4/interval_average");
    EXPECT_NEAR(number(instantaneous, "rate_delay_s"), d + 0.5 * h, 1e-4) << r.output;
    EXPECT_NEAR(number(averaged, "rate_delay_s"), d, 1e-4) << r.output;
    EXPECT_EQ(number(instantaneous, "offset_s"), 0.0);
    EXPECT_EQ(number(averaged, "offset_s"), 0.0);
    // A rate_delay off by 0.1 ms puts the state off by about 1e-4 s times |w| (about
    // 1.4 rad/s here); off by the half interval, by about 3e-3 rad.
    EXPECT_LT(number(averaged, "rms_error_rad"), 1.5e-4) << r.output;
    EXPECT_LT(number(averaged, "rms_error_rad"), number(instantaneous, "rms_error_rad"))
        << r.output;
  }
}

// ---------------------------------------------------------------------------------------------
// Fixes: their world is the states' world
// ---------------------------------------------------------------------------------------------

const Eigen::Quaterniond kTurnedWorld(
    Eigen::AngleAxisd(0.05, Eigen::Vector3d(1.0, 2.0, -1.0).normalized()));

geometry_msgs::PoseStamped pose(Stamp stamp, const Eigen::Quaterniond& q) {
  geometry_msgs::PoseStamped m;
  m.header.stamp = rosTime(stamp);
  m.header.frame_id = "world";
  m.pose.orientation.x = q.x(), m.pose.orientation.y = q.y();
  m.pose.orientation.z = q.z(), m.pose.orientation.w = q.w();
  return m;
}

/// Point rates of the coning body at 200 Hz for 10 s on /imu/data_raw, exact; on /fix its true
/// attitude q_WS every 0.2 s, recorded 1 us after the rate of the same stamp (on time); on
/// /truth, every fourth rate stamp, q_VT = A q_WS in a world V turned from the fixes' W by
/// A = kTurnedWorld.
void writeTurnedWorldBag(const std::string& path, const Motion& body) {
  rosbag::Bag bag(path, rosbag::bagmode::Write);
  for (int k = 0; k <= 2000; ++k) {
    const Stamp stamp = stampAt(k / 200.0);
    const double t = secondsOf(stamp);
    sensor_msgs::Imu imu;
    imu.header.stamp = rosTime(stamp);
    const Eigen::Vector3d w = body.rate(t);
    imu.angular_velocity.x = w.x(), imu.angular_velocity.y = w.y(), imu.angular_velocity.z = w.z();
    imu.orientation_covariance[0] = -1.0;
    bag.write("/imu/data_raw", rosTime(stamp), imu);
    if (k % 4 == 0)
      bag.write("/truth", rosTime(stamp), pose(stamp, kTurnedWorld * body.attitude(t)));
    if (k % 40 == 0) bag.write("/fix", rosTime(stamp + 1000), pose(stamp, body.attitude(t)));
  }
  bag.close();
}

// With --fixes the states' world is the fixes' (they reset the state to it here), and the truth
// must be in that world: it is not aligned to the truth's. A truth whose world is turned by
// 0.05 rad from the fixes' is therefore 0.05 rad from every fused state, from the first scored
// sample to the last: q_VT^-1 q_WS = q_WS^-1 A^-1 q_WS, a rotation by the angle of A. Aligned
// from the first pair, the error would vanish and the fused output's world error go unseen.
TEST(FixesWorld, TurnedTruthWorldShowsAsItsAngle) {
  TempDir dir;
  const Motion body = coning();
  writeTurnedWorldBag(dir.file("in.bag"), body);

  // The case claimed: every fix recorded 1 us after its stamp; the truth at a fix's stamp
  // 0.05 rad from it.
  {
    rosbag::Bag bag(dir.file("in.bag"), rosbag::bagmode::Read);
    std::map<Stamp, Eigen::Quaterniond> truth;
    std::vector<std::pair<Stamp, Eigen::Quaterniond>> fixes;
    for (const rosbag::MessageInstance& m : rosbag::View(bag)) {
      const auto p = m.instantiate<geometry_msgs::PoseStamped>();
      if (!p) continue;
      const Stamp stamp = static_cast<Stamp>(p->header.stamp.toNSec());
      if (m.getTopic() == "/truth") truth[stamp] = toEigen(p->pose.orientation);
      if (m.getTopic() == "/fix") {
        EXPECT_EQ(static_cast<Stamp>(m.getTime().toNSec()) - stamp, 1000);
        fixes.emplace_back(stamp, toEigen(p->pose.orientation));
      }
    }
    ASSERT_EQ(fixes.size(), 51u);
    for (const auto& [stamp, q] : fixes) {
      ASSERT_EQ(truth.count(stamp), 1u);
      EXPECT_NEAR(ap::rotationAngle(truth.at(stamp), q), 0.05, 1e-12);
    }
  }

  RunResult r;
  const auto rows = evaluateRows(dir, dir.file("in.bag"),
                                 "--truth /truth --fixes /fix --set fix_mode=reset --offset 0 "
                                 "--mount 0 0 0 1 --integrators cf4 --rate-samples instantaneous",
                                 r);
  ASSERT_EQ(r.status, 0) << r.output;
  ASSERT_EQ(rows.size(), 1u);
  const Row& fused = rows.at("cf4/instantaneous");
  EXPECT_GE(number(fused, "compared"), 450.0) << r.output;
  // cf4 on the exact coning rates is within 1e-7 rad of the fixes between them.
  EXPECT_NEAR(number(fused, "rms_error_rad"), 0.05, 1e-6) << r.output;
  EXPECT_NEAR(number(fused, "max_error_rad"), 0.05, 1e-6) << r.output;

  // The same truth in the fixes' own world: the fused output's error is cf4's alone.
  TempDir same;
  {
    rosbag::Bag in(dir.file("in.bag"), rosbag::bagmode::Read);
    rosbag::Bag out(same.file("in.bag"), rosbag::bagmode::Write);
    for (const rosbag::MessageInstance& m : rosbag::View(in)) {
      auto p = m.instantiate<geometry_msgs::PoseStamped>();
      if (p && m.getTopic() == "/truth") {
        const Stamp stamp = static_cast<Stamp>(p->header.stamp.toNSec());
        out.write("/truth", m.getTime(), pose(stamp, body.attitude(secondsOf(stamp))));
      } else {
        out.write(m.getTopic(), m.getTime(), m);
      }
    }
  }
  const auto own = evaluateRows(same, same.file("in.bag"),
                                "--truth /truth --fixes /fix --set fix_mode=reset --offset 0 "
                                "--mount 0 0 0 1 --integrators cf4 --rate-samples instantaneous",
                                r);
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_LT(number(own.at("cf4/instantaneous"), "max_error_rad"), 1e-6) << r.output;
}

// ---------------------------------------------------------------------------------------------
// Split parts that share one record time
// ---------------------------------------------------------------------------------------------

/// Copies `in` into two parts cut at record time `cut`: every message before it in the first,
/// every one after it in the second, and of the messages recorded at `cut` the first (in
/// rosbag's order) in the first part and the others in the second: the two parts share that
/// record time, as a split does when two messages were recorded in one tick of a clock.
std::vector<std::string> splitSharing(const std::string& in, ros::Time cut, const TempDir& dir) {
  const std::vector<std::string> paths{dir.file("part_0.bag"), dir.file("part_1.bag")};
  rosbag::Bag first(paths[0], rosbag::bagmode::Write);
  rosbag::Bag second(paths[1], rosbag::bagmode::Write);
  rosbag::Bag bag(in, rosbag::bagmode::Read);
  bool at_cut = false;
  for (const rosbag::MessageInstance& m : rosbag::View(bag)) {
    const bool to_first = m.getTime() < cut || (m.getTime() == cut && !at_cut);
    if (m.getTime() == cut) at_cut = true;
    (to_first ? first : second).write(m.getTopic(), m.getTime(), m, m.getConnectionHeader());
  }
  return paths;
}

/// The record times of a bag's first and last messages.
std::pair<ros::Time, ros::Time> recordSpan(const std::string& path) {
  rosbag::Bag bag(path, rosbag::bagmode::Read);
  rosbag::View view(bag);
  return {view.getBeginTime(), view.getEndTime()};
}

/// Point rates of the coning body at 200 Hz for 6 s on /imu/data_raw in base_link, recorded on
/// a 100 Hz clock (the record time the stamp rounded down to 10 ms, as under a simulated
/// clock): two rate messages to each record time.
void writeTickedRates(const std::string& path) {
  rosbag::Bag bag(path, rosbag::bagmode::Write);
  const Motion body = coning();
  for (int k = 0; k <= 1200; ++k) {
    const Stamp stamp = stampAt(k / 200.0);
    sensor_msgs::Imu imu;
    imu.header.stamp = rosTime(stamp);
    imu.header.frame_id = "base_link";
    const Eigen::Vector3d w = body.rate(secondsOf(stamp));
    imu.angular_velocity.x = w.x(), imu.angular_velocity.y = w.y(), imu.angular_velocity.z = w.z();
    imu.orientation_covariance[0] = -1.0;
    bag.write("/imu/data_raw", rosTime(stampAt((k / 2) / 100.0)), imu);
  }
  bag.close();
}

// Parts of one recording touch at one record time at most; when the message before the cut and
// the one after it were recorded at the same record time, the parts still are parts: no
// "share" warning, and over them, in either order, propagate_bag's output is the unsplit
// recording's, byte for byte (the merge by record time reads them as one stream).
TEST(SplitParts, SharingOneRecordTimeGiveTheWholeRecording) {
  TempDir dir;
  writeTickedRates(dir.file("whole.bag"));
  const ros::Time cut = rosTime(stampAt(3.0));
  const auto parts = splitSharing(dir.file("whole.bag"), cut, dir);
  // The case claimed: the first part ends and the second starts at the cut's record time,
  // with a rate message on each side of it.
  EXPECT_EQ(recordSpan(parts[0]).second, cut);
  EXPECT_EQ(recordSpan(parts[1]).first, cut);
  EXPECT_LT(recordSpan(parts[0]).first, cut);
  EXPECT_GT(recordSpan(parts[1]).second, cut);

  const std::string common = " --set integrator=cf4 --no-progress";
  const RunResult whole =
      run(kPropagate + " " + dir.file("whole.bag") + " -o " + dir.file("a.bag") + common);
  ASSERT_EQ(whole.status, 0) << whole.output;
  const auto expected = readRecorded(dir.file("a.bag"));
  ASSERT_EQ(readOutputBag(dir.file("a.bag")).states.size(), 1201u) << whole.output;
  for (const auto& order : {std::vector<std::string>{parts[0], parts[1]},
                            std::vector<std::string>{parts[1], parts[0]}}) {
    const std::string out = dir.file("parts.bag");
    const RunResult pieces =
        run(kPropagate + " " + quote(order[0]) + " " + quote(order[1]) + " -o " + out + common);
    ASSERT_EQ(pieces.status, 0) << pieces.output;
    EXPECT_FALSE(contains(pieces.output, "share")) << pieces.output;
    EXPECT_TRUE(expected == readRecorded(out)) << order[0] << " first\n" << pieces.output;
    std::remove(out.c_str());
  }
}

// evaluate_bag over the parts of a scene whose rate and truth messages share each record time,
// cut between the two recorded at 5 s: no "share" warning, and the errors over the parts are
// those over the whole (the costs are timings).
TEST(SplitParts, EvaluationSharingOneRecordTimeIsTheWholeRecordings) {
  TempDir dir;
  SceneBag scene;
  scene.motion = coning();
  scene.duration = 10.0;
  writeSceneBag(dir.file("whole.bag"), scene);
  const ros::Time cut = rosTime(stampAt(5.0));
  const auto parts = splitSharing(dir.file("whole.bag"), cut, dir);
  EXPECT_EQ(recordSpan(parts[0]).second, cut);
  EXPECT_EQ(recordSpan(parts[1]).first, cut);

  const std::string common = "--truth /truth --calibration 4 --integrators cf4";
  RunResult whole;
  const auto a = evaluateRows(dir, dir.file("whole.bag"), common, whole);
  ASSERT_EQ(whole.status, 0) << whole.output;
  RunResult pieces;
  const auto b = evaluateRows(dir, quote(parts[1]) + " " + quote(parts[0]), common, pieces);
  ASSERT_EQ(pieces.status, 0) << pieces.output;
  EXPECT_FALSE(contains(pieces.output, "share")) << pieces.output;
  ASSERT_EQ(a.size(), b.size());
  for (const auto& [method, row] : a) {
    for (const auto& [column, value] : row) {
      if (contains(column, "ns") || contains(column, "cost")) continue;
      EXPECT_EQ(field(b.at(method), column), value) << method << " " << column;
    }
  }
}

}  // namespace
