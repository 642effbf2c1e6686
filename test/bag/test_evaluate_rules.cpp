// Rules evaluate_bag's scores and alignment obey whatever the method and the motion: a relative
// rotation error over a window is at most the sum of the errors at its two ends (the triangle
// inequality of the rotation angle), and Wahba's fit is a proper rotation (docs/bag_tools.md:
// the mount q_ST, a rotation, never a mirror).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "../../src/tools/alignment.h"
#include "attitude_propagator/numerics/integrator.h"
#include "scene_bags.h"

namespace ap = attitude_propagator;

namespace {
// Every kinematic method of the table with each rate_samples reading: what evaluate_bag_core runs.
std::size_t evaluatedMethods() { return 2 * ap::integratorsFor(ap::Model::Kinematic).size(); }
}  // namespace
using namespace bagtest;

namespace {

using Row = std::vector<std::pair<std::string, std::string>>;

std::map<std::string, Row> evaluateRows(const TempDir& dir, const std::string& arguments,
                                        RunResult& result) {
  result = run(kEvaluateCore + " " + dir.file("in.bag") + " --csv " + dir.file("eval") +
               " --no-progress " + arguments);
  std::map<std::string, Row> rows;
  if (result.status != 0) return rows;
  for (const Row& row : readCsv(dir.file("eval.csv"))) rows[field(row, "method")] = row;
  return rows;
}

double number(const Row& row, const char* column) { return std::stod(field(row, column)); }

}  // namespace

// A tumbling triaxial body (its rotations about changing axes do not commute, so a relative
// rotation taken on the wrong side differs from the right one by up to the whole rotation):
// q_a, q_c the estimates and p_a, p_c the truths at a window's ends, the relative error
// angle((p_a^-1 p_c), (q_a^-1 q_c)) <= angle(p_a, q_a) + angle(p_c, q_c) <= 2 max_error, for
// every method, the exact ones (1e-9) and the first-order ones alike; the windows are filled.
TEST(EvaluateRules, RelativeErrorAtMostTheErrorsAtTheWindowsEnds) {
  TempDir dir;
  SceneBag scene;
  scene.motion = tumbling();
  scene.duration = 12.0;
  writeSceneBag(dir.file("in.bag"), scene);
  RunResult r;
  const auto rows = evaluateRows(dir, "--truth /truth --offset 0 --mount 0 0 0 1", r);
  ASSERT_EQ(r.status, 0) << r.output;
  ASSERT_GE(rows.size(), 4u) << r.output;
  for (const auto& [method, row] : rows) {
    const double bound = 2.0 * number(row, "max_error_rad") + 1e-12;
    for (const char* column : {"rpe_1s_max_rad", "rpe_10s_max_rad"}) {
      const double e = number(row, column);
      EXPECT_TRUE(std::isfinite(e)) << method << " " << column;
      EXPECT_LE(e, bound) << method << " " << column;
    }
  }
}

// Rates about two axes only (the vectors b_i in the xy plane) and a_i = R b_i with R a turn of
// 2.5 rad about x, which takes the plane's normal z to a direction with cos 2.5 < 0 along z:
// the sum a_i b_i^T alone has a zero singular value, and its nearest orthogonal matrix may be a
// mirror. The fit must be R itself: the only rotation that maps the plane so.
TEST(EvaluateRules, WahbaFitIsTheRotationNotItsMirror) {
  const Eigen::Matrix3d R = Eigen::AngleAxisd(2.5, Eigen::Vector3d::UnitX()).toRotationMatrix();
  std::vector<Eigen::Vector3d> a, b;
  for (int i = 0; i < 12; ++i) {
    const double angle = 2.0 * M_PI * i / 12.0;
    b.emplace_back(std::cos(angle), std::sin(angle), 0.0);
    a.push_back(R * b.back());
  }
  const Eigen::Matrix3d fit = ap::tools::wahba(a, b);
  EXPECT_NEAR(fit.determinant(), 1.0, 1e-9);
  EXPECT_LT((fit - R).norm(), 1e-6) << fit;
}

// ---------------------------------------------------------------------------------------------
// The ranking, the clocks and the truth's checks (docs/bag_tools.md, "How the ranking works")
// ---------------------------------------------------------------------------------------------

