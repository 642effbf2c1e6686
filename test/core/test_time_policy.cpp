// The time policy of docs/design.md §6: each input judged against its own source, never against
// the clock. Truths are the documented rules (a straggler is dropped, three stamps in a row from
// an earlier time are a jump, a stamp more than max_future ahead of the clock is refused, every
// published stamp once and in order) and closed forms (a constant rate about one axis turns the
// body by |w| t whatever the stamps' offset from the clock).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <map>
#include <optional>
#include <random>
#include <string>
#include <tuple>
#include <vector>

#include "attitude_propagator/config/parameters.h"
#include "attitude_propagator/engine.h"
#include "attitude_propagator/time/source_timeline.h"
#include "engine_fixtures.h"
#include "rotation_matchers.h"

namespace ap = attitude_propagator;
using namespace engine_fixtures;  // NOLINT: the fixtures are the tests' vocabulary
using Verdict = ap::SourceTimeline::Verdict;

namespace {

ap::Stamp ns(double seconds) { return static_cast<ap::Stamp>(std::llround(seconds * 1e9)); }

ap::TimePolicy policy() {
  ap::TimePolicy p;
  p.max_dt = 0.5;
  p.backward_jump = 1.0;
  return p;
}

/// A kinematic engine or a torque-free sphere turning at 0.2 rad/s about z that takes rates.
ap::EngineConfig rateConfig(bool dynamic) {
  if (!dynamic) return kinematicConfig();
  ap::EngineConfig c = spinningSphereConfig();
  c.dynamic->integrator = ap::Integrator::Rk4;
  return c;
}

const Eigen::Vector3d kSpin(0.0, 0.0, 0.2);

/// The watcher's rules for a published stream: within an epoch every stamp once and in order,
/// unit quaternion, finite. An epoch starts where time itself went back: the clock, or (the
/// kinematic model, whose stamps are the rates') a source's recognised jump.
struct Watcher : Recorder {
  bool kinematic = true;
  std::optional<ap::Stamp> last;
  std::size_t repeated_or_older = 0;
  std::size_t not_unit = 0;

  void publishState(const ap::EngineState& s) override {
    Recorder::publishState(s);
    if (last && s.stamp <= *last) ++repeated_or_older;
    if (!s.q_WB.coeffs().allFinite() || std::abs(s.q_WB.norm() - 1.0) > 1e-12 ||
        !s.w_B.allFinite()) {
      ++not_unit;
    }
    last = s.stamp;
  }
  void note(const ap::EngineNote& n) override {
    Recorder::note(n);
    const bool new_epoch = n.kind == ap::EngineNote::ClockJumpedBack ||
                           (kinematic && n.kind == ap::EngineNote::StampsJumpedBack);
    if (new_epoch) last.reset();
  }
};

}  // namespace

// ---------------------------------------------------------------------------------------------
// SourceTimeline: one source's order
// ---------------------------------------------------------------------------------------------

TEST(SourceTimeline, NewerStampsAreInOrderAndOlderOnesStragglersByAnyAmount) {
  ap::SourceTimeline line;
  EXPECT_EQ(line.judge(ns(10.0), policy()), Verdict::InOrder);
  EXPECT_EQ(line.judge(ns(10.01), policy()), Verdict::InOrder);
  EXPECT_EQ(line.judge(ns(10.01), policy()), Verdict::Straggler);  // repeated
  EXPECT_EQ(line.judge(ns(9.0), policy()), Verdict::Straggler);    // exactly the threshold back
  EXPECT_EQ(line.judge(ns(2.0), policy()), Verdict::Straggler);    // seconds back, once
  EXPECT_EQ(line.judge(ns(10.02), policy()), Verdict::InOrder);
  EXPECT_EQ(*line.newest(), ns(10.02));
}

TEST(SourceTimeline, ThreeInARowFromAnEarlierTimeAreAJump) {
  ap::SourceTimeline line;
  line.judge(ns(10.0), policy());
  ASSERT_EQ(ap::kJumpConfirmation, 3);
  EXPECT_EQ(line.judge(ns(2.0), policy()), Verdict::Straggler);
  EXPECT_EQ(line.judge(ns(2.1), policy()), Verdict::Straggler);
  EXPECT_EQ(line.judge(ns(2.2), policy()), Verdict::JumpedBack);
  EXPECT_EQ(*line.newest(), ns(2.2));
  EXPECT_EQ(line.judge(ns(2.3), policy()), Verdict::InOrder);
}

TEST(SourceTimeline, JustBeyondTheThresholdARunGoesOnAndAtItNot) {
  // Newest 10 s, threshold 1 s: 8.6 and 8.8 start a run; a third just beyond the threshold
  // completes it, a third exactly at it is a plain straggler that breaks it.
  ap::SourceTimeline beyond;
  beyond.judge(ns(10.0), policy());
  EXPECT_EQ(beyond.judge(ns(8.6), policy()), Verdict::Straggler);
  EXPECT_EQ(beyond.judge(ns(8.8), policy()), Verdict::Straggler);
  EXPECT_EQ(beyond.judge(ns(9.0) - 1, policy()), Verdict::JumpedBack);

  ap::SourceTimeline at_threshold;
  at_threshold.judge(ns(10.0), policy());
  at_threshold.judge(ns(8.6), policy());
  at_threshold.judge(ns(8.8), policy());
  EXPECT_EQ(at_threshold.judge(ns(9.0), policy()), Verdict::Straggler);
  EXPECT_EQ(at_threshold.judge(ns(8.85), policy()), Verdict::Straggler);  // a run of one again
  EXPECT_EQ(*at_threshold.newest(), ns(10.0));
}

TEST(SourceTimeline, ARunMustGoOnWithinMaxDt) {
  ap::SourceTimeline line;
  line.judge(ns(100.0), policy());
  EXPECT_EQ(line.judge(ns(1.0), policy()), Verdict::Straggler);
  EXPECT_EQ(line.judge(ns(1.5), policy()), Verdict::Straggler);      // exactly max_dt on: goes on
  EXPECT_EQ(line.judge(ns(2.0) + 1, policy()), Verdict::Straggler);  // beyond max_dt: run of one
  EXPECT_EQ(line.judge(ns(2.1), policy()), Verdict::Straggler);
  EXPECT_EQ(line.judge(ns(2.1), policy()), Verdict::Straggler);  // repeated: not on, run of one
  EXPECT_EQ(line.judge(ns(2.2), policy()), Verdict::Straggler);
  EXPECT_EQ(line.judge(ns(2.3), policy()), Verdict::JumpedBack);

  ap::SourceTimeline exact;
  exact.judge(ns(100.0), policy());
  exact.judge(ns(1.0), policy());
  exact.judge(ns(1.5), policy());
  EXPECT_EQ(exact.judge(ns(2.0), policy()), Verdict::JumpedBack);  // each step exactly max_dt
}

