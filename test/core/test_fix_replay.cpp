// FixReplay (estimation/fix_replay.h, docs/design.md §6.9) on its own, driving a model of the
// test's: LoggingModel turns its state by Exp(w (t_s - t)) on each step to stamp s with the rate
// w (a constant rate about one axis is then exact in closed form: the motion from t_a to t_b is
// Exp(w (t_b - t_a))), and logs every step it is asked to replay. The history: a base state at
// the origin, then one step every 10 ms at a constant rate. A fix in reset mode makes the
// attitude the fix's at its stamp, so the newest state is the fix carried by the motion since.
#include <gtest/gtest.h>

#include <cstddef>
#include <memory>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include <Eigen/Geometry>

#include "attitude_propagator/estimation/attitude_fix.h"
#include "attitude_propagator/estimation/fix_replay.h"
#include "attitude_propagator/limits.h"
#include "attitude_propagator/numerics/quaternion.h"

namespace ap = attitude_propagator;

namespace {

constexpr ap::Stamp kOrigin = 100'000'000'000;  // a whole second: core time 0
constexpr ap::Stamp kStep = 10'000'000;         // 10 ms between entries
const Eigen::Vector3d kRate(0.0, 0.0, 0.5);     // rad/s, about z

ap::Stamp entry(int i) { return kOrigin + i * kStep; }
double seconds(ap::Stamp from, ap::Stamp to) { return static_cast<double>(to - from) * 1e-9; }
/// The motion at kRate from stamp `from` to `to`.
Eigen::Quaterniond motion(ap::Stamp from, ap::Stamp to) {
  return ap::expMap(kRate * seconds(from, to));
}
/// A fix's attitude, one per j, none near another.
Eigen::Quaterniond fixAttitude(int j) {
  return Eigen::Quaterniond(Eigen::AngleAxisd(0.1 * (j + 1), Eigen::Vector3d::UnitX()));
}

/// A model whose one rule is the rotation at the step's rate over the step; it logs what it is
/// asked to replay, and returns from a replay what the live call would (a step to keep, a state
/// to publish), which the FixReplay must discard but for the covariance.
class LoggingModel final : public ap::Propagator {
 public:
  explicit LoggingModel(const ap::TimeBase& time) : time_(time) {}

  ap::ModelResult submit(const ap::Input& input, std::optional<ap::Stamp> /*clock*/) override {
    return step(input);
  }
  ap::ModelResult replay(const ap::ModelStep& s) override {
    replayed.push_back(s.input);
    return step(s.input);
  }
  void setState(double t, const Eigen::Quaterniond& q_WB, const Eigen::Vector3d&) override {
    t_ = t;
    q_ = q_WB;
    anchored_ = true;
  }
  std::size_t reset() override { return 0; }
  InputOrderRestart restartInputOrder(ap::Source) override { return {}; }
  void reconfigure(const ap::EngineConfig&) override {}
  ap::EngineState state() const override {
    ap::EngineState s;
    s.q_WB = q_;
    return s;
  }
  ap::Model model() const override { return ap::Model::Kinematic; }
  const std::string& modelName() const override { return name_; }
  ap::Integrator integrator() const override { return ap::Integrator::Rk4; }
  std::optional<double> savedTime() const override {
    return anchored_ ? std::optional<double>(t_) : std::nullopt;
  }
  // The snapshot: a KinematicPropagator pinned at the model's time and orientation (a plain
  // value the ModelSnapshot can hold).
  void save(ap::ModelSnapshot& into) const override {
    ap::KinematicPropagator held{ap::KinematicConfig{}};
    held.setState(t_, q_, Eigen::Vector3d::Zero());
    into = std::move(held);
  }
  void restore(const ap::ModelSnapshot& from) override {
    if (const auto* held = std::get_if<ap::KinematicPropagator>(&from)) {
      t_ = held->time();
      q_ = held->orientation();
    }
  }
  void correctOrientation(const Eigen::Quaterniond& q_WB) override { q_ = q_WB; }