namespace {

std::map<std::string, Row> readRows(const TempDir& dir) {
  std::map<std::string, Row> rows;
  for (const Row& row : readCsv(dir.file("eval.csv"))) rows[field(row, "method")] = row;
  return rows;
}

std::string recommendedOf(const std::map<std::string, Row>& rows) {
  for (const auto& [method, row] : rows) {
    if (field(row, "recommended") == "1") return method;
  }
  return "";
}

double smallest(const std::map<std::string, Row>& rows, const char* column) {
  double best = INFINITY;
  for (const auto& [method, row] : rows) best = std::min(best, number(row, column));
  return best;
}

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

}  // namespace

// The windows: 10 periods of the slower stream, doubling up to 10 s.
TEST(EvaluateRules, RankingWindowsFromTheSlowerStream) {
  const std::vector<double> w = ap::tools::rankingWindows(1.0 / 30.0, 1.0 / 50.0);
  ASSERT_EQ(w.size(), 5u);
  for (std::size_t i = 0; i < w.size(); ++i)
    EXPECT_NEAR(w[i], std::ldexp(1.0 / 3.0, int(i)), 1e-12);
  EXPECT_EQ(ap::tools::rankingWindows(2.0, 0.005), std::vector<double>{20.0});  // longer alone
}

// The ranking window: the shortest whose smallest error is above the floor; windows without
// values are passed over; when none is above the floor, the longest measured.
TEST(EvaluateRules, RankingWindowIsTheShortestTheTruthResolves) {
  const double nan = std::nan("");
  using ap::tools::chooseRankingWindow;
  EXPECT_EQ(chooseRankingWindow({{1e-5, 2e-5}, {2e-5, 5e-5}, {4e-5, 1e-4}}, 1.5e-5), 1u);
  EXPECT_EQ(chooseRankingWindow({{nan, nan}, {2e-5, nan}, {4e-5, 1e-4}}, 1e-5), 1u);
  EXPECT_EQ(chooseRankingWindow({{1e-6, 2e-6}, {2e-6, 5e-6}, {nan, nan}}, 1e-5), 1u);
  EXPECT_EQ(chooseRankingWindow({}, 1e-5), 0u);
}

// A truth turning 7.4 times as far as the rates (odometry yaw), or half as far, is refused; a
// scale within 2 either way, or turns too small to judge, are not.
TEST(EvaluateRules, TurnMismatchBeyondAnySetting) {
  using ap::tools::turnMismatch;
  EXPECT_TRUE(turnMismatch(35.7, 4.8));
  EXPECT_TRUE(turnMismatch(1.0, 2.01));
  EXPECT_FALSE(turnMismatch(4.8 * 1.99, 4.8));
  EXPECT_FALSE(turnMismatch(4.8, 4.8 * 1.99));
  EXPECT_FALSE(turnMismatch(0.4, 0.01));  // below kMinJudgedTurn: a still recording
  EXPECT_TRUE(contains(*turnMismatch(35.7, 4.8), "35.7 rad"));
}