TEST(SourceTimeline, AnInOrderStampBreaksARun) {
  ap::SourceTimeline line;
  line.judge(ns(10.0), policy());
  line.judge(ns(2.0), policy());
  line.judge(ns(2.1), policy());
  EXPECT_EQ(line.judge(ns(10.1), policy()), Verdict::InOrder);
  EXPECT_EQ(line.judge(ns(2.2), policy()), Verdict::Straggler);
  EXPECT_EQ(line.judge(ns(2.3), policy()), Verdict::Straggler);
  EXPECT_EQ(line.judge(ns(2.4), policy()), Verdict::JumpedBack);
}

TEST(SourceTimeline, LagIsTheMeanOfClockMinusStamp) {
  ap::SourceTimeline line;
  EXPECT_FALSE(line.lag());
  line.observeLag(ns(101.5), ns(100.0));
  EXPECT_DOUBLE_EQ(*line.lag(), 1.5);  // the first observation is the mean
  // A constant skew stays the mean whatever the number of inputs; noise averages out.
  for (int k = 0; k < 1000; ++k) line.observeLag(ns(101.5 + k), ns(100.0 + k));
  EXPECT_NEAR(*line.lag(), 1.5, 1e-9);
  for (int k = 0; k < 1000; ++k) line.observeLag(ns(100.0 + k), ns(102.0 + k));
  EXPECT_NEAR(*line.lag(), -2.0, 1e-9);  // ahead of the clock: negative
}

// ---------------------------------------------------------------------------------------------
// Stragglers, skew, starved processes: the state never pays
// ---------------------------------------------------------------------------------------------

namespace {

/// Feeds 200 Hz rates about z for `seconds` with the sensor's clock `skew` seconds ahead of the
/// node's (negative: behind); each input arrives when the node's clock reads its stamp - skew.
void feedSkewed(ap::AttitudeEngine& engine, double skew, double seconds) {
  const int n = static_cast<int>(std::llround(seconds * 200));
  for (int k = 0; k <= n; ++k) {
    const double node_time = 0.005 * k;
    engine.poll(at(node_time));
    engine.submit(rate(at(node_time + skew), kSpin));
  }
}

}  // namespace

class SkewedSensorClock : public ::testing::TestWithParam<std::tuple<bool, double>> {};

TEST_P(SkewedSensorClock, NeverResetsNorRepeatsAStamp) {
  const auto [dynamic, skew] = GetParam();
  Watcher sink;
  sink.kinematic = !dynamic;
  ap::AttitudeEngine engine(rateConfig(dynamic), sink);
  feedSkewed(engine, skew, 5.0);
  const ap::EngineCounters& c = engine.counters();
  EXPECT_EQ(c.resets, 0u);
  EXPECT_EQ(sink.repeated_or_older, 0u);
  EXPECT_EQ(sink.not_unit, 0u);
  EXPECT_EQ(c.dropped_stale, 0u);
  if (skew > 1.0) {  // beyond max_future (1 s): every input refused, nothing published ahead
    EXPECT_EQ(c.rejected_future, 1001u);
    EXPECT_EQ(c.accepted, 0u);
    for (const auto& s : sink.states) EXPECT_LE(s.stamp, at(5.0 + 1.0));
    return;
  }
  for (int i = 0; i < 3; ++i) engine.poll(at(5.0 + std::max(skew, 0.0)));  // the queue's turn
  EXPECT_EQ(c.accepted, 1001u);
  EXPECT_NEAR(*engine.inputLag(ap::Source::Imu), -skew, 1e-9);
  // A constant rate (the sphere's own): the body turns by |w| t, t from the first stamp
  // (kinematic: 5 s of inputs) or from the clock's first grid stamp (dynamic).
  const ap::EngineState& s = sink.states.back();
  const double t = dynamic ? static_cast<double>(s.stamp - at(0.0)) * 1e-9 : 5.0;
  EXPECT_ROTATION_NEAR(s.q_WB, aboutAxis(kSpin, 0.2 * t), 1e-9);
  if (dynamic) {
    EXPECT_EQ(c.late, skew < 0.0 ? 1001u : 0u);
  }
}

INSTANTIATE_TEST_SUITE_P(Skews, SkewedSensorClock,
                         ::testing::Combine(::testing::Bool(), ::testing::Values(-100.0, -1.5, -0.5,
                                                                                 0.5, 1.5, 100.0)));

class StarvedProcess : public ::testing::TestWithParam<bool> {};

TEST_P(StarvedProcess, InputsQueuedDuringAFiveSecondStopAreAllUsed) {
  // SIGSTOP for 5 s under a 1 kHz stream: no callback runs; then the clock reads 5 s later
  // and the 5000 queued inputs arrive, in order, all behind it.
  const bool dynamic = GetParam();
  Watcher sink;
  sink.kinematic = !dynamic;
  ap::AttitudeEngine engine(rateConfig(dynamic), sink);
  int k = 0;
  for (; k <= 1000; ++k) {
    engine.poll(at(0.001 * k));
    engine.submit(rate(at(0.001 * k), kSpin));
  }
  const int resume = 6000;
  for (; k <= resume; ++k) {  // stopped from 1 s to 6 s: the clock is read only after
    engine.poll(at(0.001 * resume));
    engine.submit(rate(at(0.001 * k), kSpin));
  }
  for (; k <= 8000; ++k) {
    engine.poll(at(0.001 * k));
    engine.submit(rate(at(0.001 * k), kSpin));
  }
  for (int i = 0; i < 10; ++i) engine.poll(at(8.0));  // the grid catches up within its budget
  const ap::EngineCounters& c = engine.counters();
  EXPECT_EQ(c.resets, 0u);
  EXPECT_EQ(c.dropped_stale, 0u);
  EXPECT_EQ(c.accepted, 8001u);
  EXPECT_EQ(sink.repeated_or_older, 0u);
  EXPECT_EQ(sink.not_unit, 0u);
  EXPECT_EQ(sink.states.back().stamp, at(8.0));
  EXPECT_ROTATION_NEAR(sink.states.back().q_WB, aboutAxis(kSpin, 0.2 * 8.0), 1e-9);
}

