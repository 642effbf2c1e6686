// The node's diagnostics (src/ros/node_diagnostics.cpp, input_window.cpp) against their
// documented rules (docs/node.md, diagnostics): each WARN rule on both sides of its boundary,
// the order of the rules, and what the input window blames. Wall times are given, not read.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "../core/engine_fixtures.h"
#include "../core/sampling.h"
#include "attitude_propagator/ros/node_diagnostics.h"

namespace ap = attitude_propagator;
using diagnostic_msgs::DiagnosticStatus;

namespace {

ros::WallTime at(double s) { return ros::WallTime(1000.0 + s); }

/// Counters after `received` rate samples of which `lost` were gaps, the rest accepted.
ap::EngineCounters gapsOf(std::uint64_t received, std::uint64_t gaps) {
  ap::EngineCounters c;
  c.received = received;
  c.accepted = received - gaps;
  c.gaps = gaps;
  return c;
}

/// The problem of a window from zero counters at 0 s to `c` at `seconds`.
std::string windowProblem(const ap::EngineCounters& c, double seconds = 1.0, double max_dt = 1.0) {
  ap::InputWindow w;
  w.closeInputWindow(at(0), {}, max_dt);
  w.closeInputWindow(at(seconds), c, max_dt);
  return w.problem();
}

std::string value(const diagnostic_updater::DiagnosticStatusWrapper& s, const std::string& key) {
  for (const auto& kv : s.values) {
    if (kv.key == key) return kv.value;
  }
  ADD_FAILURE() << "no key " << key;
  return {};
}

}  // namespace

TEST(InputWindow, HalfOfTheSamplesLostIsAProblemLessIsNot) {
  EXPECT_EQ(windowProblem(gapsOf(100, 49)), "");
  EXPECT_EQ(windowProblem(gapsOf(100, 50)),
            "half or more of the rate samples of the last second were lost (50 of 100): gaps "
            "longer than max_dt 1 s (input period 0.01 s): messages lost on the way or stamps "
            "far apart");
  EXPECT_EQ(windowProblem(gapsOf(3, 1)), "");  // odd counts: 1 of 3 is less than half
  EXPECT_NE(windowProblem(gapsOf(3, 2)), "");
  EXPECT_EQ(windowProblem(gapsOf(0, 0)), "");  // nothing received: nothing lost
}

TEST(InputWindow, TheWindowClosesAfterOneSecondAndNotBefore) {
  ap::InputWindow w;
  w.closeInputWindow(at(0), {}, 1.0);
  w.closeInputWindow(at(ap::kInputWindow - 1e-3), gapsOf(100, 100), 1.0);
  EXPECT_EQ(w.problem(), "");  // still open
  w.closeInputWindow(at(ap::kInputWindow), gapsOf(100, 100), 1.0);
  EXPECT_NE(w.problem(), "");
}

TEST(InputWindow, TheFirstCallOnlyOpensAWindow) {
  ap::InputWindow w;
  w.closeInputWindow(at(0), gapsOf(100, 100), 1.0);
  EXPECT_EQ(w.problem(), "");
  // Losses before the window opened are not the window's.
  w.closeInputWindow(at(1), gapsOf(200, 100), 1.0);
  EXPECT_EQ(w.problem(), "");
}

TEST(InputWindow, EachWindowCountsFromItsStart) {
  ap::InputWindow w;
  w.closeInputWindow(at(0), {}, 1.0);
  w.closeInputWindow(at(1), gapsOf(100, 80), 1.0);
  EXPECT_NE(w.problem(), "");
  w.closeInputWindow(at(2), gapsOf(200, 110), 1.0);  // 30 of the next 100 lost
  EXPECT_EQ(w.problem(), "");
}

TEST(InputWindow, TheCommonestCauseIsNamedTheFirstOnATie) {
  ap::EngineCounters c;
  c.received = 10;
  c.dropped_stale = 3;
  c.rejected_no_rate = 4;
  c.dropped_no_time = 4;
  // 11 losses counted for 10 received (one input can count twice): never more than received.
  EXPECT_EQ(windowProblem(c),
            "half or more of the rate samples of the last second were lost (10 of 10): "
            "angular_velocity_covariance[0] == -1 (REP-145: no rate)");
}