// The truth's own slow error (an AHRS's heading wandering by 0.1 rad over 40 s, a closed form)
// dominates every method's whole-run RMS error, so that the whole-run rule (the cheapest within
// 10 % of the lowest RMS) could not tell euler from cf4. Over the ranking window the truth's
// error barely moves and the integrators' own errors show: the window is the shortest the rule
// gives (10 rate periods, 50 ms: the truth is noise-free), where euler's error is more than 10 %
// above the best; the recommendation is within 10 % of the best error over it, and over 1 s
// within 1.2 times the best.
TEST(EvaluateRules, RankingMeasuresTheIntegratorNotTheTruthsDrift) {
  TempDir dir;
  SceneBag scene;
  scene.motion = coning(0.3, 2.0 * M_PI * 1.1);
  scene.duration = 60.0;
  const auto attitude = scene.motion.attitude;
  scene.truth_attitude = [attitude](double t) {
    // Heading wandering in the world frame, as an AHRS's does.
    return Eigen::Quaterniond(
        Eigen::AngleAxisd(0.1 * std::sin(2.0 * M_PI * t / 40.0), Eigen::Vector3d::UnitZ()) *
        attitude(t));
  };
  writeSceneBag(dir.file("in.bag"), scene);
  RunResult r;
  const auto rows = evaluateRows(dir, "--truth /truth --offset 0 --mount 0 0 0 1", r);
  ASSERT_EQ(r.status, 0) << r.output;
  const std::string pick = recommendedOf(rows);
  ASSERT_FALSE(pick.empty()) << r.output;
  // The whole-run rule's blindness: euler within 10 % of the lowest RMS error.
  EXPECT_LE(number(rows.at("euler/instantaneous"), "rms_error_rad"),
            1.1 * smallest(rows, "rms_error_rad"))
      << r.output;
  EXPECT_NEAR(number(rows.at(pick), "ranking_window_s"), 10.0 / 200.0, 1e-12);
  EXPECT_TRUE(contains(r.output, "ranking window: 0.05 s")) << r.output;
  EXPECT_LE(number(rows.at(pick), "rpe_ranking_rms_rad"),
            1.1 * smallest(rows, "rpe_ranking_rms_rad"));
  EXPECT_LE(number(rows.at(pick), "rpe_1s_rms_rad"), 1.2 * smallest(rows, "rpe_1s_rms_rad"))
      << r.output;
  // Over the ranking window euler's own error shows: it is not among the equals.
  EXPECT_GT(number(rows.at("euler/instantaneous"), "rpe_ranking_rms_rad"),
            1.1 * smallest(rows, "rpe_ranking_rms_rad"))
      << r.output;
  EXPECT_NE(pick, "euler/instantaneous");
}

// The truth's clock unknown (the default): a truth stamped 25 ms late is compared at the offset
// found, and no rate_delay is recommended. Stated the same (--truth-clock same), the data
// contradict it (the rates would lag by -25 ms): the report says so, the comparison falls back
// to the offset found, the CSVs (and the front end's chart) are written, and the exit code is 5.
TEST(EvaluateRules, TruthClockUnknownUnlessStated) {
  TempDir dir;
  SceneBag scene;
  scene.motion = tumbling();
  scene.duration = 10.0;
  scene.truth_offset = 0.025;
  writeSceneBag(dir.file("in.bag"), scene);
  RunResult r;
  const auto rows = evaluateRows(dir, "--truth /truth --mount 0 0 0 1", r);
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NEAR(number(rows.at("cf4/instantaneous"), "offset_s"), 0.025, 1e-4) << r.output;
  EXPECT_LT(number(rows.at("cf4/instantaneous"), "rms_error_rad"), 1e-6) << r.output;
  EXPECT_TRUE(contains(r.output, "# rate_delay: not recommended")) << r.output;

  const RunResult same =
      run(kEvaluateCore + " " + dir.file("in.bag") + " --csv " + dir.file("eval") +
          " --no-progress --truth /truth --mount 0 0 0 1" + " --truth-clock same");
  EXPECT_EQ(same.status, 5) << same.output;
  EXPECT_TRUE(contains(same.output, "the data contradict --truth-clock same")) << same.output;
  const auto fallback = readRows(dir);
  ASSERT_EQ(fallback.size(), evaluatedMethods());
  EXPECT_NEAR(number(fallback.at("cf4/instantaneous"), "offset_s"), 0.025, 1e-4);
  EXPECT_LT(number(fallback.at("cf4/instantaneous"), "rms_error_rad"), 1e-6);
  EXPECT_TRUE(contains(same.output, "# rate_delay: not recommended")) << same.output;
  // The front end draws the chart all the same, and passes the exit code on.
  const RunResult front =
      run("EVALUATE_BAG_CORE=" + quote(kEvaluateCore) + " /usr/bin/python3 " + quote(kEvaluate) +
          " " + dir.file("in.bag") + " --csv " + dir.file("front") +
          " --no-progress --truth /truth --mount 0 0 0 1" + " --truth-clock same");
  EXPECT_EQ(front.status, 5) << front.output;
  EXPECT_TRUE(std::ifstream(dir.file("front.png")).good()) << front.output;
}

