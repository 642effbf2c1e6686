// Every bounded queue of the core at its capacity and one past it, and every count the docs
// state about the core: what is kept, what is dropped, and how each is counted. The truths are
// the documented rules (docs/design.md §5.3, §6.5, §6.9, §7.6; docs/numerics.md §3;
// docs/real_streams.md), never a number the code produced before.
#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "attitude_propagator/engine.h"
#include "attitude_propagator/limits.h"
#include "attitude_propagator/models/kinematic_propagator.h"
#include "attitude_propagator/time/source_timeline.h"
#include "attitude_propagator/time/stamp_filter.h"
#include "engine_fixtures.h"

namespace {

namespace ap = attitude_propagator;
using engine_fixtures::aboutAxis;
using engine_fixtures::at;
using engine_fixtures::kSecond;
using engine_fixtures::Recorder;

ap::Input rateAt(ap::Stamp stamp, const Eigen::Vector3d& w_B = Eigen::Vector3d::Zero()) {
  return engine_fixtures::rate(stamp, w_B);
}

ap::Input torqueAt(ap::Stamp stamp) {
  return engine_fixtures::torque(stamp, Eigen::Vector3d(0.0, 0.0, 0.1));
}

std::vector<ap::Stamp> appliedStamps(const Recorder& sink, ap::Source source) {
  std::vector<ap::Stamp> stamps;
  for (const ap::Input& in : sink.applied) {
    if (in.source == source) stamps.push_back(in.stamp);
  }
  return stamps;
}

// ---- The dynamic input queue (§5.3, §7.6) ----------------------------------------------------

TEST(Queues, DynamicQueueAtCapacityAndOnePast) {
  // max_pending inputs wait; one more drops the input stamped furthest ahead (the newcomer,
  // or the furthest queued one), counted pending_overflow. (The nearer newcomer is a rate: an
  // input is judged against its own source first, and 1.9 s was the torques' newest.)
  ap::EngineConfig c = engine_fixtures::torqueConfig();
  c.max_pending = 4;
  Recorder sink;
  ap::AttitudeEngine engine(c, sink);
  engine.clockTick(at(1.0));
  for (double t : {1.5, 1.6, 1.7, 1.8}) engine.submit(torqueAt(at(t)));
  EXPECT_EQ(engine.pending(), 4u);
  EXPECT_EQ(engine.counters().pending_overflow, 0u);
  engine.submit(torqueAt(at(1.9)));  // the furthest ahead: itself dropped
  EXPECT_EQ(engine.pending(), 4u);
  EXPECT_EQ(engine.counters().pending_overflow, 1u);
  engine.submit(rateAt(at(1.55)));  // nearer: 1.8 dropped
  EXPECT_EQ(engine.pending(), 4u);
  EXPECT_EQ(engine.counters().pending_overflow, 2u);
  engine_fixtures::runClock(engine, 1.0, 2.0, 0.02);
  EXPECT_EQ(appliedStamps(sink, ap::Source::Torque),
            (std::vector<ap::Stamp>{at(1.5), at(1.6), at(1.7)}));
  EXPECT_EQ(appliedStamps(sink, ap::Source::Imu), (std::vector<ap::Stamp>{at(1.55)}));
  // Every input accounted for once.
  const ap::EngineCounters& n = engine.counters();
  EXPECT_EQ(n.received, 6u);
  EXPECT_EQ(n.accepted + n.pending_overflow, n.received);
}

TEST(Queues, DynamicQueueHoldsTheDocumented4096) {
  // §7.6: 4096 inputs ahead of the clock.
  Recorder sink;
  ap::AttitudeEngine engine(engine_fixtures::torqueConfig(), sink);
  EXPECT_EQ(engine.config().max_pending, 4096u);
  engine.clockTick(at(1.0));
  for (int k = 1; k <= 4096; ++k) engine.submit(torqueAt(at(1.0) + k * 100000));
  EXPECT_EQ(engine.pending(), 4096u);
  EXPECT_EQ(engine.counters().pending_overflow, 0u);
  engine.submit(torqueAt(at(1.0) + 4097 * 100000));
  EXPECT_EQ(engine.pending(), 4096u);
  EXPECT_EQ(engine.counters().pending_overflow, 1u);
}

TEST(Queues, ResetDropsTheQueueAndTheHeldTorque) {
  // §5.5: a reset drops the waiting inputs (dropped_on_reset) and goes back to the initial
  // state (at rest): nothing of the torque before it acts after it, not even through a
  // reconfiguration, which restores only a torque held since the anchor.
  Recorder sink;
  ap::AttitudeEngine engine(engine_fixtures::torqueConfig(), sink);
  engine.clockTick(at(1.0));
  engine.submit(engine_fixtures::torque(at(1.0), Eigen::Vector3d(0.0, 0.0, 2.0)));
  engine.submit(torqueAt(at(1.5)));
  engine.submit(torqueAt(at(1.6)));
  engine_fixtures::runClock(engine, 1.0, 1.2, 0.02);
  EXPECT_GT(engine.state().w_B.norm(), 0.1);  // 1 rad/s^2 for 0.2 s
  engine.reset();
  EXPECT_EQ(engine.counters().dropped_on_reset, 2u);
  EXPECT_EQ(engine.pending(), 0u);
  engine_fixtures::runClock(engine, 1.2, 1.3, 0.02);
  EXPECT_EQ(engine.reconfigure(engine.config()), "");
  engine_fixtures::runClock(engine, 1.3, 2.0, 0.02);
  EXPECT_EQ(engine.state().w_B.norm(), 0.0);
  EXPECT_LT(engine.state().q_WB.angularDistance(Eigen::Quaterniond::Identity()), 1e-15);
}

TEST(Queues, AJumpBackOfASourceDropsItsQueuedInputsAsStale) {
  // §6.5, dynamic model: the third stamp from an earlier time is a jump; the two before it go on
  // before it as late inputs, the queued inputs of the old timeline are dropped (dropped_stale);
  // no reset, so nothing is counted dropped_on_reset. Every input is counted once.
  Recorder sink;
  ap::AttitudeEngine engine(engine_fixtures::torqueConfig(), sink);
  engine_fixtures::runClock(engine, 9.0, 10.0, 0.02);
  engine.submit(torqueAt(at(10.5)));
  engine.submit(torqueAt(at(10.6)));
  EXPECT_EQ(engine.pending(), 2u);
  for (double t : {5.0, 5.01, 5.02}) engine.submit(torqueAt(at(t)));
  const ap::EngineCounters& n = engine.counters();
  EXPECT_EQ(n.jumps_back, 1u);
  EXPECT_EQ(n.resets, 0u);
  EXPECT_EQ(engine.pending(), 0u);
  EXPECT_EQ(n.dropped_on_reset, 0u);
  EXPECT_EQ(n.dropped_stale, 2u);  // the two queued
  EXPECT_EQ(n.accepted, 3u);       // the run, late inputs
  EXPECT_EQ(n.received, 5u);
}

// ---- Bounded work per call (§7.6) ------------------------------------------------------------

TEST(Queues, GridBudgetIsTheDocumented1000StampsPerCall) {
  Recorder sink;
  ap::AttitudeEngine engine(engine_fixtures::torqueConfig(), sink);  // 50 Hz
  EXPECT_EQ(engine.config().grid_budget, 1000u);
  engine.poll(at(1.0));
  std::size_t before = sink.states.size();
  engine.poll(at(31.0));  // 1500 grid stamps due
  EXPECT_EQ(sink.states.size() - before, 1000u);
  EXPECT_EQ(engine.counters().deferred_ticks, 1u);
  before = sink.states.size();
  engine.drain();
  EXPECT_EQ(sink.states.size() - before, 500u);
  EXPECT_EQ(sink.states.back().stamp, at(31.0));
  EXPECT_EQ(engine.counters().deferred_ticks, 1u);
  EXPECT_TRUE(sink.stampsIncrease());
}

TEST(Queues, WorkBudgetStopsACallAtItsUnits) {
  // §7.6: a call stops at the first grid stamp at which the integrator work summed over its
  // grid stamps (one unit per fixed step of rk4: the steps each published state reports)
  // reaches work_budget; the rest waits for the next call (deferred_ticks).
  ap::EngineConfig c = engine_fixtures::torqueConfig();
  c.work_budget = 10;
  Recorder sink;
  ap::AttitudeEngine engine(c, sink);
  engine.poll(at(1.0));
  std::size_t deferred = 0;
  for (int call = 0; sink.states.back().stamp < at(2.0); ++call) {
    ASSERT_LT(call, 50);
    const std::size_t before = sink.states.size();
    const std::uint64_t steps_before = sink.states.back().steps;
    if (call == 0) {
      engine.poll(at(2.0));  // 50 grid stamps due
    } else {
      engine.drain();
    }
    ASSERT_GT(sink.states.size(), before);
    const std::uint64_t spent = sink.states.back().steps - steps_before;
    const std::uint64_t before_last = sink.states[sink.states.size() - 2].steps - steps_before;
    if (sink.states.back().stamp < at(2.0)) {
      ++deferred;
      EXPECT_GE(spent, 10u) << call;        // stopped only once the budget was reached
      EXPECT_LT(before_last, 10u) << call;  // and no earlier
    } else {
      EXPECT_LE(before_last, 10u) << call;
    }
  }
  EXPECT_GE(deferred, 4u);  // 50 grid stamps of at least one unit each
  EXPECT_EQ(engine.counters().deferred_ticks, deferred);
  EXPECT_TRUE(sink.stampsIncrease());
}

// ---- The pending gyro bias samples (§7.6) ----------------------------------------------------

TEST(Queues, BiasQueueOf64NoneTakesEffectBeforeItsStamp) {
  // Full, the sample stamped furthest ahead is dropped (bias_queue_full): the newcomer when it
  // is, else the furthest waiting one. None is applied before a rate reaches its stamp.
  Recorder sink;
  ap::AttitudeEngine engine(engine_fixtures::kinematicConfig(), sink);
  engine.submit(rateAt(at(1.0)));
  static_assert(ap::kMaxPendingBias == 64, "the stamps below count 64 waiting");
  for (int k = 1; k <= 64; ++k) {
    ASSERT_TRUE(engine.submitBias(at(10.0 + k), Eigen::Vector3d(1e-3 * k, 0.0, 0.0)));
  }
  EXPECT_FALSE(engine.submitBias(at(100.0), Eigen::Vector3d(0.0, 0.5, 0.0)));  // furthest
  EXPECT_EQ(engine.counters().bias_queue_full, 1u);
  EXPECT_EQ(engine.gyroBias(), Eigen::Vector3d::Zero());                     // none due yet
  ASSERT_TRUE(engine.submitBias(at(10.5), Eigen::Vector3d(0.0, 0.6, 0.0)));  // 74 s dropped
  EXPECT_EQ(engine.counters().bias_queue_full, 2u);
  EXPECT_EQ(engine.gyroBias(), Eigen::Vector3d::Zero());
  engine.submit(rateAt(at(10.9)));
  EXPECT_EQ(engine.gyroBias(), Eigen::Vector3d(0.0, 0.6, 0.0));
  engine.submit(rateAt(at(11.0)));
  EXPECT_EQ(engine.gyroBias(), Eigen::Vector3d(1e-3, 0.0, 0.0));
  engine.submit(rateAt(at(80.0)));  // the rest, up to 73 s: the one at 74 s was dropped
  EXPECT_EQ(engine.gyroBias(), Eigen::Vector3d(63e-3, 0.0, 0.0));
  EXPECT_EQ(engine.counters().bias_applied, 64u);
  EXPECT_EQ(engine.counters().rejected_bias, 0u);
}

TEST(Queues, BiasAheadOfTheClockByMoreThanMaxFutureIsRefused) {
  // The rule of every input (§6.5): more than max_future ahead of a known clock is refused,
  // counted; 65 of them change nothing.
  Recorder sink;
  ap::EngineConfig c = engine_fixtures::kinematicConfig();
  c.max_future = 1.0;
  ap::AttitudeEngine engine(c, sink);
  engine.poll(at(10.0));
  for (int k = 0; k < 65; ++k) {
    EXPECT_FALSE(engine.submitBias(at(10.0 + 3600.0), Eigen::Vector3d(0.0, 0.0, 1.0)));
  }
  EXPECT_EQ(engine.counters().rejected_bias, 65u);
  EXPECT_EQ(engine.counters().bias_queue_full, 0u);
  EXPECT_TRUE(engine.submitBias(at(11.0), Eigen::Vector3d(0.0, 0.0, 0.5)));  // at the bound
  engine.submit(rateAt(at(10.0)));
  EXPECT_EQ(engine.gyroBias(), Eigen::Vector3d::Zero());
  EXPECT_EQ(engine.counters().bias_applied, 0u);
}

// ---- Late fixes (§6.9) -----------------------------------------------------------------------

/// A kinematic engine at rest at 1 s (zero rates from 0 to 1 s at 100 Hz), P_B = 0.
struct RestingEngine {
  Recorder sink;
  ap::AttitudeEngine engine;
  explicit RestingEngine(const ap::EngineConfig& c = engine_fixtures::kinematicConfig())
      : engine(c, sink) {
    for (int k = 0; k <= 100; ++k) engine.submit(rateAt(at(0.01 * k)));
  }
};

const Eigen::Matrix3d kNoCovariance = Eigen::Matrix3d::Zero();

TEST(Queues, PendingFixesAtCapacityAndOnePast) {
  // kMaxPendingFixes = 8 wait; past it the fix stamped furthest ahead is dropped and counted
  // fixes_queue_full, whether it is the newcomer or a waiting one.
  EXPECT_EQ(ap::kMaxPendingFixes, 8u);
  RestingEngine e;
  const Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
  for (int k = 1; k <= 8; ++k) {
    EXPECT_EQ(e.engine.submitFix(at(1.0 + 0.1 * k), q, kNoCovariance), ap::FixOutcome::Waiting);
  }
  EXPECT_EQ(e.engine.pendingFixes(), 8u);
  EXPECT_EQ(e.engine.counters().fixes_queue_full, 0u);
  EXPECT_EQ(e.engine.submitFix(at(1.9), q, kNoCovariance), ap::FixOutcome::QueueFull);
  EXPECT_EQ(e.engine.counters().fixes_queue_full, 1u);
  // Nearer than the furthest waiting (1.8 s): it waits, 1.8 s goes.
  EXPECT_EQ(e.engine.submitFix(at(1.05), q, kNoCovariance), ap::FixOutcome::Waiting);
  EXPECT_EQ(e.engine.counters().fixes_queue_full, 2u);
  EXPECT_EQ(e.engine.pendingFixes(), 8u);
  // The rates reach 1.75 s: the eight waiting ones up to 1.7 s are applied; 1.8 s never.
  for (int k = 101; k <= 175; ++k) e.engine.submit(rateAt(at(0.01 * k)));
  EXPECT_EQ(e.engine.counters().fixes_accepted, 8u);
  EXPECT_EQ(e.engine.pendingFixes(), 0u);
  for (int k = 176; k <= 200; ++k) e.engine.submit(rateAt(at(0.01 * k)));
  EXPECT_EQ(e.engine.counters().fixes_accepted, 8u);
}

TEST(Queues, ResetDropsTheWaitingFixes) {
  RestingEngine e;
  const Eigen::Quaterniond q = aboutAxis(Eigen::Vector3d::UnitX(), 0.02);
  EXPECT_EQ(e.engine.submitFix(at(1.2), q, kNoCovariance), ap::FixOutcome::Waiting);
  e.engine.reset();
  EXPECT_EQ(e.engine.pendingFixes(), 0u);
  // Stamped before the new anchor: too old (design.md §6.9), not an input dropped at the reset.
  EXPECT_EQ(e.engine.counters().fixes_too_old, 1u);
  EXPECT_EQ(e.engine.counters().dropped_on_reset, 0u);
  for (int k = 101; k <= 150; ++k) e.engine.submit(rateAt(at(0.01 * k)));
  EXPECT_EQ(e.engine.counters().fixes_accepted, 0u);
  EXPECT_LT(e.engine.state().q_WB.angularDistance(Eigen::Quaterniond::Identity()), 1e-15);
}

TEST(Queues, FixHistoryHoldsAtMost4096Inputs) {
  // kMaxFixHistorySamples = 4096: at 1 kHz with fix_history 10 s the memory bound rules; a fix
  // at the oldest input kept is applied, one a millisecond before it is too old.
  EXPECT_EQ(ap::kMaxFixHistorySamples, 4096u);
  ap::EngineConfig c = engine_fixtures::kinematicConfig();
  c.fixes.history = ap::kMaxFixHistory;
  Recorder sink;
  ap::AttitudeEngine engine(c, sink);
  const Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
  engine.submit(rateAt(at(0.0)));
  EXPECT_EQ(engine.submitFix(at(0.0), q, kNoCovariance), ap::FixOutcome::Accepted);
  const int n = 5000;
  for (int k = 1; k <= n; ++k) engine.submit(rateAt(at(1e-3 * k)));
  EXPECT_EQ(engine.fixHistorySize(), 4096u);
  const double oldest = 1e-3 * (n - 4095);
  EXPECT_EQ(engine.submitFix(at(oldest - 1e-3), q, kNoCovariance), ap::FixOutcome::TooOld);
  EXPECT_EQ(engine.submitFix(at(oldest), q, kNoCovariance), ap::FixOutcome::Accepted);
  EXPECT_EQ(engine.counters().fixes_too_old, 1u);
}

TEST(Queues, FiveGateRejectionsInARowThenAReset) {
  // kFixRejectionRun = 5: five fixes in a row beyond the gate are rejected; the sixth is applied
  // as a reset (fixes_accepted and fixes_reset). The run starts again after it, and any applied
  // fix ends a run.
  EXPECT_EQ(ap::kFixRejectionRun, 5);
  RestingEngine e;
  const ap::EngineCounters& n = e.engine.counters();
  const Eigen::Quaterniond far = aboutAxis(Eigen::Vector3d(0.0, 1.0, 0.0), 1.0);  // 100 sigma
  for (int k = 0; k < 5; ++k) {
    EXPECT_EQ(e.engine.submitFix(at(1.0), far, kNoCovariance), ap::FixOutcome::RejectedGate) << k;
  }
  EXPECT_EQ(n.fixes_rejected_gate, 5u);
  EXPECT_EQ(e.engine.submitFix(at(1.0), far, kNoCovariance), ap::FixOutcome::Reset);
  EXPECT_EQ(n.fixes_accepted, 1u);
  EXPECT_EQ(n.fixes_reset, 1u);
  EXPECT_LT(e.engine.state().q_WB.angularDistance(far), 1e-12);  // the fix itself
  // From the reset orientation the identity is 100 sigma away: five more rejections first.
  const Eigen::Quaterniond home = Eigen::Quaterniond::Identity();
  for (int k = 0; k < 3; ++k) {
    EXPECT_EQ(e.engine.submitFix(at(1.0), home, kNoCovariance), ap::FixOutcome::RejectedGate);
  }
  // A fix within the gate ends the run of three.
  EXPECT_EQ(e.engine.submitFix(at(1.0), far, kNoCovariance), ap::FixOutcome::Accepted);
  for (int k = 0; k < 5; ++k) {
    EXPECT_EQ(e.engine.submitFix(at(1.0), home, kNoCovariance), ap::FixOutcome::RejectedGate) << k;
  }
  EXPECT_EQ(e.engine.submitFix(at(1.0), home, kNoCovariance), ap::FixOutcome::Reset);
  EXPECT_EQ(n.fixes_rejected_gate, 13u);
  EXPECT_EQ(n.fixes_accepted, 3u);
  EXPECT_EQ(n.fixes_reset, 2u);
}

// ---- Counts of the time policy (§6.5) ---------------------------------------------------------

TEST(Queues, ThreeStampsInARowMakeAJumpBack) {
  EXPECT_EQ(ap::kJumpConfirmation, 3);
  Recorder sink;
  ap::AttitudeEngine engine(engine_fixtures::kinematicConfig(), sink);
  for (int k = 0; k <= 10; ++k) engine.submit(rateAt(at(100.0 + 0.01 * k)));
  const std::size_t published = sink.states.size();
  engine.submit(rateAt(at(50.0)));
  engine.submit(rateAt(at(50.01)));
  EXPECT_EQ(engine.counters().jumps_back, 0u);
  EXPECT_EQ(engine.counters().dropped_stale, 0u);  // held until the run is a jump or breaks
  EXPECT_EQ(sink.states.size(), published);
  engine.submit(rateAt(at(50.02)));
  EXPECT_EQ(engine.counters().jumps_back, 1u);
  EXPECT_EQ(engine.counters().resets, 1u);  // kinematic: the initial state at the third stamp
  EXPECT_EQ(sink.states.back().stamp, at(50.02));
}

TEST(Queues, ResetKeepsEachSourcesOrder) {
  // §5.5: after ~reset a straggler stays a straggler, and nothing is published at or before a
  // stamp already published.
  Recorder sink;
  ap::AttitudeEngine engine(engine_fixtures::kinematicConfig(), sink);
  for (int k = 0; k <= 50; ++k) engine.submit(rateAt(at(5.0 + 0.01 * k)));
  engine.reset();
  engine.submit(rateAt(at(5.2)));
  EXPECT_EQ(engine.counters().dropped_stale, 1u);
  EXPECT_EQ(sink.states.back().stamp, at(5.5));
  engine.submit(rateAt(at(5.51)));
  EXPECT_EQ(sink.states.back().stamp, at(5.51));
  EXPECT_TRUE(sink.stampsIncrease());
}

TEST(Queues, OneStatePerStampAlsoForSetState) {
  // §6.6: set_state at the stamp already published publishes nothing again.
  Recorder sink;
  ap::AttitudeEngine engine(engine_fixtures::kinematicConfig(), sink);
  engine.submit(rateAt(at(1.0)));
  engine.submit(rateAt(at(1.01)));
  const std::size_t published = sink.states.size();
  EXPECT_EQ(
      engine.setState(at(1.01), aboutAxis(Eigen::Vector3d::UnitZ(), 0.5), Eigen::Vector3d::Zero()),
      "");
  EXPECT_EQ(sink.states.size(), published);
  EXPECT_EQ(engine.setState(at(1.01) + 1, aboutAxis(Eigen::Vector3d::UnitZ(), 0.5),
                            Eigen::Vector3d::Zero()),
            "");
  EXPECT_EQ(sink.states.size(), published + 1);
  EXPECT_TRUE(sink.stampsIncrease());
}

TEST(Queues, EveryRefusalCountedOnceAsReceived) {
  using R = ap::Rejection;
  const std::vector<std::pair<R, std::uint64_t ap::EngineCounters::*>> kinds = {
      {R::NoRate, &ap::EngineCounters::rejected_no_rate},
      {R::WrongType, &ap::EngineCounters::rejected_type},
      {R::NoTransform, &ap::EngineCounters::dropped_no_tf},
      {R::NoTime, &ap::EngineCounters::dropped_no_time},
      {R::BadCovariance, &ap::EngineCounters::rejected_covariance},
  };
  for (const auto& [why, counter] : kinds) {
    Recorder sink;
    ap::AttitudeEngine engine(engine_fixtures::kinematicConfig(), sink);
    engine.reject(why);
    EXPECT_EQ(engine.counters().received, 1u);
    EXPECT_EQ(engine.counters().*counter, 1u);
    EXPECT_EQ(engine.counters().accepted, 0u);
  }
  // A refused future input: received, rejected_future, nothing else.
  Recorder sink;
  ap::AttitudeEngine engine(engine_fixtures::kinematicConfig(), sink);
  engine.clockTick(at(1.0));
  engine.submit(rateAt(at(3.0)));
  EXPECT_EQ(engine.counters().received, 1u);
  EXPECT_EQ(engine.counters().rejected_future, 1u);
  EXPECT_EQ(engine.counters().dropped_stale, 0u);
}

TEST(Queues, InputLagIsAMeanOverAbout32Inputs) {
  // §6.5: the first lag is the lag itself; each later one moves the mean by 1/32 of the
  // difference (kLagWeight).
  EXPECT_EQ(ap::kLagWeight, 1.0 / 32.0);
  Recorder sink;
  ap::AttitudeEngine engine(engine_fixtures::kinematicConfig(), sink);
  engine.clockTick(at(10.0));
  engine.submit(rateAt(at(9.75)));
  ASSERT_TRUE(engine.inputLag(ap::Source::Imu).has_value());
  EXPECT_NEAR(*engine.inputLag(ap::Source::Imu), 0.25, 1e-12);
  engine.clockTick(at(10.5));
  engine.submit(rateAt(at(10.25)));  // lag 0.25 again
  EXPECT_NEAR(*engine.inputLag(ap::Source::Imu), 0.25, 1e-12);
  engine.submit(rateAt(at(10.5)));  // lag 0
  EXPECT_NEAR(*engine.inputLag(ap::Source::Imu), 0.25 * 31.0 / 32.0, 1e-12);
}

// ---- Gap filling of averaged samples (docs/real_streams.md: 2 <= m <= 5) ---------------------

// Two to five periods (one to four lost) are filled; six and seven, past kGapPeriods (5.5), are
// dropouts: held, nothing filled.
TEST(Queues, GapsOfTwoToFivePeriodsAreFilled) {
  ap::KinematicConfig config;
  config.rate_samples = ap::RateSamples::IntervalAverage;
  EXPECT_EQ(config.max_gap_fill, 4);
  ap::KinematicPropagator k(config);
  const Eigen::Vector3d w(0.1, 0.2, 0.3);
  int step = 0;
  auto feed = [&](int periods) {
    step += periods;
    return k.addSample(0.01 * step, w);
  };
  for (int i = 0; i < 10; ++i) feed(1);
  std::uint64_t filled = k.filledSamples();
  for (int m = 2; m <= 7; ++m) {
    EXPECT_EQ(feed(m), m <= 5 ? ap::StampOutcome::Advanced : ap::StampOutcome::HeldGap) << m;
    EXPECT_EQ(k.filledSamples() - filled, m <= 5 ? static_cast<std::uint64_t>(m - 1) : 0u) << m;
    filled = k.filledSamples();
    for (int i = 0; i < 6; ++i) feed(1);  // the nominal period again
  }
}

// ---- The stamp filter (docs/numerics.md §3) --------------------------------------------------

/// A 100 Hz sensor clock whose receipt stamps jitter uniformly by +-0.1 ms (seeded).
struct JitteredClock {
  std::mt19937 rng{20261202};
  std::uniform_real_distribution<double> jitter{-1e-4, 1e-4};
  int n = 0;
  double next(double extra = 0.0, int periods = 1) {
    n += periods;
    return 100.0 + 0.01 * n + jitter(rng) + extra;
  }
};

TEST(Queues, StampFilterRestartsAfterFiveRejectionsInARow) {
  ap::SensorClockFilter f;
  EXPECT_EQ(ap::SensorClockFilter::Options{}.restart_after, 5);
  JitteredClock clock;
  for (int i = 0; i < 300; ++i) f.filter(clock.next());
  const std::uint64_t restarts = f.restarts();
  const std::uint64_t rejected = f.rejected();
  using V = ap::SensorClockFilter::Verdict;
  // 3 ms late: 30 sigma of the jitter, far inside the restart jump of 1 s.
  for (int run : {4, 4}) {
    for (int i = 0; i < run; ++i) EXPECT_EQ(f.filter(clock.next(3e-3)).verdict, V::Rejected);
    EXPECT_EQ(f.filter(clock.next()).verdict, V::Modelled);  // ends the run
  }
  EXPECT_EQ(f.restarts(), restarts);
  EXPECT_EQ(f.rejected() - rejected, 8u);
  for (int i = 0; i < 4; ++i) EXPECT_EQ(f.filter(clock.next(3e-3)).verdict, V::Rejected);
  EXPECT_EQ(f.filter(clock.next(3e-3)).verdict, V::Restarted);
  EXPECT_EQ(f.restarts(), restarts + 1);
}

TEST(Queues, StampFilterRestartsAfterFiveDropsInARow) {
  // A sample after a lost one, five times in a row: the rate fell, a new period.
  ap::SensorClockFilter f;
  JitteredClock clock;
  for (int i = 0; i < 300; ++i) f.filter(clock.next());
  const std::uint64_t restarts = f.restarts();
  const std::uint64_t missed = f.missed();
  using V = ap::SensorClockFilter::Verdict;
  for (int run : {4, 4}) {
    for (int i = 0; i < run; ++i) {
      const ap::SensorClockFilter::Result r = f.filter(clock.next(0.0, 2));
      EXPECT_EQ(r.verdict, V::Modelled);
      EXPECT_EQ(r.missed, 1u);
    }
    EXPECT_EQ(f.filter(clock.next()).missed, 0u);  // ends the run
  }
  EXPECT_EQ(f.restarts(), restarts);
  EXPECT_EQ(f.missed() - missed, 8u);
  for (int i = 0; i < 4; ++i) EXPECT_EQ(f.filter(clock.next(0.0, 2)).verdict, V::Modelled);
  EXPECT_EQ(f.filter(clock.next(0.0, 2)).verdict, V::Restarted);
  EXPECT_EQ(f.restarts(), restarts + 1);
}

TEST(Queues, StampFilterBatchLimitIs100RepeatedStamps) {
  // A read of up to max_batch = 100 repeated stamps is modelled; the 101st sample of a read
  // turns the filter to unfiltered stamps.
  EXPECT_EQ(ap::SensorClockFilter::Options{}.max_batch, 100);
  ap::SensorClockFilter f;
  JitteredClock clock;
  for (int read = 0; read < 20; ++read) {
    const double t = clock.next(0.0, 10);
    for (int i = 0; i < 10; ++i) f.filter(t);
  }
  const double t100 = clock.next(0.0, 100);
  for (int i = 0; i < 100; ++i) {
    EXPECT_NE(f.filter(t100).verdict, ap::SensorClockFilter::Verdict::Unfiltered) << i;
    EXPECT_FALSE(f.unfiltered()) << i;
  }
  const double t101 = clock.next(0.0, 101);
  for (int i = 0; i < 100; ++i)
    EXPECT_FALSE(f.filter(t101).verdict == ap::SensorClockFilter::Verdict::Unfiltered) << i;
  EXPECT_EQ(f.filter(t101).verdict, ap::SensorClockFilter::Verdict::Unfiltered);
  EXPECT_TRUE(f.unfiltered());
}

}  // namespace