// Every counter of the core's table that counts a rate or torque input left unused is a cause of
// loss, named by the node's advice or, without one, by the table's meaning: a counter added to
// the table cannot be left out of the window.
TEST(InputWindow, EveryUnusedInputCounterOfTheTableIsACause) {
  int counted = 0;
  for (const ap::CounterInfo& info : ap::engineCounterTable()) {
    if (!ap::countsUnusedInput(info)) continue;
    SCOPED_TRACE(info.name);
    ap::EngineCounters c;
    c.received = 10;
    ap::counterField(c, info) = 10;
    const char* advice = ap::inputLossAdvice(info.name);
    const std::string cause = advice != nullptr ? advice : info.meaning;
    EXPECT_EQ(windowProblem(c),
              "half or more of the rate samples of the last second were lost (10 of 10): " + cause);
    ++counted;
  }
  EXPECT_GE(counted, 12);  // the twelve drops of docs/bag_tools.md's list at least
  EXPECT_EQ(ap::inputLossAdvice("gaps"), nullptr);  // the gaps' cause needs max_dt (below)
}

TEST(InputWindow, AMaxDtBelowTheInputPeriodIsNamed) {
  // 100 samples in 1 s: a period of 0.01 s.
  EXPECT_NE(windowProblem(gapsOf(100, 100), 1.0, 0.01).find("gaps longer than max_dt 0.01 s"),
            std::string::npos);
  EXPECT_EQ(windowProblem(gapsOf(100, 100), 1.0, 0.0099),
            "half or more of the rate samples of the last second were lost (100 of 100): max_dt "
            "0.0099 s is below the input period 0.01 s");
}

TEST(InputLag, BeyondHalfASecondEitherWay) {
  const double limit = ap::kInputLagWarning;
  EXPECT_FALSE(ap::lagBeyondWarning({limit, -limit, std::nullopt}));
  EXPECT_EQ(ap::lagBeyondWarning({limit + 1e-9}), limit + 1e-9);
  EXPECT_EQ(ap::lagBeyondWarning({-limit - 1e-9}), -limit - 1e-9);
  EXPECT_EQ(ap::lagBeyondWarning({std::nullopt, 0.1, 0.7, -0.9}), 0.7);  // the first beyond
}

class Summary : public ::testing::Test {
 protected:
  diagnostic_updater::DiagnosticStatusWrapper summarize(bool expects_input, double silence,
                                                        const std::string& window = "",
                                                        std::uint64_t fixes_not_applied = 0,
                                                        std::optional<double> lag = {}) {
    ap::EngineCounters c;
    c.fixes_rejected_gate = fixes_not_applied;
    diagnostic_updater::DiagnosticStatusWrapper status;
    ap::summarize(status, expects_input, silence, window, fixes_, c, lag);
    return status;
  }
  ap::InstanceLog log_;
  ap::FixInput fixes_{ap::validateParameters({}), log_};
};

TEST_F(Summary, NoRateInputForMoreThanASecond) {
  const std::string none = "no rate input in the last second";
  EXPECT_EQ(summarize(true, -1.0).message, none);  // none yet
  EXPECT_EQ(summarize(true, -1.0).level, DiagnosticStatus::WARN);
  EXPECT_EQ(summarize(true, 1.0).message, "propagating");
  EXPECT_EQ(summarize(true, 1.0).level, DiagnosticStatus::OK);
  EXPECT_EQ(summarize(true, 1.0 + 1e-9).message, none);
  EXPECT_EQ(summarize(false, -1.0).message, "propagating");  // no rate input expected
}

TEST_F(Summary, RatesThatArriveRefusedAreNamedNotNoInput) {
  ap::EngineCounters c;
  diagnostic_updater::DiagnosticStatusWrapper status;
  ap::summarize(status, true, -1.0, "", fixes_, c, {}, "no transform from 'imu' to 'base_link'");
  EXPECT_EQ(status.level, DiagnosticStatus::WARN);
  EXPECT_EQ(status.message, "rate input refused: no transform from 'imu' to 'base_link'");
}