// Truths that cannot be one are refused (exit 4, nothing written), each naming what is wrong:
// odometry yaw turning 7.4 times as far as the gyro (the gyro turns through a t^2 / 2 about z,
// the "truth" through 7.4 times that), quaternions all zero, quaternions of norm 1.1, and an
// Imu whose every message says it has no orientation (REP-145).
TEST(EvaluateRules, TruthsThatCannotBeOneAreRefused) {
  const Motion spin = torquedFromRest(Eigen::Vector3d::UnitZ(), 0.1, 4.0);  // 1.25 rad at 10 s
  struct Case {
    const char* name;
    std::function<void(SceneBag&)> set;
    const char* says;
  };
  const std::vector<Case> cases{
      {"odometry yaw",
       [](SceneBag& s) {
         s.truth = TruthType::Odometry;
         s.truth_attitude = [](double t) {
           return Eigen::Quaterniond(
               Eigen::AngleAxisd(7.4 * 0.1 / 4.0 * t * t / 2.0, Eigen::Vector3d::UnitZ()));
         };
       },
       "times as far"},
      {"zero quaternions", [](SceneBag& s) { s.truth_norm = 0.0; }, "are zero or non-finite"},
      {"non-unit quaternions", [](SceneBag& s) { s.truth_norm = 1.1; }, "are not unit"},
      {"REP-145",
       [](SceneBag& s) {
         s.truth = TruthType::Imu;
         s.truth_orientation_covariance = -1.0;
       },
       "REP-145"},
  };
  for (const Case& c : cases) {
    TempDir dir;
    SceneBag scene;
    scene.motion = spin;
    scene.duration = 10.0;
    c.set(scene);
    writeSceneBag(dir.file("in.bag"), scene);
    RunResult r;
    evaluateRows(dir, "--truth /truth --offset 0 --mount 0 0 0 1", r);
    EXPECT_EQ(r.status, 4) << c.name << "\n" << r.output;
    EXPECT_TRUE(contains(r.output, c.says)) << c.name << "\n" << r.output;
    EXPECT_TRUE(contains(r.output, "/truth")) << c.name << "\n" << r.output;
    EXPECT_FALSE(std::ifstream(dir.file("eval.csv")).good()) << c.name;
  }
}

// An Imu's orientation is a truth (REP-145: orientation_covariance[0] not -1): cf4 follows the
// closed form to 1e-6 rad. Odometry is taken with a warning.
TEST(EvaluateRules, ImuOrientationIsATruthOdometryWarned) {
  for (const TruthType type : {TruthType::Imu, TruthType::Odometry}) {
    TempDir dir;
    SceneBag scene;
    scene.motion = tumbling();
    scene.duration = 10.0;
    scene.truth = type;
    writeSceneBag(dir.file("in.bag"), scene);
    RunResult r;
    const auto rows = evaluateRows(dir, "--truth /truth --offset 0 --mount 0 0 0 1", r);
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_LT(number(rows.at("cf4/instantaneous"), "max_error_rad"), 1e-6) << r.output;
    EXPECT_EQ(contains(r.output, "is odometry: its orientation is rarely a truth"),
              type == TruthType::Odometry)
        << r.output;
  }
}

// The rate is reported as the mean over the run (span / (N - 1) of the stamps written), with the
// intervals' standard deviation beside it: a 180 Hz stream with 0.5 ms of receipt jitter and 10 %
// of its samples lost.
TEST(EvaluateRules, MeanRateAndJitterAreReported) {
  TempDir dir;
  SceneBag scene;
  scene.motion = coning();
  scene.duration = 10.0;
  scene.rate_hz = 180.0;
  scene.jitter = 5e-4;  // 5.6 ms apart: never out of order
  scene.drop = 0.1;
  const Written w = writeSceneBag(dir.file("in.bag"), scene);
  std::vector<Stamp> stamps = w.rate_stamps;
  std::sort(stamps.begin(), stamps.end());
  const double mean = double(stamps.back() - stamps.front()) * 1e-9 / double(stamps.size() - 1);
  double ss = 0.0;
  for (std::size_t i = 1; i < stamps.size(); ++i) {
    ss += std::pow(double(stamps[i] - stamps[i - 1]) * 1e-9 - mean, 2);
  }
  const double sd = std::sqrt(ss / double(stamps.size() - 2));
  RunResult r;
  evaluateRows(dir, "--truth /truth --offset 0 --mount 0 0 0 1", r);
  ASSERT_EQ(r.status, 0) << r.output;
  char text[200];
  std::snprintf(text, sizeof text,
                "%.1f Hz mean (intervals %.3f ms mean, %.3f ms standard deviation", 1.0 / mean,
                mean * 1e3, sd * 1e3);
  EXPECT_TRUE(contains(r.output, text)) << text << "\n" << r.output;
}