  const Eigen::Quaterniond& orientation() const { return q_; }
  /// The steps asked to be replayed, in order.
  std::vector<ap::Input> replayed;

 private:
  ap::ModelResult step(const ap::Input& input) {
    const double t = time_.coreTime(input.stamp);
    ap::ModelResult result;
    result.outcome = ap::StampOutcome::Advanced;
    result.source = input.source;
    result.stamp = input.stamp;
    result.publish = true;
    result.hand_on = true;
    result.keep_step = true;
    result.covariance = ap::ModelResult::Covariance::Step;
    result.h = t - t_;
    result.w_step = input.value;
    result.input = &input;
    q_ = q_ * ap::expMap(input.value * (t - t_));
    t_ = t;
    return result;
  }

  const ap::TimeBase& time_;
  double t_ = 0.0;
  Eigen::Quaterniond q_ = Eigen::Quaterniond::Identity();
  bool anchored_ = false;
  std::string name_ = "logging";
};

/// A FixReplay over a LoggingModel: the base state at the origin, then `steps` steps at kRate.
class Rig : public ap::StepCovariance {
 public:
  explicit Rig(ap::FixMode mode = ap::FixMode::Reset, double history = 1.0, int steps = 10) {
    config.mode = mode;
    config.history = history;
    time.pin(kOrigin);
    model.setState(0.0, Eigen::Quaterniond::Identity(), Eigen::Vector3d::Zero());
    error.P_B = 0.01 * Eigen::Matrix3d::Identity();
    replay.record(ap::ModelStep{}, true);
    for (int i = 1; i <= steps; ++i) step(entry(i));
    newest = entry(steps);
  }

  void followCovariance(const ap::ModelResult& result) override {
    followed.push_back(result.stamp);
  }

  void step(ap::Stamp stamp, ap::Source source = ap::Source::Imu) {
    ap::Input input;
    input.source = source;
    input.stamp = stamp;
    input.value = kRate;
    model.submit(input, std::nullopt);
    replay.record(ap::ModelStep{input, false});
  }
  ap::FixOutcome fix(ap::Stamp stamp, const Eigen::Quaterniond& q_WB) {
    return replay.applyInStampOrder({stamp, q_WB, 1e-4 * Eigen::Matrix3d::Identity()});
  }
  /// The stamps the model was asked to replay, in order.
  std::vector<ap::Stamp> replayedStamps() const {
    std::vector<ap::Stamp> stamps;
    for (const ap::Input& input : model.replayed) stamps.push_back(input.stamp);
    return stamps;
  }

  ap::FixConfig config;
  ap::TimeBase time;
  LoggingModel model{time};
  ap::ErrorState error;
  std::vector<ap::Stamp> followed;  // the stamps of the results whose covariance was followed
  ap::FixReplay replay{config, time, model, error, *this};
  ap::Stamp newest = kOrigin;
};

std::vector<ap::Stamp> entries(int first, int last) {
  std::vector<ap::Stamp> stamps;
  for (int i = first; i <= last; ++i) stamps.push_back(entry(i));
  return stamps;
}

double angleTo(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b) {
  return ap::rotationAngle(a, b);
}

constexpr double kTight = 1e-12;  // rad: round-off of a few products

}  // namespace

TEST(FixReplay, ReplaysTheLoggedStepsAfterTheEntryAFixActsAtInOrderKeepingOnlyTheCovariance) {
  Rig rig;
  const std::size_t kept = rig.replay.size();
  ASSERT_EQ(kept, 11u);  // the base and ten steps
  ASSERT_TRUE(rig.replay.replayAffordable(entry(4)));
  EXPECT_EQ(rig.fix(entry(4), fixAttitude(0)), ap::FixOutcome::Reset);
  // Stamped exactly at entry 4: it acts there, and the steps to entries 5..10 are replayed,
  // in order, each once.
  EXPECT_EQ(rig.replayedStamps(), entries(5, 10));
  // Of each replayed result only the covariance: followed once per step; its step is not kept
  // again (the history has as many entries), nothing else of it is acted on.
  EXPECT_EQ(rig.followed, entries(5, 10));
  EXPECT_EQ(rig.replay.size(), kept);
  // The newest state is the fix carried by the motion since its stamp.
  EXPECT_LT(angleTo(rig.model.orientation(), fixAttitude(0) * motion(entry(4), rig.newest)),
            kTight);
}