TEST(NodeDiagnostics, ARefusalInTheLastSecondIsTheSummary) {
  const ap::NodeConfig config = ap::validateParameters({});
  engine_fixtures::DiscardingSink sink;
  ap::AttitudeEngine engine(ap::engineConfig(config), sink);
  ap::InstanceLog log;
  ap::FixInput fixes(config, log);
  ap::TfConflictWatch tf;
  ap::NodeDiagnostics d(at(0));
  d.inputRefused(at(0.5), "the cause");
  diagnostic_updater::DiagnosticStatusWrapper status;
  d.diagnose(at(1.5), config, engine, fixes, tf, 0, status);
  EXPECT_EQ(status.message, "rate input refused: the cause");
  diagnostic_updater::DiagnosticStatusWrapper later;
  d.diagnose(at(1.5 + 1e-3), config, engine, fixes, tf, 0, later);  // more than 1 s after
  EXPECT_EQ(later.message, "no rate input in the last second");
}

TEST_F(Summary, TheFirstRuleThatHoldsIsTheSummary) {
  EXPECT_EQ(summarize(true, -1.0, "lost", ap::kFixWarnRun, 0.9).message,
            "no rate input in the last second");
  EXPECT_EQ(summarize(true, 0.0, "lost", ap::kFixWarnRun, 0.9).message, "lost");
  const auto fixes = summarize(true, 0.0, "", ap::kFixWarnRun, 0.9);
  EXPECT_EQ(fixes.level, DiagnosticStatus::WARN);
  EXPECT_EQ(fixes.message.rfind("the last 3 orientation fixes were not applied", 0), 0u);
  EXPECT_EQ(summarize(true, 0.0, "", ap::kFixWarnRun - 1, 0.9).message.rfind("inputs arrive", 0),
            0u);
}

TEST_F(Summary, ALagSaysWhichWay) {
  const auto behind = summarize(true, 0.0, "", 0, 0.75);
  EXPECT_EQ(behind.level, DiagnosticStatus::WARN);
  EXPECT_EQ(behind.message,
            "inputs arrive 0.750 s behind ROS time (sensor clock skewed, or a queue): tf lookups "
            "at now will miss");
  EXPECT_EQ(summarize(true, 0.0, "", 0, -1.25).message,
            "inputs arrive 1.250 s ahead of ROS time (sensor clock skewed, or a queue): tf "
            "lookups at now will miss");
}

TEST(NodeDiagnostics, TheInputRateAndTheWrappersCounts) {
  const ap::NodeConfig config = ap::validateParameters({});
  engine_fixtures::DiscardingSink sink;
  ap::AttitudeEngine engine(ap::engineConfig(config), sink);
  ap::InstanceLog log;
  ap::FixInput fixes(config, log);
  ap::TfConflictWatch tf;
  ap::Parameters stop;
  stop.tf_conflict = "stop";
  tf2_msgs::TFMessage other;
  other.transforms.resize(1);
  other.transforms[0].child_frame_id = stop.body_frame;
  tf.onTfSeen(other, "/a", false, false, stop, at(0));

  ap::NodeDiagnostics diagnostics(at(0));
  for (int i = 1; i <= 4; ++i) {
    ap::Input in;
    in.stamp = 1000000000LL * 100 + i * 10000000LL;
    in.value = Eigen::Vector3d(0.1, 0.0, 0.0);
    engine.submit(in);
  }
  diagnostics.inputArrived(at(1.5));
  diagnostic_updater::DiagnosticStatusWrapper status;
  diagnostics.diagnose(at(2), config, engine, fixes, tf, 7, status);
  EXPECT_EQ(status.message, "propagating");  // an input 0.5 s ago
  const std::uint64_t accepted = engine.counters().accepted;
  EXPECT_EQ(accepted, 4u);
  EXPECT_EQ(std::stod(value(status, "input_rate_hz")), accepted / 2.0);
  EXPECT_EQ(value(status, "accepted"), "4");
  EXPECT_EQ(value(status, "callback_errors"), "7");
  EXPECT_EQ(value(status, "tf_conflicts"), "1");
  EXPECT_EQ(value(status, "tf_stopped"), "True");
  EXPECT_EQ(value(status, "tf_resumes"), "0");
  EXPECT_EQ(diagnostics.lastDiagnosis(), at(2));

  // The next interval counts from this diagnosis: no input since.
  diagnostic_updater::DiagnosticStatusWrapper later;
  diagnostics.diagnose(at(3), config, engine, fixes, tf, 7, later);
  EXPECT_EQ(std::stod(value(later, "input_rate_hz")), 0.0);
  EXPECT_EQ(later.message, "no rate input in the last second");  // 1.5 s since
}