// A sample with a non-finite component is skipped as a lost sample is, and bridged as one:
// the same scene (interval averages of the coning motion, and point samples) with sample 2000
// of 4001 NaN and with it lost gives every method the same errors, to the last digit written.
TEST(EvaluateRules, NonFiniteSampleIsBridgedAsALostOne) {
  for (const bool averaged : {true, false}) {
    std::map<std::string, Row> rows[2];
    for (int variant = 0; variant < 2; ++variant) {
      TempDir dir;
      SceneBag scene;
      scene.motion = coning();
      scene.averaged = averaged;
      (variant == 0 ? scene.non_finite : scene.lost).push_back(2000);
      writeSceneBag(dir.file("in.bag"), scene);
      RunResult r;
      rows[variant] = evaluateRows(dir, "--truth /truth --offset 0 --mount 0 0 0 1", r);
      ASSERT_EQ(r.status, 0) << r.output;
      EXPECT_EQ(contains(r.output, "skipped: 1 rate samples with a non-finite component"),
                variant == 0)
          << r.output;
    }
    ASSERT_EQ(rows[0].size(), evaluatedMethods());
    for (const auto& [method, row] : rows[0]) {
      for (const char* column : {"max_error_rad", "rms_error_rad", "rpe_1s_rms_rad"}) {
        EXPECT_EQ(field(row, column), field(rows[1].at(method), column))
            << method << " " << column << (averaged ? " averaged" : " point samples");
      }
    }
  }
}

// The public recordings (not shipped; AP_REAL_BAGS names their folder, the test skips without
// it): with their IMUs' own AHRS orientation as truth, the recommendation's error over 1 s is
// within 1.2 times the best method's; an IMU without orientation is refused (exit 4).
TEST(EvaluateRules, RealRecordings) {
  const char* folder = std::getenv("AP_REAL_BAGS");
  if (!folder || !std::ifstream(std::string(folder) + "/test1.bag").good()) {
    GTEST_SKIP() << "AP_REAL_BAGS: no folder with the real recordings";
  }
  const std::vector<std::pair<std::string, std::string>> bags{{"test1.bag", "/imu/data"},
                                                              {"ardrone_imu.bag", "/ardrone/imu"}};
  for (const auto& [bag, topic] : bags) {
    TempDir dir;
    const RunResult r =
        run(kEvaluateCore + " " + quote(std::string(folder) + "/" + bag) + " --rates " + topic +
            " --truth " + topic + " --no-progress --csv " + dir.file("eval"));
    ASSERT_EQ(r.status, 0) << bag << "\n" << r.output;
    const auto rows = readRows(dir);
    const std::string pick = recommendedOf(rows);
    ASSERT_FALSE(pick.empty()) << r.output;
    const double best = smallest(rows, "rpe_1s_rms_rad");
    std::printf("[ real     ] %s: %s, 1 s error %.3g rad, best %.3g (%.3f times)\n", bag.c_str(),
                pick.c_str(), number(rows.at(pick), "rpe_1s_rms_rad"), best,
                number(rows.at(pick), "rpe_1s_rms_rad") / best);
    EXPECT_LE(number(rows.at(pick), "rpe_1s_rms_rad"), 1.2 * best) << bag << "\n" << r.output;
  }
  const std::string phidgets = std::string(folder) + "/phidgets_imu_upside_down.bag";
  if (std::ifstream(phidgets).good()) {
    TempDir dir;
    const RunResult r =
        run(kEvaluateCore + " " + quote(phidgets) +
            " --rates /imu/data_raw --truth /imu/data_raw --no-progress --csv " + dir.file("eval"));
    EXPECT_EQ(r.status, 4) << r.output;
    EXPECT_TRUE(contains(r.output, "has no orientation")) << r.output;
  }
}