INSTANTIATE_TEST_SUITE_P(Models, StarvedProcess, ::testing::Bool());

TEST(TimePolicyKinematic, OneStragglerSecondsOldIsDroppedAndTheStateDoesNotPay) {
  Watcher sink;
  ap::AttitudeEngine engine(kinematicConfig(), sink);
  for (int k = 0; k <= 200; ++k) {
    engine.submit(rate(at(0.01 * k), kSpin));
    if (k == 100) engine.submit(rate(at(0.01 * k - 10.0), kSpin));  // 10 s old, once
  }
  EXPECT_EQ(engine.counters().dropped_stale, 1u);
  EXPECT_EQ(engine.counters().resets, 0u);
  EXPECT_EQ(sink.repeated_or_older, 0u);
  EXPECT_ROTATION_NEAR(sink.states.back().q_WB, aboutAxis(kSpin, 0.2 * 2.0), 1e-12);
}

/// A rate that changes in every axis, so that no sample can be left out unnoticed.
Eigen::Vector3d varyingRate(double t) {
  return Eigen::Vector3d(0.3 * std::sin(2.0 * t), 0.2 + 0.1 * t, 0.5 * std::cos(3.0 * t));
}

TEST(TimePolicyKinematic, AfterAJumpBackTheStateIsAFreshStartOnTheNewStamps) {
  // A looped bag: 2 s of a stream, then its stamps 10 s back for 1 s. The inputs that confirm
  // the jump are integrated from the new anchor: the state is the one a fresh engine fed only
  // the new stamps has (the same origin, the same samples: to round-off).
  Watcher sink;
  ap::AttitudeEngine engine(kinematicConfig(), sink);
  Recorder fresh_sink;
  ap::AttitudeEngine fresh(kinematicConfig(), fresh_sink);
  for (int k = 0; k <= 200; ++k) engine.submit(rate(at(0.01 * k), varyingRate(0.01 * k)));
  for (int k = 201; k <= 300; ++k) {
    const double t = 0.01 * k - 10.0;
    engine.submit(rate(at(t), varyingRate(t)));
    fresh.submit(rate(at(t), varyingRate(t)));
  }
  EXPECT_EQ(engine.counters().jumps_back, 1u);
  EXPECT_EQ(engine.counters().dropped_stale, 0u);
  EXPECT_EQ(engine.counters().accepted, 301u);
  ASSERT_EQ(sink.states.back().stamp, fresh_sink.states.back().stamp);
  EXPECT_ROTATION_NEAR(sink.states.back().q_WB, fresh_sink.states.back().q_WB, 1e-15);
  EXPECT_EQ(sink.states.back().w_B, fresh_sink.states.back().w_B);

  // A constant rate: after the jump the body turned |w| times the new stamps' span.
  Watcher constant_sink;
  ap::AttitudeEngine constant(kinematicConfig(), constant_sink);
  for (int k = 0; k <= 200; ++k) constant.submit(rate(at(0.01 * k), kSpin));
  for (int k = 201; k <= 300; ++k) constant.submit(rate(at(0.01 * k - 10.0), kSpin));
  EXPECT_ROTATION_NEAR(constant_sink.states.back().q_WB, aboutAxis(kSpin, 0.2 * 0.99), 1e-12);
}

/// The parameter `time_jump_threshold` is the policy's backward_jump in both models: stamps
/// that go back by just less stay stragglers (dropped, no reset), by just more are one jump.
class TimeJumpThreshold : public ::testing::TestWithParam<bool> {};

