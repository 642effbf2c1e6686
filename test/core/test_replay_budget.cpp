// The replay budget (replay_budget.h, docs/design.md §6.9) against its documented rule: in a
// second of stamp time at most kReplayFloor + kReplayPerRecorded times the states the rates
// recorded (in that second or the one before, the larger) are replayed; a late fix or
// measurement whose replay would exceed it is refused before anything changes, and counted.
#include <gtest/gtest.h>

#include <cstddef>
#include <map>
#include <string>

#include "attitude_propagator/estimation/replay_budget.h"
#include "engine_fixtures.h"

namespace ap = attitude_propagator;
using namespace engine_fixtures;  // NOLINT: the fixtures are the tests' vocabulary

TEST(ReplayBudget, TheFloorIsAffordedExactlyBeforeAnyRecord) {
  ap::ReplayBudget budget;
  EXPECT_TRUE(budget.affords(at(0.5), ap::kReplayFloor - 1));
  EXPECT_TRUE(budget.affords(at(0.5), ap::kReplayFloor));
  EXPECT_FALSE(budget.affords(at(0.5), ap::kReplayFloor + 1));
}

TEST(ReplayBudget, EachRecordedStateAddsItsShareAndChargesUseItUp) {
  ap::ReplayBudget budget;
  for (int k = 0; k < 10; ++k) budget.recorded(at(0.01 * k));
  const std::size_t allowance = ap::kReplayFloor + 10 * ap::kReplayPerRecorded;
  EXPECT_EQ(budget.allowance(), allowance);
  budget.charge(at(0.2), 100);
  EXPECT_TRUE(budget.affords(at(0.3), allowance - 100));
  EXPECT_FALSE(budget.affords(at(0.3), allowance - 99));
  EXPECT_EQ(budget.replayedThisSecond(), 100u);
}

TEST(ReplayBudget, ANewSecondStartsEmptyAndKeepsThePreviousSecondsRecords) {
  ap::ReplayBudget budget;
  for (int k = 0; k < 100; ++k) budget.recorded(at(0.01 * k));  // 100 in the first second
  budget.charge(at(0.99), ap::kReplayFloor);
  budget.recorded(at(1.0));  // one in the second: the first second's 100 still count
  EXPECT_EQ(budget.replayedThisSecond(), 0u);
  EXPECT_EQ(budget.allowance(), ap::kReplayFloor + 100 * ap::kReplayPerRecorded);
  // Two seconds later nothing recorded since: the floor alone.
  EXPECT_TRUE(budget.affords(at(3.5), ap::kReplayFloor));
  EXPECT_EQ(budget.allowance(), ap::kReplayFloor);
}

TEST(ReplayBudget, AnEarlierStampIsCountedInTheCurrentSecond) {
  ap::ReplayBudget budget;
  budget.charge(at(2.5), 10);
  budget.charge(at(1.5), 10);  // a replay judged at an older stamp: never a fresh second
  EXPECT_EQ(budget.replayedThisSecond(), 20u);
}

TEST(ReplayBudget, ClearedItStartsAgainAtAnEarlierSecond) {
  ap::ReplayBudget budget;
  budget.charge(at(10.5), ap::kReplayFloor);
  EXPECT_FALSE(budget.affords(at(0.5), 1));  // time went back: still the later second's
  budget.clear();
  EXPECT_TRUE(budget.affords(at(0.5), ap::kReplayFloor));
}

namespace {

ap::EngineConfig withFixes(ap::FixMode mode, double history) {
  ap::EngineConfig c = kinematicConfig();
  c.fixes.mode = mode;
  c.fixes.history = history;
  return c;
}

}  // namespace

// A flood: 1 kHz rates and, from 5 s on, a fix with every rate stamped 4 s earlier (each
// replays 4000 states). Per second the budget is kReplayFloor + 1000 kReplayPerRecorded
// states: at most that / 4000 fixes (6) are applied in any second, the rest refused and
// counted, and every rate is still taken.
TEST(ReplayBudgetEngine, AFloodOfLateFixesIsBoundedPerSecondAndEveryRateIsTaken) {
  DiscardingSink sink;
  ap::AttitudeEngine engine(withFixes(ap::FixMode::Reset, 10.0), sink);
  const Eigen::Quaterniond q(Eigen::AngleAxisd(0.1, Eigen::Vector3d::UnitZ()));
  std::map<int, int> applied_in_second;
  int fixes = 0;
  for (int k = 0; k <= 10000; ++k) {
    engine.submit(rate(at(0.001 * k), Eigen::Vector3d(0.0, 0.0, 0.2)));
    if (k == 0) engine.submitFix(at(0.0), q, Eigen::Matrix3d::Zero());  // the history starts
    if (k < 5000) continue;
    ++fixes;
    const ap::FixOutcome o = engine.submitFix(at(0.001 * k - 4.0), q, Eigen::Matrix3d::Zero());
    if (o == ap::FixOutcome::Reset) ++applied_in_second[k / 1000];
  }
  const std::size_t per_second = (ap::kReplayFloor + 1000 * ap::kReplayPerRecorded) / 4000;
  ASSERT_EQ(per_second, 6u);
  for (const auto& [second, applied] : applied_in_second) {
    EXPECT_LE(applied, static_cast<int>(per_second)) << "second " << second;
    EXPECT_GE(applied, 1) << "second " << second;
  }
  const ap::EngineCounters& c = engine.counters();
  EXPECT_EQ(c.accepted, 10001u);
  EXPECT_EQ(c.fixes_accepted + c.fixes_over_budget, static_cast<std::uint64_t>(fixes) + 1);
  EXPECT_GT(c.fixes_over_budget, 4000u);
}