TEST(FixReplay, AFixOneNanosecondAfterAnEntryActsThereAndTakesTheNextStepAgainFirst) {
  Rig rig;
  const ap::Stamp stamp = entry(4) + 1;
  EXPECT_EQ(rig.fix(stamp, fixAttitude(0)), ap::FixOutcome::Reset);
  // Entry 4 is the last at or before it; the step to entry 5 is taken again from it (the
  // interval's own motion, to interpolate along), then the steps from entry 5 on are replayed.
  std::vector<ap::Stamp> expected{entry(5)};
  for (ap::Stamp s : entries(5, 10)) expected.push_back(s);
  EXPECT_EQ(rig.replayedStamps(), expected);
  EXPECT_LT(angleTo(rig.model.orientation(), fixAttitude(0) * motion(stamp, rig.newest)), kTight);
}

TEST(FixReplay, AFixOneNanosecondBeforeAnEntryActsAtTheEntryBeforeIt) {
  Rig rig;
  const ap::Stamp stamp = entry(4) - 1;
  EXPECT_EQ(rig.fix(stamp, fixAttitude(0)), ap::FixOutcome::Reset);
  std::vector<ap::Stamp> expected{entry(4)};
  for (ap::Stamp s : entries(4, 10)) expected.push_back(s);
  EXPECT_EQ(rig.replayedStamps(), expected);
  EXPECT_LT(angleTo(rig.model.orientation(), fixAttitude(0) * motion(stamp, rig.newest)), kTight);
}

TEST(FixReplay, AFixAtTheNewestEntryReplaysNothing) {
  Rig rig;
  EXPECT_TRUE(rig.replay.reaches(rig.newest));
  EXPECT_FALSE(rig.replay.reaches(rig.newest + 1));  // it would wait for the rates
  EXPECT_EQ(rig.fix(rig.newest, fixAttitude(0)), ap::FixOutcome::Reset);
  EXPECT_TRUE(rig.model.replayed.empty());
  EXPECT_LT(angleTo(rig.model.orientation(), fixAttitude(0)), kTight);
}

TEST(FixReplay, ReplayedRatesTakeTheBiasEstimateAsItIsNowAndTorquesDoNot) {
  Rig rig(ap::FixMode::Reset, 1.0, 0);
  rig.config.estimate_gyro_bias = true;
  rig.error.bias_B = Eigen::Vector3d(0.01, -0.02, 0.03);  // kept with every entry
  for (int i = 1; i <= 4; ++i) rig.step(entry(i));
  rig.step(entry(5), ap::Source::Torque);
  rig.step(entry(6));
  EXPECT_EQ(rig.fix(entry(4), fixAttitude(0)), ap::FixOutcome::Reset);
  ASSERT_EQ(rig.replayedStamps(), entries(5, 6));
  const Eigen::Vector3d& b = rig.error.bias_B;  // as it is now, after the fix
  EXPECT_TRUE(rig.replay.takesBiasEstimate(rig.model.replayed[1]));
  EXPECT_FALSE(rig.replay.takesBiasEstimate(rig.model.replayed[0]));
  EXPECT_EQ(rig.model.replayed[0].value, kRate);      // the torque as kept
  EXPECT_EQ(rig.model.replayed[1].value, kRate - b);  // the rate less the estimate
}

TEST(FixReplay, AFixExactlyFixHistoryOldIsAppliedAndOneNanosecondOlderIsTooOld) {
  // fix_history 50 ms: the newest entry at or before newest - 50 ms (entry 5) is kept.
  const double history = 0.05;
  {
    Rig rig(ap::FixMode::Reset, history);
    EXPECT_EQ(rig.fix(entry(5), fixAttitude(0)), ap::FixOutcome::Reset);
    EXPECT_EQ(rig.replayedStamps(), entries(6, 10));
  }
  for (ap::Stamp older : {entry(5) - 1, entry(1), kOrigin}) {
    Rig rig(ap::FixMode::Reset, history);
    const Eigen::Quaterniond before = rig.model.orientation();
    EXPECT_EQ(rig.fix(older, fixAttitude(0)), ap::FixOutcome::TooOld) << older - kOrigin;
    EXPECT_TRUE(rig.model.replayed.empty());
    EXPECT_EQ(rig.model.orientation().coeffs(), before.coeffs());  // untouched
  }
}