TEST_P(TimeJumpThreshold, ParameterDecidesWhatIsAJumpOnEitherSide) {
  ap::Parameters p;
  p.time_jump_threshold = 5.0;
  if (GetParam()) {
    p.inertia = {1.0, 1.0, 1.0};
    p.integrator = "rk4";
  }
  const ap::EngineConfig config = ap::engineConfig(ap::validateParameters(p));
  for (const double back : {4.9, 5.1}) {
    Recorder sink;
    ap::AttitudeEngine engine(config, sink);
    for (int k = 0; k <= 800; ++k) engine.submit(rate(at(0.01 * k), kSpin));
    // From 8 s, the stamps go on `back` seconds earlier.
    for (int k = 801; k <= 900; ++k) engine.submit(rate(at(0.01 * k - back), kSpin));
    EXPECT_EQ(engine.counters().jumps_back, back > 5.0 ? 1u : 0u) << back;
    // (The dynamic model drops the inputs of the old timeline still queued for the grid when
    // a jump is recognised: counted too, so only the kinematic count is the stragglers'.)
    if (!GetParam()) {
      EXPECT_EQ(engine.counters().dropped_stale, back > 5.0 ? 0u : 100u) << back;
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Models, TimeJumpThreshold, ::testing::Bool());

TEST(TimeJumpThreshold, OutsideItsRangeIsRefusedAndItsEndsAccepted) {
  for (const double v : {0.0, 1e-4, 3600.5, std::nan(""), -1.0}) {
    ap::Parameters p;
    p.time_jump_threshold = v;
    EXPECT_THROW(ap::validateParameters(p), std::invalid_argument) << v;
  }
  for (const double v : {1e-3, 3600.0}) {
    ap::Parameters p;
    p.time_jump_threshold = v;
    EXPECT_EQ(ap::validateParameters(p).kinematic.time_policy.backward_jump, v);
  }
}

/// The run from an earlier time: kJumpConfirmation + offset inputs (offset -1, 0, +1), in the
/// kinematic model (false) and the dynamic one (true).
class JumpRuns : public ::testing::TestWithParam<std::tuple<bool, int>> {};

TEST_P(JumpRuns, ARunShortOfTheConfirmationIsDroppedAndAConfirmedOneIsKeptWhole) {
  const bool dynamic = std::get<0>(GetParam());
  const int m = ap::kJumpConfirmation + std::get<1>(GetParam());
  Watcher sink;
  sink.kinematic = !dynamic;
  ap::AttitudeEngine engine(rateConfig(dynamic), sink);
  for (int k = 0; k <= 100; ++k) {
    if (dynamic) engine.poll(at(0.01 * k));
    engine.submit(rate(at(0.01 * k), kSpin));
  }
  const std::size_t applied_before = sink.applied.size();
  for (int k = 0; k < m; ++k) engine.submit(rate(at(-9.0 + 0.01 * k), kSpin));
  const ap::EngineCounters& c = engine.counters();
  if (m < ap::kJumpConfirmation) {
    // Held until the next input of the old timeline breaks the run: then dropped as stale.
    EXPECT_EQ(c.dropped_stale, 0u);
    if (dynamic) engine.poll(at(1.01));
    engine.submit(rate(at(1.01), kSpin));
    if (dynamic) engine.poll(at(1.02));  // an input at the clock waits for its next look
    EXPECT_EQ(c.jumps_back, 0u);
    EXPECT_EQ(c.dropped_stale, static_cast<std::uint64_t>(m));
    EXPECT_EQ(c.accepted, 102u);
    EXPECT_EQ(sink.applied.size(), applied_before + 1);
    EXPECT_EQ(sink.applied.back().stamp, at(1.01));
    if (!dynamic) {
      EXPECT_ROTATION_NEAR(sink.states.back().q_WB, aboutAxis(kSpin, 0.2 * 1.01), 1e-12);
    }
    return;
  }
  // A jump: every input of the run is used, in order, none counted twice.
  EXPECT_EQ(c.jumps_back, 1u);
  EXPECT_EQ(c.dropped_stale, 0u);
  EXPECT_EQ(c.accepted, 101u + static_cast<std::uint64_t>(m));
  EXPECT_EQ(c.received, 101u + static_cast<std::uint64_t>(m));
  ASSERT_EQ(sink.applied.size(), applied_before + static_cast<std::size_t>(m));
  for (int k = 0; k < m; ++k)
    EXPECT_EQ(sink.applied[applied_before + k].stamp, at(-9.0 + 0.01 * k));
  if (dynamic) {
    EXPECT_EQ(c.resets, 0u);
    EXPECT_EQ(c.late, static_cast<std::uint64_t>(m));  // the clock stayed at 1.0 s
  } else {
    // From the initial state at the first of the run: 0.2 rad/s for (m - 1) periods.
    EXPECT_EQ(c.resets, 1u);
    EXPECT_EQ(sink.states.back().stamp, at(-9.0 + 0.01 * (m - 1)));
    EXPECT_ROTATION_NEAR(sink.states.back().q_WB, aboutAxis(kSpin, 0.2 * 0.01 * (m - 1)), 1e-15);
  }
  EXPECT_EQ(sink.repeated_or_older, 0u);
}

INSTANTIATE_TEST_SUITE_P(ModelsAndCounts, JumpRuns,
                         ::testing::Combine(::testing::Bool(), ::testing::Values(-1, 0, 1)));

TEST(TimePolicyDynamic, OneLateTorqueSecondsBehindTheClockActsNowAndNeverResets) {
  // A torque stamped 3 s before the clock (in order within its source): it acts from the last
  // knot, where the model can still change; the state is not reset and no stamp repeats.
  Watcher sink;
  sink.kinematic = false;
  ap::AttitudeEngine engine(torqueConfig(), sink);
  runClock(engine, 0.0, 5.0, 0.01);
  engine.submit(torque(at(2.0), Eigen::Vector3d(0.0, 0.0, 0.4)));
  runClock(engine, 5.0, 6.0, 0.01);
  const ap::EngineCounters& c = engine.counters();
  EXPECT_EQ(c.resets, 0u);
  EXPECT_EQ(c.late, 1u);
  EXPECT_EQ(sink.repeated_or_older, 0u);
  // From rest, I = 2: w = tau / I (t - t0), angle (tau / I) (t - t0)^2 / 2 from the knot 5.0.
  const ap::EngineState& s = sink.states.back();
  EXPECT_EQ(s.stamp, at(6.0));
  EXPECT_NEAR(s.w_B.z(), 0.2 * 1.0, 1e-12);
  EXPECT_ROTATION_NEAR(s.q_WB, aboutAxis(Eigen::Vector3d::UnitZ(), 0.1), 1e-9);
}

TEST(TimePolicyDynamic, APersistentJumpOfASourceGoesOnLateWithoutAReset) {
  Watcher sink;
  sink.kinematic = false;
  ap::AttitudeEngine engine(rateConfig(true), sink);
  for (int k = 0; k <= 200; ++k) {
    engine.poll(at(0.01 * k));
    engine.submit(rate(at(0.01 * k), kSpin));
  }
  // The driver restarts with its clock 10 s behind and stays there.
  for (int k = 201; k <= 400; ++k) {
    engine.poll(at(0.01 * k));
    engine.submit(rate(at(0.01 * k - 10.0), kSpin));
  }
  const ap::EngineCounters& c = engine.counters();
  EXPECT_EQ(c.jumps_back, 1u);
  EXPECT_EQ(c.resets, 0u);
  EXPECT_EQ(c.dropped_stale, 0u);  // the run that confirmed the jump goes on late too
  EXPECT_EQ(sink.repeated_or_older, 0u);
  EXPECT_ROTATION_NEAR(sink.states.back().q_WB, aboutAxis(kSpin, 0.2 * 4.0), 1e-9);
}

TEST(TimePolicyDynamic, AJumpDropsTheSourcesQueuedInputsFromTheOldTimeline) {
  Recorder sink;
  ap::AttitudeEngine engine(rateConfig(true), sink);
  engine.poll(at(1.0));
  for (int k = 1; k <= 5; ++k) engine.submit(rate(at(1.0 + 0.1 * k), kSpin));  // ahead: queued
  ASSERT_EQ(engine.pending(), 5u);
  for (int k = 0; k < ap::kJumpConfirmation; ++k) engine.submit(rate(at(-9.0 + 0.01 * k), kSpin));
  EXPECT_EQ(engine.counters().jumps_back, 1u);
  EXPECT_EQ(engine.pending(), 0u);
  EXPECT_EQ(engine.counters().dropped_stale, 5u);
  runClock(engine, 1.0, 2.0, 0.01);
  // Only the new timeline's inputs were applied, in order, none of the old queue after them.
  ASSERT_EQ(sink.applied.size(), static_cast<std::size_t>(ap::kJumpConfirmation));
  for (int k = 0; k < ap::kJumpConfirmation; ++k)
    EXPECT_EQ(sink.applied[k].stamp, at(-9.0 + 0.01 * k));
}

// ---------------------------------------------------------------------------------------------
// The future
// ---------------------------------------------------------------------------------------------

class FutureStamps : public ::testing::TestWithParam<bool> {};

TEST_P(FutureStamps, MoreThanMaxFutureAheadOfTheClockIsRefusedAtItAccepted) {
  const bool dynamic = GetParam();
  Watcher sink;
  sink.kinematic = !dynamic;
  ap::EngineConfig config = rateConfig(dynamic);
  config.max_future = 0.25;
  ap::AttitudeEngine engine(config, sink);
  engine.poll(at(1.0));
  engine.submit(rate(at(1.0), kSpin));
  engine.submit(rate(at(1.25) + 1, kSpin));  // 1 ns beyond
  EXPECT_EQ(engine.counters().rejected_future, 1u);
  engine.submit(rate(at(1.25), kSpin));  // exactly max_future ahead
  EXPECT_EQ(engine.counters().rejected_future, 1u);
  EXPECT_EQ(engine.counters().accepted + engine.pending(), 2u);  // dynamic: it waits
  engine.submit(rate(at(3601.0), kSpin));                        // an hour ahead
  EXPECT_EQ(engine.counters().rejected_future, 2u);
  for (const auto& s : sink.states) EXPECT_LE(s.stamp, at(1.25));
  // The next normal inputs go on as if the far one had never come.
  for (int k = 1; k <= 100; ++k) {
    engine.poll(at(1.25 + 0.01 * k));
    engine.submit(rate(at(1.25 + 0.01 * k), kSpin));
  }
  EXPECT_EQ(engine.counters().dropped_stale, 0u);
  EXPECT_EQ(engine.counters().resets, 0u);
  EXPECT_EQ(sink.repeated_or_older, 0u);
  if (!dynamic) {
    EXPECT_ROTATION_NEAR(sink.states.back().q_WB, aboutAxis(kSpin, 0.2 * 1.25), 1e-12);
  }
}

TEST_P(FutureStamps, SetStateBeyondMaxFutureIsRefusedWithTheReason) {
  const bool dynamic = GetParam();
  Recorder sink;
  ap::AttitudeEngine engine(rateConfig(dynamic), sink);
  const Eigen::Quaterniond q = aboutAxis(Eigen::Vector3d::UnitX(), 0.3);
  // No clock yet: nothing to compare with.
  EXPECT_EQ(engine.setState(at(100.0), q, kSpin), "");
  engine.poll(at(100.0));
  const std::string error = engine.setState(at(130.0), q, kSpin);
  EXPECT_NE(error.find("max_future"), std::string::npos) << error;
  EXPECT_EQ(engine.setState(at(101.0), q, kSpin), "");  // exactly max_future (1 s) ahead
  EXPECT_NE(engine.setState(at(101.0) + 1, q, kSpin), "");
}

TEST_P(FutureStamps, WithoutAClockNothingIsRefused) {
  Recorder sink;
  ap::AttitudeEngine engine(rateConfig(GetParam()), sink);
  engine.submit(rate(at(1e6), kSpin));
  EXPECT_EQ(engine.counters().rejected_future, 0u);
  EXPECT_EQ(engine.counters().accepted, 1u);
}

INSTANTIATE_TEST_SUITE_P(Models, FutureStamps, ::testing::Bool());

// One odd stamp never costs the state, whatever max_future allows (§6.5): an input on time for
// a second, then one 1.5 s or an hour ahead (within max_future), then on time again. The odd one
// is held (counted), no jump back, no reset: the body turns by |w| t about z as the on-time
// rates say, and nothing is published beyond the on-time stamps (tf never holds it).
TEST(TimePolicy, OneForwardGlitchWithinMaxFutureCostsNothing) {
  for (const double lead : {1.5, 3600.0}) {
    SCOPED_TRACE(lead);
    Watcher sink;
    ap::EngineConfig config = kinematicConfig();
    config.max_future = lead == 1.5 ? 2.0 : ap::kMaxFuture;
    ap::AttitudeEngine engine(config, sink);
    for (int k = 0; k <= 300; ++k) {
      const double t = 0.01 * k;
      engine.poll(at(t));
      if (k == 100) engine.submit(rate(at(t + lead), kSpin));
      engine.submit(rate(at(t), kSpin));
    }
    EXPECT_EQ(engine.counters().held_ahead, 1u);
    EXPECT_EQ(engine.counters().jumps_back, 0u);
    EXPECT_EQ(engine.counters().resets, 0u);
    EXPECT_EQ(engine.counters().accepted, 301u);
    const Eigen::Quaterniond truth = aboutAxis(Eigen::Vector3d::UnitZ(), 0.2 * 3.0);
    EXPECT_LE(ap::rotationAngle(engine.state().q_WB, truth), 1e-12);
    for (const auto& s : sink.states) EXPECT_LE(s.stamp, at(3.0));
  }
}

// A stream far behind the clock (a replayed base, a sensor clock of its own) that resumes
// later after a pause, or on a new base after a reset, but still behind the clock, is a gap,
// not a glitch: nothing is held, and the first input after it is taken (design.md §6 table).
TEST(TimePolicy, AStreamResumingLaterButBehindTheClockIsAGapNotAGlitch) {
  Watcher sink;
  ap::EngineConfig config = kinematicConfig();
  config.max_future = 2.0;
  ap::AttitudeEngine engine(config, sink);
  const double behind = 5000.0;  // the clock runs this far ahead of the stamps
  for (int k = 0; k <= 100; ++k) {
    engine.poll(at(behind + 0.01 * k));
    engine.submit(rate(at(0.01 * k), kSpin));
  }
  // 900 s later on the stream's own time, 1 s later on the clock: still 4100 s behind it.
  for (int k = 0; k <= 100; ++k) {
    engine.poll(at(behind + 2.0 + 0.01 * k));
    engine.submit(rate(at(900.0 + 0.01 * k), kSpin));
  }
  EXPECT_EQ(engine.counters().held_ahead, 0u);
  EXPECT_EQ(engine.counters().accepted, 202u);
}

// A source whose stamps move ahead of the clock for good (a sensor clock stepped forward) is
// followed once kJumpConfirmation inputs in a row go on from there; until then each is held.
TEST(TimePolicy, ALeadThatPersistsIsTheSourcesNewLead) {
  Watcher sink;
  ap::EngineConfig config = kinematicConfig();
  config.max_future = 10.0;
  ap::AttitudeEngine engine(config, sink);
  for (int k = 0; k <= 100; ++k) {
    engine.poll(at(0.01 * k));
    engine.submit(rate(at(0.01 * k), kSpin));
  }
  for (int k = 1; k <= 100; ++k) {
    const double t = 1.0 + 0.01 * k;
    engine.poll(at(t));
    engine.submit(rate(at(t + 5.0), kSpin));
    if (k < ap::kJumpConfirmation) {
      EXPECT_EQ(engine.counters().held_ahead, std::uint64_t(k));
    }
  }
  EXPECT_EQ(engine.counters().held_ahead, std::uint64_t(ap::kJumpConfirmation - 1));
  EXPECT_EQ(engine.counters().accepted, 101u + 100u - (ap::kJumpConfirmation - 1));
  EXPECT_EQ(engine.counters().resets, 0u);
}

TEST(TimePolicy, MaxFutureOutsideItsRangeIsRefused) {
  Recorder sink;
  // A time: non-positive is refused (docs/parameters.md).
  for (double bad : {0.0, -1e-9, ap::kMaxFuture * (1 + 1e-12), double(NAN), double(INFINITY)}) {
    ap::EngineConfig config = kinematicConfig();
    config.max_future = bad;
    EXPECT_THROW(ap::AttitudeEngine(config, sink), std::invalid_argument) << bad;
  }
  for (double good : {1e-9, ap::kMaxFuture}) {
    ap::EngineConfig config = kinematicConfig();
    config.max_future = good;
    EXPECT_NO_THROW(ap::AttitudeEngine(config, sink)) << good;
  }
}

// ---------------------------------------------------------------------------------------------
// Reconfigure, set_state and reset keep the input history
// ---------------------------------------------------------------------------------------------

TEST(TimePolicyDynamic, ATorqueInTransitDuringAReconfigureIsStillNewer) {
  Recorder sink;
  ap::AttitudeEngine engine(torqueConfig(), sink);
  runClock(engine, 0.0, 1.0, 0.01);
  engine.submit(torque(at(1.0), Eigen::Vector3d(0.0, 0.0, 0.2)));
  runClock(engine, 1.0, 1.5, 0.01);
  ap::EngineConfig next = torqueConfig();
  next.dynamic->integrator = ap::Integrator::Dopri5;
  ASSERT_EQ(engine.reconfigure(next), "");
  engine.submit(torque(at(1.2), Eigen::Vector3d(0.0, 0.0, 0.4)));  // stamped before, arrives now
  EXPECT_EQ(engine.counters().dropped_stale, 0u);
  EXPECT_EQ(engine.counters().late, 1u);
  // From 1.5 on the new torque acts: w = 0.1 (1.0..1.5) + 0.2 (1.5..2.0) over I = 2.
  runClock(engine, 1.5, 2.0, 0.01);
  EXPECT_NEAR(sink.states.back().w_B.z(), 0.1 * 0.5 + 0.2 * 0.5, 1e-9);
}

TEST(TimePolicyKinematic, AfterSetStateAndAReconfigureOlderRatesAreNeverAppliedAfterNewerOnes) {
  Recorder sink;
  ap::AttitudeEngine engine(kinematicConfig(), sink);
  for (int k = 0; k <= 100; ++k) engine.submit(rate(at(0.01 * k), kSpin));
  ASSERT_EQ(engine.setState(at(0.5), Eigen::Quaterniond::Identity(), kSpin), "");
  ap::EngineConfig next = kinematicConfig();
  next.kinematic.integrator = ap::Integrator::Rk4;
  ASSERT_EQ(engine.reconfigure(next), "");
  for (int k = 60; k <= 120; ++k) engine.submit(rate(at(0.01 * k + 0.001), kSpin));  // queued
  for (std::size_t i = 1; i < sink.applied.size(); ++i) {
    EXPECT_GT(sink.applied[i].stamp, sink.applied[i - 1].stamp) << i;
  }
  EXPECT_TRUE(sink.stampsIncrease());
}

TEST(TimePolicyDynamic, ResetCountsTheQueuedInputsItDrops) {
  Recorder sink;
  ap::AttitudeEngine engine(torqueConfig(), sink);
  runClock(engine, 0.0, 1.0, 0.01);
  for (int k = 1; k <= 7; ++k) engine.submit(torque(at(1.0 + 0.1 * k), Eigen::Vector3d::UnitX()));
  ASSERT_EQ(engine.pending(), 7u);
  engine.reset();
  EXPECT_EQ(engine.pending(), 0u);
  EXPECT_EQ(engine.counters().dropped_on_reset, 7u);
  EXPECT_EQ(engine.counters().received,
            engine.counters().accepted + engine.counters().dropped_on_reset);
}

// ---------------------------------------------------------------------------------------------
// Every stamp once, in order: random inputs, clocks, reconfigures, set_state and reset
// ---------------------------------------------------------------------------------------------

class RandomTimelines : public ::testing::TestWithParam<bool> {};

TEST_P(RandomTimelines, EveryPublishedStampOnceInOrderUnitAndNeverBeyondMaxFuture) {
  const bool dynamic = GetParam();
  std::mt19937_64 random(20261202);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  Watcher sink;
  sink.kinematic = !dynamic;
  const ap::EngineConfig config = dynamic ? torqueConfig() : kinematicConfig();
  ap::AttitudeEngine engine(config, sink);
  double clock = 100.0;
  double engine_clock = clock;  // the engine's: jitter back within the threshold is ignored
  double offset = 0.0;          // the sensor clock's, changed by a driver restart
  engine.clockTick(at(clock));
  std::size_t checked = 0;
  for (int step = 0; step < 20000; ++step) {
    const double u = unit(random);
    if (u < 0.45) {  // the stream: latency, stragglers, stamps far ahead, a restarted driver
      const double v = unit(random);
      if (v > 0.997) offset -= 20.0;
      double stamp = clock + offset - 0.02 * unit(random);
      if (v < 0.03) stamp -= 5.0 * unit(random);
      if (v > 0.98 && v <= 0.997) stamp += 10.0 * unit(random);
      const Eigen::Vector3d value(unit(random) - 0.5, unit(random) - 0.5, unit(random) - 0.5);
      engine.submit(dynamic && unit(random) < 0.5 ? torque(at(stamp), value)
                                                  : rate(at(stamp), value));
    } else if (u < 0.9) {  // the clock: forward, jitter back, rarely a loop back or a jump
      const double v = unit(random);
      clock += v < 0.02 ? -0.5 * unit(random) : 0.01 * unit(random);
      if (v > 0.999) clock -= 30.0;
      if (v > 0.997 && v <= 0.999) clock += 3.0;
      engine_clock = clock < engine_clock - 1.0 ? clock : std::max(engine_clock, clock);
      if (v < 0.5) {
        engine.clockTick(at(clock));
      } else {
        engine.poll(at(clock));
      }
    } else if (u < 0.93) {
      ap::EngineConfig next = config;
      const bool second = unit(random) < 0.5;
      if (dynamic) {
        next.dynamic->integrator = second ? ap::Integrator::Dopri5 : ap::Integrator::Rk4;
      } else {
        next.kinematic.integrator = second ? ap::Integrator::Rk4 : ap::Integrator::Cf4;
      }
      EXPECT_EQ(engine.reconfigure(next), "");
    } else if (u < 0.96) {
      engine.setState(at(clock + 2.0 * (unit(random) - 0.8)),
                      aboutAxis(Eigen::Vector3d(unit(random), 1.0, unit(random)), unit(random)),
                      Eigen::Vector3d::Zero());
    } else if (u < 0.97) {
      engine.reset();
    } else {
      engine.drain();
    }
    for (; checked < sink.states.size(); ++checked) {
      EXPECT_LE(sink.states[checked].stamp, at(engine_clock + config.max_future)) << step;
    }
  }
  EXPECT_EQ(sink.repeated_or_older, 0u);
  EXPECT_EQ(sink.not_unit, 0u);
  EXPECT_EQ(engine.counters().received,
            engine.counters().accepted + engine.counters().dropped_stale +
                engine.counters().rejected_future + engine.counters().dropped_on_reset +
                engine.pending() + engine.counters().rejected_out_of_range +
                engine.counters().rejected_non_finite + engine.counters().pending_overflow +
                engine.counters().held_ahead);
  // The run publishes throughout. A kinematic stream 20 s behind a set_state pinned at ROS time
  // stays stale until its stamps jump back; a forward glitch is held (held_ahead) and no longer
  // causes such a jump back, so fewer states than the 1000 of before come out.
  EXPECT_GT(sink.states.size(), 400u)
      << "held_ahead " << engine.counters().held_ahead << ", resets " << engine.counters().resets
      << ", jumps_back " << engine.counters().jumps_back << ", accepted "
      << engine.counters().accepted << ", stale " << engine.counters().dropped_stale << ", future "
      << engine.counters().rejected_future;
}

INSTANTIATE_TEST_SUITE_P(Models, RandomTimelines, ::testing::Bool());

// ---------------------------------------------------------------------------------------------
// ClockTimeline: ROS time's own timeline, and two taking turns (two /clock publishers)
// ---------------------------------------------------------------------------------------------

namespace {

using ClockVerdict = ap::ClockTimeline::Verdict;

/// Counts of each verdict over a run of ticks, and whether the clock followed ever went back
/// after two timelines were recognised.
struct ClockRun {
  std::map<ClockVerdict, int> verdicts;
  int followed_back_after_two = 0;

  void tick(ap::ClockTimeline& clock, double t) {
    const std::optional<ap::Stamp> before = clock.now();
    const ClockVerdict v = clock.judge(ns(t), policy());
    ++verdicts[v];
    if (verdicts[ClockVerdict::TwoTimelines] > 0 && before && *clock.now() < *before &&
        v != ClockVerdict::JumpedBack) {
      ++followed_back_after_two;
    }
  }
  int count(ClockVerdict v) const { return verdicts.count(v) ? verdicts.at(v) : 0; }
};

}  // namespace

TEST(ClockTimeline, ALoopedClockJumpsBackOnceAndGoesOnWithoutASecondTimeline) {
  ap::ClockTimeline clock;
  ClockRun run;
  for (int k = 0; k <= 300; ++k) run.tick(clock, 100.0 + 0.01 * k);  // 100 .. 103
  for (int k = 0; k <= 800; ++k) run.tick(clock, 95.0 + 0.01 * k);   // looped: 95 .. 103
  EXPECT_EQ(run.count(ClockVerdict::JumpedBack), 1);
  EXPECT_EQ(run.count(ClockVerdict::TwoTimelines), 0);
  EXPECT_EQ(run.count(ClockVerdict::OtherTimeline), 0);
  EXPECT_FALSE(clock.other());
}

/// Two /clock publishers 5 s apart, each at 100 Hz, ticks interleaved; `later_first`: the later
/// timeline ticks first.
class TwoClockPublishers : public ::testing::TestWithParam<bool> {};

TEST_P(TwoClockPublishers, CostOneJumpBackAtMostAndTheLaterTimelineIsFollowed) {
  ap::ClockTimeline clock;
  ClockRun run;
  const bool later_first = GetParam();
  for (int k = 0; k < 300; ++k) {  // 3 s of each
    const double later = 100.0 + 0.01 * k, earlier = 95.0 + 0.01 * k;
    run.tick(clock, later_first ? later : earlier);
    run.tick(clock, later_first ? earlier : later);
  }
  EXPECT_EQ(run.count(ClockVerdict::JumpedBack), 1);
  EXPECT_EQ(run.count(ClockVerdict::TwoTimelines), 1);
  EXPECT_EQ(run.followed_back_after_two, 0);
  EXPECT_EQ(*clock.now(), ns(100.0 + 0.01 * 299));
  ASSERT_TRUE(clock.other());
  EXPECT_EQ(*clock.other(), ns(95.0 + 0.01 * 299));
}

INSTANTIATE_TEST_SUITE_P(EitherFirst, TwoClockPublishers, ::testing::Bool());

TEST(ClockTimeline, ASlowSecondPublisherIsRecognisedToo) {
  // A stale simulator at 1 Hz, 5 s behind a bag at 100 Hz.
  ap::ClockTimeline clock;
  ClockRun run;
  for (int k = 0; k < 1000; ++k) {
    run.tick(clock, 100.0 + 0.01 * k);
    if (k % 100 == 50) run.tick(clock, 95.0 + 0.01 * k);
  }
  EXPECT_EQ(run.count(ClockVerdict::JumpedBack), 1);
  EXPECT_EQ(run.count(ClockVerdict::TwoTimelines), 1);
  // Ten ticks of the slow one: the first is the jump back, the other nine are ignored.
  EXPECT_EQ(run.count(ClockVerdict::OtherTimeline), 9);
  EXPECT_EQ(run.followed_back_after_two, 0);
}

TEST(ClockTimeline, SettlesWhenTheOtherFallsSilentAndThenAJumpBackCountsAgain) {
  ap::ClockTimeline clock;
  ClockRun run;
  for (int k = 0; k < 100; ++k) {
    run.tick(clock, 100.0 + 0.01 * k);
    run.tick(clock, 95.0 + 0.01 * k);
  }
  ASSERT_EQ(run.count(ClockVerdict::TwoTimelines), 1);
  // The earlier publisher stops; the later goes on for more than kClockSettle.
  const double settled = 101.0 + ap::kClockSettle + 0.5;
  for (double t = 101.0; t <= settled; t += 0.01) run.tick(clock, t);
  EXPECT_FALSE(clock.other());
  // A genuine loop after that: time starts again.
  EXPECT_EQ(clock.judge(ns(50.0), policy()), ClockVerdict::JumpedBack);
}

TEST(ClockTimeline, WhenTheFollowedFallsSilentTheOtherIsTakenWithOneJumpBack) {
  // 20 s apart: the later publisher stops, the earlier goes on; it is taken once it went on for
  // more than kClockSettle without a tick of the followed one.
  ap::ClockTimeline clock;
  ClockRun run;
  for (int k = 0; k < 100; ++k) {
    run.tick(clock, 120.0 + 0.01 * k);
    run.tick(clock, 100.0 + 0.01 * k);
  }
  ASSERT_EQ(run.count(ClockVerdict::JumpedBack), 1);
  ASSERT_EQ(run.count(ClockVerdict::TwoTimelines), 1);
  int back = 0;
  std::optional<ap::Stamp> back_at;
  for (int k = 100; k <= 100 + 1000; ++k) {
    const double t = 100.0 + 0.01 * k;
    if (clock.judge(ns(t), policy()) == ClockVerdict::JumpedBack) {
      ++back;
      back_at = ns(t);
    }
  }
  EXPECT_EQ(back, 1);
  ASSERT_TRUE(back_at);
  // From the other's first tick since the followed one's last: 100.99.
  EXPECT_GT(*back_at - ns(100.99), ns(ap::kClockSettle));
  EXPECT_LE(*back_at - ns(100.99), ns(ap::kClockSettle + 0.02));
  EXPECT_FALSE(clock.other());
  EXPECT_EQ(*clock.now(), ns(111.0));
}

TEST(ClockTimeline, WhenTheFollowedFallsSilentACloseOtherCatchesUpWithoutAJump) {
  // 5 s apart: the clock followed stays at the later publisher's last tick until the earlier
  // timeline reaches it (within backward_jump: jitter), then goes on with it; never back. It
  // has settled kClockSettle after the other's last tick behind (100.99).
  ap::ClockTimeline clock;
  ClockRun run;
  for (int k = 0; k < 100; ++k) {
    run.tick(clock, 100.0 + 0.01 * k);
    run.tick(clock, 95.0 + 0.01 * k);
  }
  for (int k = 100; k <= 1000; ++k) run.tick(clock, 95.0 + 0.01 * k);
  EXPECT_EQ(*clock.now(), ns(105.0));
  EXPECT_TRUE(clock.other());  // not settled yet
  for (int k = 1001; k <= 1200; ++k) run.tick(clock, 95.0 + 0.01 * k);
  EXPECT_EQ(run.count(ClockVerdict::JumpedBack), 1);  // the first, before two were known
  EXPECT_EQ(run.followed_back_after_two, 0);
  EXPECT_FALSE(clock.other());
}

TEST(ClockTimeline, AForwardJumpLongAfterALoopIsAGapNotASecondTimeline) {
  ap::ClockTimeline clock;
  for (double t = 100.0; t < 101.0; t += 0.01) clock.judge(ns(t), policy());
  EXPECT_EQ(clock.judge(ns(50.0), policy()), ClockVerdict::JumpedBack);
  for (double t = 50.0; t < 50.0 + ap::kClockSettle + 1.0; t += 0.01) clock.judge(ns(t), policy());
  EXPECT_EQ(clock.judge(ns(101.0), policy()), ClockVerdict::Ahead);
}

TEST(TimePolicy, TwoClockPublishersCostOneResetAndStampsGoBackOnce) {
  // Both models: 3 s of two /clock publishers 5 s apart at 100 Hz each, rates stamped on the
  // later timeline (the kinematic model's time).
  for (const bool dynamic : {false, true}) {
    Watcher sink;
    sink.kinematic = !dynamic;
    ap::AttitudeEngine engine(rateConfig(dynamic), sink);
    int back_notes = 0;
    std::vector<ap::Stamp> two_timelines;  // the ClockTwoTimelines notes' stamps
    for (int k = 0; k < 300; ++k) {
      engine.clockTick(at(100.0 + 0.01 * k));
      engine.clockTick(at(95.0 + 0.01 * k));
      engine.submit(rate(at(100.0 + 0.01 * k), kSpin));
    }
    for (const ap::EngineNote& n : sink.notes) {
      back_notes += n.kind == ap::EngineNote::ClockJumpedBack;
      if (n.kind == ap::EngineNote::ClockTwoTimelines) two_timelines.push_back(n.stamp);
    }
    // One note, with the clock and a stamp of the other timeline (the earlier one, 5 s behind).
    ASSERT_EQ(two_timelines.size(), 1u) << dynamic;
    EXPECT_LT(two_timelines[0], at(99.0)) << dynamic;
    EXPECT_GE(two_timelines[0], at(95.0)) << dynamic;
    const ap::EngineCounters& c = engine.counters();
    EXPECT_LE(c.resets, 1u) << dynamic;
    EXPECT_LE(back_notes, 1) << dynamic;
    EXPECT_EQ(c.clock_conflicts, 1u) << dynamic;
    // Refused only while the earlier timeline is followed: between its jump back and the next
    // tick of the later one, the input ticked before it.
    EXPECT_LE(c.rejected_future, 1u) << dynamic;
    EXPECT_EQ(sink.repeated_or_older, 0u) << dynamic;  // within the one epoch after the reset
    ASSERT_TRUE(engine.otherClock());
    EXPECT_EQ(*engine.otherClock(), at(95.0 + 0.01 * 299));
    ASSERT_FALSE(sink.states.empty());
    EXPECT_GE(sink.states.back().stamp, at(102.9));
  }
}