// Every engine counter is published once, under the core table's name and in its order, with
// the counter's value; no key is published twice (the fix and aiding counters among them).
TEST(NodeDiagnostics, EveryEngineCounterOnceUnderItsTableName) {
  const ap::NodeConfig config = ap::validateParameters({});
  engine_fixtures::DiscardingSink sink;
  ap::AttitudeEngine engine(ap::engineConfig(config), sink);
  ap::InstanceLog log;
  ap::FixInput fixes(config, log);
  ap::TfConflictWatch tf;
  ap::NodeDiagnostics diagnostics(at(0));
  ap::Input straggler;
  for (std::int64_t ms : {100, 200, 150}) {  // the third at or before the newest: stale
    straggler.stamp = 1000000000LL * 100 + ms * 1000000LL;
    engine.submit(straggler);
  }
  diagnostic_updater::DiagnosticStatusWrapper status;
  diagnostics.diagnose(at(1), config, engine, fixes, tf, 0, status);
  std::vector<std::string> keys, counters;
  for (const auto& kv : status.values) {
    EXPECT_EQ(std::count(keys.begin(), keys.end(), kv.key), 0) << "twice: " << kv.key;
    keys.push_back(kv.key);
    for (const ap::CounterInfo& info : ap::engineCounterTable()) {
      if (info.name == kv.key) counters.push_back(kv.key);
    }
  }
  std::vector<std::string> table;
  for (const ap::CounterInfo& info : ap::engineCounterTable()) table.push_back(info.name);
  EXPECT_EQ(counters, table);
  EXPECT_EQ(value(status, "received"), "3");
  EXPECT_EQ(value(status, "accepted"), "2");
  EXPECT_EQ(value(status, "dropped_stale"), "1");
}

// use_mag: the engine's sphere fit, live (addFieldFit): "none" while the reads fix no sphere
// (4 reads: 4 unknowns and no scatter), then its centre, the mag_bias to give, and whether it is
// determined (HardIronSphere::determined: 600 exact reads spread every way are); without
// use_mag no key.
TEST(NodeDiagnostics, TheFieldFitWithUseMag) {
  ap::Parameters p;
  p.use_mag = true;
  const ap::NodeConfig config = ap::validateParameters(p);
  engine_fixtures::DiscardingSink sink;
  ap::AttitudeEngine engine(ap::engineConfig(config), sink);
  ap::InstanceLog log;
  ap::FixInput fixes(config, log);
  ap::NodeDiagnostics diagnostics(at(0));
  const Eigen::Vector3d own(12e-6, -31e-6, 7e-6);
  const int n = 600;
  auto diagnosed = [&] {
    diagnostic_updater::DiagnosticStatusWrapper status;
    diagnostics.diagnose(at(1), config, engine, fixes, ap::TfConflictWatch(), 0, status);
    return status;
  };
  auto read = [&](int from, int to) {  // the reads from..to-1 of n spread evenly
    for (int k = from; k < to; ++k) {
      engine.submitMagneticField(1000000000LL * 100 + k, own + 48e-6 * evenDirection(k, n),
                                 Eigen::Matrix3d::Zero());
    }
    return diagnosed();
  };
  const auto few = read(0, 4);
  EXPECT_EQ(value(few, "mag_bias_fit_reads"), "4");
  EXPECT_EQ(value(few, "mag_bias_fit"), "none");
  EXPECT_EQ(value(few, "mag_bias_fit_stddev"), "none");
  EXPECT_EQ(value(few, "mag_bias_fit_determined"), "False");
  const auto all = read(4, n);
  EXPECT_EQ(value(all, "mag_bias_fit_reads"), "600");
  EXPECT_EQ(value(all, "mag_bias_fit"), "[1.2e-05, -3.1e-05, 7e-06]");
  EXPECT_EQ(value(all, "mag_bias_fit_determined"), "True");

  const ap::NodeConfig without = ap::validateParameters({});
  diagnostic_updater::DiagnosticStatusWrapper status;
  diagnostics.diagnose(at(2), without, engine, fixes, ap::TfConflictWatch(), 0, status);
  for (const auto& kv : status.values)
    EXPECT_EQ(kv.key.rfind("mag_bias_fit", 0), std::string::npos);
}