// The fixes applied are kept, at most kMaxFixesReapplied, to be applied again after an earlier
// one: the newest state is then the one all of them on time give (in reset mode: the latest
// fix carried by the motion since). Past the bound the oldest is forgotten, and a fix stamped
// before it is too old (one stamped at it is not).
class FixesKeptUpToTheBound : public ::testing::TestWithParam<std::size_t> {};

TEST_P(FixesKeptUpToTheBound, AnEarlierFixIsAppliedBeforeTheKeptOnesOrRefusedPastThem) {
  const std::size_t applied = GetParam();
  Rig rig(ap::FixMode::Reset, 1.0, 20);
  // Fixes at entries 3, 4, ..., each applied in turn.
  for (std::size_t j = 0; j < applied; ++j) {
    ASSERT_EQ(rig.fix(entry(3 + static_cast<int>(j)), fixAttitude(static_cast<int>(j))),
              ap::FixOutcome::Reset);
  }
  const int last = 3 + static_cast<int>(applied) - 1;
  const Eigen::Quaterniond newest = fixAttitude(last - 3) * motion(entry(last), rig.newest);
  ASSERT_LT(angleTo(rig.model.orientation(), newest), kTight);
  const std::size_t kept = std::min(applied, ap::kMaxFixesReapplied);
  const int oldest_kept = last - static_cast<int>(kept) + 1;
  rig.model.replayed.clear();

  if (applied > ap::kMaxFixesReapplied) {
    // Stamped before the forgotten fix: too old, nothing touched.
    EXPECT_EQ(rig.fix(entry(oldest_kept - 1) - 1, fixAttitude(40)), ap::FixOutcome::TooOld);
    EXPECT_TRUE(rig.model.replayed.empty());
  }
  // Stamped before every kept one (at the forgotten one's stamp, past the bound): applied, then
  // each kept fix again, in stamp order, each with its replay.
  const int earlier = applied > ap::kMaxFixesReapplied ? oldest_kept - 1 : 2;
  EXPECT_EQ(rig.fix(entry(earlier), fixAttitude(40)), ap::FixOutcome::Reset);
  std::vector<ap::Stamp> expected = entries(earlier + 1, 20);
  for (int e = oldest_kept; e <= last; ++e) {
    for (ap::Stamp s : entries(e + 1, 20)) expected.push_back(s);
  }
  EXPECT_EQ(rig.replayedStamps(), expected);
  EXPECT_LT(angleTo(rig.model.orientation(), newest), kTight);
}

INSTANTIATE_TEST_SUITE_P(FixReplay, FixesKeptUpToTheBound,
                         ::testing::Values(ap::kMaxFixesReapplied - 1, ap::kMaxFixesReapplied,
                                           ap::kMaxFixesReapplied + 1));

TEST(FixReplay, ALateMeasurementPlacedAtAnEntryIsKeptThereAndTheStepsAfterItReplayedOnce) {
  Rig rig(ap::FixMode::Fuse);
  const std::size_t kept = rig.replay.size();
  std::optional<ap::FixReplay::Placed> placed = rig.replay.place(entry(4));
  ASSERT_TRUE(placed.has_value());
  // The attitude at its stamp: the motion from the origin (the model set back there).
  EXPECT_LT(angleTo(placed->q, motion(kOrigin, entry(4))), kTight);
  auto m = std::make_shared<const ap::AttitudeFix>(fixAttitude(0),
                                                   1e-4 * Eigen::Matrix3d::Identity(), 1e9);
  ASSERT_TRUE(ap::fuseMeasurement(*m, placed->q, placed->e).accepted);
  const Eigen::Quaterniond fused = placed->q;
  rig.replay.applyPlaced(std::move(*placed), m, entry(4), false);
  EXPECT_EQ(rig.replay.size(), kept + 1);  // an entry of its own
  EXPECT_EQ(rig.replayedStamps(), entries(5, 10));
  // Applied once: the newest state is the fused attitude carried by the motion since.
  EXPECT_LT(angleTo(rig.model.orientation(), fused * motion(entry(4), rig.newest)), kTight);
}