// What the budget must never refuse: fixes at 10 Hz, 100 ms late, on 200 Hz rates.
TEST(ReplayBudgetEngine, OrdinaryLateFixesAreNeverOverBudget) {
  DiscardingSink sink;
  ap::AttitudeEngine engine(withFixes(ap::FixMode::Fuse, 1.0), sink);
  for (int k = 0; k <= 2000; ++k) {
    const double t = 0.005 * k;
    engine.submit(rate(at(t), Eigen::Vector3d(0.0, 0.0, 0.2)));
    if (k >= 20 && k % 20 == 0) {
      engine.submitFix(at(t - 0.1), aboutAxis(Eigen::Vector3d::UnitZ(), 0.2 * (t - 0.1)),
                       Eigen::Matrix3d::Zero());
    }
  }
  EXPECT_EQ(engine.counters().fixes_over_budget, 0u);
  // The first starts the history at the newest state, after its own stamp: too old.
  EXPECT_EQ(engine.counters().fixes_too_old, 1u);
  EXPECT_EQ(engine.counters().fixes_accepted, 99u);
}

// The estimate counts the re-applications: a fix before an applied one replays the states
// after it once, and once more from the applied fix on. 100 Hz rates for 10 s (allowance in the
// newest second: 4096 + 20 x 100 = 6096), a fix at 9 s (100 states), then fixes at 1 s, each
// estimated at 900 x 2 = 1800 and charged 900 + 100: the fifth fits (5100 + 1800 > 6096 only
// for the sixth), the sixth does not.
TEST(ReplayBudgetEngine, TheEstimateCountsTheFixesAppliedAgain) {
  DiscardingSink sink;
  ap::AttitudeEngine engine(withFixes(ap::FixMode::Reset, 10.0), sink);
  const Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
  for (int k = 0; k <= 1000; ++k) {
    engine.submit(rate(at(0.01 * k), Eigen::Vector3d(0.0, 0.0, 0.2)));
    if (k == 0) engine.submitFix(at(0.0), q, Eigen::Matrix3d::Zero());  // the history starts
  }
  ASSERT_EQ(engine.submitFix(at(9.0), q, Eigen::Matrix3d::Zero()), ap::FixOutcome::Reset);
  for (int j = 1; j <= 5; ++j) {
    EXPECT_EQ(engine.submitFix(at(1.0), q, Eigen::Matrix3d::Zero()), ap::FixOutcome::Reset) << j;
  }
  EXPECT_EQ(engine.submitFix(at(1.0), q, Eigen::Matrix3d::Zero()), ap::FixOutcome::OverBudget);
  EXPECT_EQ(engine.counters().fixes_over_budget, 1u);
}

// The fix counters' one list: each counter once, in the order of docs/node.md's table, and the
// fixes not applied are all of them but the applied ones (accepted, resets among them).
TEST(FixCounters, OneListEachCounterOnceAndTheNotAppliedSum) {
  ap::EngineCounters c;
  c.fixes_accepted = 1;
  c.fixes_reset = 2;
  c.fixes_rejected_gate = 4;
  c.fixes_too_old = 8;
  c.fixes_bad_quaternion = 16;
  c.fixes_bad_covariance = 32;
  c.fixes_queue_full = 64;
  c.fixes_future = 128;
  c.fixes_over_budget = 256;
  std::string names;
  std::uint64_t sum = 0;
  ap::forEachFixCounter(c, [&](const char* name, std::uint64_t value) {
    names += std::string(names.empty() ? "" : " ") + name;
    sum += value;
  });
  EXPECT_EQ(names,
            "accepted reset rejected_gate too_old bad_quaternion bad_covariance queue_full future "
            "over_budget");
  EXPECT_EQ(sum, 511u);
  EXPECT_EQ(ap::fixesNotApplied(c), 511u - 1u - 2u);
}