TEST(FixReplay, ARefusedPlacementLeavesTheNewestStateAndTheAppliedFixes) {
  Rig rig;
  ASSERT_EQ(rig.fix(entry(8), fixAttitude(1)), ap::FixOutcome::Reset);
  const Eigen::Quaterniond newest = rig.model.orientation();
  std::optional<ap::FixReplay::Placed> placed = rig.replay.place(entry(4));
  ASSERT_TRUE(placed.has_value());
  rig.replay.dropPlaced(std::move(*placed));
  EXPECT_EQ(rig.model.orientation().coeffs(), newest.coeffs());
  // The fix at entry 8 is still kept: an earlier one is applied before it, and it again.
  ASSERT_EQ(rig.fix(entry(2), fixAttitude(0)), ap::FixOutcome::Reset);
  EXPECT_LT(angleTo(rig.model.orientation(), newest), kTight);
}

TEST(FixReplay, AMeasurementTooOldToPlaceTouchesNothing) {
  Rig rig(ap::FixMode::Reset, 0.05);  // entries 5..10 kept
  ASSERT_EQ(rig.fix(entry(8), fixAttitude(1)), ap::FixOutcome::Reset);
  const Eigen::Quaterniond newest = rig.model.orientation();
  EXPECT_FALSE(rig.replay.place(entry(5) - 1).has_value());
  EXPECT_EQ(rig.model.orientation().coeffs(), newest.coeffs());
  ASSERT_EQ(rig.fix(entry(6), fixAttitude(0)), ap::FixOutcome::Reset);
  EXPECT_LT(angleTo(rig.model.orientation(), newest), kTight);  // the fix at 8 applied again
}

TEST(FixReplay, AMeasurementAtTheNewestStateIsKeptAtThatStateNotAtItsOwnStamp) {
  Rig rig;
  EXPECT_TRUE(rig.replay.atNewest(rig.newest));
  EXPECT_FALSE(rig.replay.atNewest(rig.newest - 1));
  auto m = std::make_shared<const ap::AttitudeFix>(fixAttitude(0),
                                                   1e-4 * Eigen::Matrix3d::Identity(), 1e9);
  const ap::Stamp measured = rig.newest + 3'000'000;  // a sample stamped after the state
  rig.replay.keepAtNewest(m, measured, false);
  EXPECT_EQ(rig.replay.size(), 12u);
  EXPECT_TRUE(rig.replay.atNewest(rig.newest));
  EXPECT_FALSE(rig.replay.reaches(measured));
}

TEST(FixReplay, NothingKeptReachesNoStampAndAffordsAnyReplay) {
  ap::FixConfig config;
  ap::TimeBase time;
  LoggingModel model(time);
  ap::ErrorState error;
  struct Ignore : ap::StepCovariance {
    void followCovariance(const ap::ModelResult&) override {}
  } covariance;
  ap::FixReplay replay(config, time, model, error, covariance);
  EXPECT_EQ(replay.size(), 0u);
  EXPECT_FALSE(replay.reaches(kOrigin));
  EXPECT_FALSE(replay.atNewest(kOrigin));
  EXPECT_TRUE(replay.replayAffordable(kOrigin));
  replay.record(ap::ModelStep{}, true);  // an unanchored model has no state to keep
  EXPECT_EQ(replay.size(), 0u);
  Rig rig;
  rig.replay.clear();
  EXPECT_EQ(rig.replay.size(), 0u);
  EXPECT_EQ(rig.fix(entry(4), fixAttitude(0)), ap::FixOutcome::TooOld);
}
