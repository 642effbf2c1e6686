// AttitudeEngine: the scheduling the node relies on, without ROS. Truths are closed forms
// (constant rate, torque from rest) and the rules of docs/design.md: one state per stamp, grid
// stamps only, inputs applied at their stamps, clock jumps back reset, clock jumps ahead are
// gaps while a late callback is not, and bounded work per call.
#include <gtest/gtest.h>

#include <cfloat>
#include <cmath>
#include <cstdint>
#include <vector>

#include "attitude_propagator/engine.h"
#include "engine_fixtures.h"
#include "reference_dynamics.h"
#include "rotation_matchers.h"
#include "torqued_body.h"

namespace ap = attitude_propagator;
namespace ref = reference_dynamics;

using namespace engine_fixtures;  // NOLINT: the fixtures are the tests' vocabulary

namespace {

/// The spinning asymmetric body of torqued_body.h with torque input, rk4 at `max_step`, 50 Hz.
ap::EngineConfig spinningTorquedConfig(double max_step) {
  ap::EngineConfig c = torqueConfig();
  c.dynamic->body = torqued_body::body();
  c.dynamic->initial = torqued_body::initial();
  c.dynamic->max_step = max_step;
  return c;
}

double stateError(const ap::EngineState& s, const ap::DynamicState& truth) {
  return ref::stateError(s.q_WB, s.w_B, truth);
}

/// The reference state at `t` under the body torque of torqued_body.h from 0 and the
/// fixed-frame one from `switch_time`.
ap::DynamicState switchedReference(double switch_time, double t) {
  return ref::Trajectory(torqued_body::tensor_B(), torqued_body::initial(), 0.0,
                         {{0.0, torqued_body::torque(ap::TorqueFrame::Body)},
                          {switch_time, torqued_body::torque(ap::TorqueFrame::Fixed)}})
      .advanceTo(t);
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Kinematic model: one state per input
// ---------------------------------------------------------------------------------------------

TEST(EngineKinematic, ConstantRateEveryInputPublishesItsStamp) {
  Recorder sink;
  ap::AttitudeEngine engine(kinematicConfig(), sink);
  const Eigen::Vector3d w(0.1, -0.2, 0.3);
  for (int k = 0; k <= 100; ++k) engine.submit(rate(at(0.01 * k), w));
  ASSERT_EQ(sink.states.size(), 101u);
  EXPECT_TRUE(sink.stampsIncrease());
  EXPECT_EQ(sink.applied.size(), 101u);
  EXPECT_EQ(engine.counters().accepted, 101u);
  // cf4 is exact for a constant rate: q(t) = Exp(t w).
  EXPECT_ROTATION_NEAR(sink.states.back().q_WB, aboutAxis(w, w.norm() * 1.0), 1e-13);
}

TEST(EngineKinematic, StaleAndDuplicateStampsAreDroppedAndCounted) {
  Recorder sink;
  ap::AttitudeEngine engine(kinematicConfig(), sink);
  engine.submit(rate(at(0.0), Eigen::Vector3d::UnitZ()));
  engine.submit(rate(at(0.01), Eigen::Vector3d::UnitZ()));
  engine.submit(rate(at(0.01), Eigen::Vector3d::UnitZ()));   // duplicate
  engine.submit(rate(at(0.005), Eigen::Vector3d::UnitZ()));  // stale
  EXPECT_EQ(engine.counters().dropped_stale, 2u);
  EXPECT_EQ(sink.states.size(), 2u);
}

TEST(EngineKinematic, NonFiniteAndBadCovarianceAreRejectedWithTheStateUnchanged) {
  Recorder sink;
  ap::AttitudeEngine engine(kinematicConfig(), sink);
  engine.submit(rate(at(0.0), Eigen::Vector3d::UnitZ()));
  ap::Input nan = rate(at(0.01), Eigen::Vector3d(NAN, 0, 0));
  engine.submit(nan);
  EXPECT_EQ(engine.counters().rejected_non_finite, 1u);
  EXPECT_EQ(sink.states.size(), 1u);
}

// sample_door.h: a refused value (non-finite, or a rate above kMaxBodyRate, a torque above
// kMaxTorque) is refused before its source's order sees it. Stamped ahead of the stream, it
// would otherwise become the source's newest, and every on-time input after it a straggler.
TEST(EngineKinematic, ARefusedRateNeverCountsInItsSourcesOrder) {
  Recorder sink;
  ap::AttitudeEngine engine(kinematicConfig(), sink);
  engine.submit(rate(at(0.0), Eigen::Vector3d::UnitZ()));
  engine.submit(rate(at(0.5), Eigen::Vector3d(2.0 * ap::kMaxBodyRate, 0.0, 0.0)));
  engine.submit(rate(at(0.6), Eigen::Vector3d(NAN, 0.0, 0.0)));
  engine.submit(rate(at(0.01), Eigen::Vector3d::UnitZ()));
  engine.submit(rate(at(0.02), Eigen::Vector3d::UnitZ()));
  EXPECT_EQ(engine.counters().rejected_out_of_range, 1u);
  EXPECT_EQ(engine.counters().rejected_non_finite, 1u);
  EXPECT_EQ(engine.counters().dropped_stale, 0u);
  ASSERT_EQ(sink.states.size(), 3u);
  EXPECT_EQ(sink.states.back().stamp, at(0.02));
}

// On a generic body (engine_fixtures.h): 0.4 N m along its first principal axis for 0.99 s
// spins it about that axis alone at 0.4 * 0.99 / 1.5 rad/s.
TEST(EngineDynamic, ARefusedTorqueNeverCountsInItsSourcesOrder) {
  Recorder sink;
  ap::AttitudeEngine engine(genericTorqueConfig(), sink);
  const Eigen::Vector3d e1 = genericAxes().col(0), e2 = genericAxes().col(1);
  runClock(engine, 0.0, 1.0, 0.01);
  engine.submit(torque(at(1.5), 2.0 * ap::kMaxTorque * e2));
  engine.submit(torque(at(1.01), 0.4 * e1));
  EXPECT_EQ(engine.counters().rejected_out_of_range, 1u);
  EXPECT_EQ(engine.counters().dropped_stale, 0u);
  runClock(engine, 1.0, 2.0, 0.01);
  const ap::EngineState* s = sink.stateAt(at(2.0));
  ASSERT_NE(s, nullptr);
  EXPECT_LT((s->w_B - 0.4 * 0.99 / kGenericMoments[0] * e1).norm(), 1e-12);
}

TEST(EngineKinematic, GyroBiasIsSubtractedFromItsStampOn) {
  Recorder sink;
  ap::EngineConfig config = kinematicConfig();
  config.gyro_bias_B = Eigen::Vector3d(0.0, 0.0, 0.1);
  ap::AttitudeEngine engine(config, sink);
  const Eigen::Vector3d w(0.0, 0.0, 0.6);
  // 0.5 rad/s net for 1 s, then a bias sample of 0.2 from t = 1: 0.4 rad/s for 1 s.
  EXPECT_TRUE(engine.submitBias(at(1.0), Eigen::Vector3d(0.0, 0.0, 0.2)));
  for (int k = 0; k <= 200; ++k) engine.submit(rate(at(0.01 * k), w));
  // Point samples across the switch: the interpolants smooth the 0.1 rad/s step over about one
  // sample interval, an error of order h 0.1 = 1e-3 rad.
  EXPECT_ROTATION_NEAR(sink.states.back().q_WB, aboutAxis(Eigen::Vector3d::UnitZ(), 0.9), 2e-3);
  EXPECT_FALSE(engine.submitBias(at(3.0), Eigen::Vector3d(NAN, 0, 0)));
  EXPECT_FALSE(engine.submitBias(at(3.0), Eigen::Vector3d(1e200, 0, 0)));
  EXPECT_EQ(engine.counters().rejected_bias, 2u);
}

// "At or after": a bias stamped exactly at a rate sample's stamp is subtracted from that sample.
TEST(EngineKinematic, ABiasStampedAtARateSampleAppliesToIt) {
  Recorder sink;
  ap::AttitudeEngine engine(kinematicConfig(), sink);
  const Eigen::Vector3d bias(0.01, -0.02, 0.03);
  engine.submit(rate(at(0.0), Eigen::Vector3d::Zero()));
  ASSERT_TRUE(engine.submitBias(at(0.01), bias));
  engine.submit(rate(at(0.005), Eigen::Vector3d::Zero()));
  EXPECT_EQ(engine.gyroBias(), Eigen::Vector3d::Zero());
  engine.submit(rate(at(0.01), Eigen::Vector3d::Zero()));
  EXPECT_EQ(engine.gyroBias(), bias);
}

// The body-frame covariance of the orientation error does not depend on where the world frame
// is: with the same body rates and noise, a start turned a quarter turn about x gives the same
// P_B (measured 2.6e-15 relative; bound 2e-14). The noise is anisotropic, so a step rotation taken
// in the world frame instead of the body frame shows (0.86 relative).
TEST(EngineKinematic, OrientationCovarianceIsTheSameFromAnyStartingOrientation) {
  Eigen::Matrix3d P[2];
  for (int turned = 0; turned < 2; ++turned) {
    Recorder sink;
    ap::EngineConfig config = kinematicConfig();
    if (turned) config.kinematic.initial_q_WB = aboutAxis(Eigen::Vector3d::UnitX(), M_PI / 2);
    ap::AttitudeEngine engine(config, sink);
    for (int k = 0; k <= 100; ++k) {
      ap::Input in = rate(at(0.01 * k), Eigen::Vector3d(0.0, 0.0, 1.0));
      in.rate_covariance_B = Eigen::Vector3d(1e-4, 1e-6, 1e-6).asDiagonal();
      engine.submit(in);
    }
    P[turned] = sink.states.back().P_B;
  }
  ASSERT_GT(P[0].norm(), 0.0);
  EXPECT_LE((P[1] - P[0]).norm(), 2e-14 * P[0].norm()) << P[0] << "\n" << P[1];
}

// With the stamp filter on, each state is published at the filtered stamp: receipt stamps
// 0 to 4e-4 s after a 100 Hz clock (a latency 2e-4 (1 + sin 1.7k), its floor 0) come out
// within 1e-5 s of the sensor's clock once the filter has settled (the receipt stamps are up to
// 4e-4 s off).
TEST(EngineKinematic, TheStampFilterPublishesAtTheSensorClock) {
  Recorder sink;
  ap::EngineConfig config = kinematicConfig();
  config.kinematic.stamp_filter = ap::StampFilter::SensorClock;
  ap::AttitudeEngine engine(config, sink);
  const int samples = 600, settled = 300;
  for (int k = 0; k < samples; ++k) {
    const double latency = 2e-4 * (1.0 + std::sin(1.7 * k));
    engine.submit(rate(at(0.01 * k + latency), Eigen::Vector3d(0.0, 0.0, 0.3)));
  }
  ASSERT_EQ(sink.states.size(), static_cast<std::size_t>(samples));
  double worst = 0.0;
  for (int k = settled; k < samples; ++k) {
    worst = std::max(worst, std::abs(static_cast<double>(sink.states[k].stamp - at(0.01 * k))));
  }
  EXPECT_LE(worst * 1e-9, 1e-5);
}

// A FIFO read of ten samples at 200 Hz, every sample stamped with the read's receipt time
// (2 ms after its newest sample): with the stamp filter every sample passes the engine's order
// check and is integrated at its own stamp. Without the filter a repeated stamp is a straggler.
TEST(EngineKinematic, FifoReadsWithRepeatedStampsReachTheStampFilterWhole) {
  const int reads = 300, per_read = 10;
  const Eigen::Vector3d w(0.0, 0.2, 0.4);
  auto feed = [&](ap::AttitudeEngine& engine) {
    for (int r = 0; r < reads; ++r) {
      const ap::Stamp receipt = at(0.005 * (per_read * (r + 1) - 1) + 0.002);
      for (int i = 0; i < per_read; ++i) engine.submit(rate(receipt, w));
    }
  };
  Recorder sink;
  ap::EngineConfig config = kinematicConfig();
  config.kinematic.stamp_filter = ap::StampFilter::SensorClock;
  ap::AttitudeEngine engine(config, sink);
  feed(engine);
  EXPECT_EQ(engine.counters().accepted, static_cast<std::uint64_t>(reads * per_read));
  EXPECT_EQ(engine.counters().dropped_stale, 0u);
  // Every sample has a state of its own: the first read, before the period is known, too (its
  // stamps kMinStampStep apart, docs/numerics.md §3): no stamp is published twice.
  ASSERT_EQ(sink.states.size(), static_cast<std::size_t>(reads * per_read));
  EXPECT_TRUE(sink.stampsIncrease());
  // After the first reads the stamps are the sensor's (5 ms apart, 2 ms late): the rotation
  // between two states is Exp(w Δt) over their own stamps.
  const ap::EngineState& a = sink.states[100 * per_read];
  const ap::EngineState& b = sink.states.back();
  EXPECT_NEAR((b.stamp - a.stamp) * 1e-9, 0.005 * (sink.states.size() - 1 - 100 * per_read), 1e-6);
  EXPECT_ROTATION_NEAR(a.q_WB.conjugate() * b.q_WB,
                       aboutAxis(w, w.norm() * (b.stamp - a.stamp) * 1e-9), 1e-9);

  Recorder unfiltered;
  ap::AttitudeEngine plain(kinematicConfig(), unfiltered);
  feed(plain);
  EXPECT_EQ(plain.counters().dropped_stale, static_cast<std::uint64_t>(reads * (per_read - 1)));
}

TEST(EngineKinematic, OrientationCovarianceStartsAsConfiguredAndGrowsWithRateNoise) {
  Recorder sink;
  ap::EngineConfig config = kinematicConfig();
  config.initial_orientation_stddev = 0.1;
  config.rate_stddev = 0.01;
  ap::AttitudeEngine engine(config, sink);
  // At rest Phi = I and J_r = I: P = P0 + n h^2 R (a random walk of the angle).
  for (int k = 0; k <= 50; ++k) engine.submit(rate(at(0.01 * k), Eigen::Vector3d::Zero()));
  const double expected = 0.1 * 0.1 + 50 * 0.01 * 0.01 * 1e-4;
  EXPECT_NEAR(sink.states.front().P_B(0, 0), 0.01, 4 * DBL_EPSILON * 0.01);
  EXPECT_NEAR(sink.states.back().P_B(2, 2), expected, 64 * DBL_EPSILON * expected);
  EXPECT_EQ(sink.states.back().P_B(0, 1), 0.0);
  // Pinned by set_state: what the caller says, no uncertainty left.
  engine.setState(at(1.0), Eigen::Quaterniond::Identity(), Eigen::Vector3d::Zero());
  EXPECT_TRUE(sink.states.back().P_B.isZero(0.0));
  // An unknown start (pi) stays capped at pi^2 whatever the integration adds.
  Recorder unknown_sink;
  config.initial_orientation_stddev = M_PI;
  ap::AttitudeEngine unknown(config, unknown_sink);
  for (int k = 0; k <= 50; ++k) unknown.submit(rate(at(0.01 * k), Eigen::Vector3d(1, 2, 3)));
  const Eigen::Matrix3d P = unknown_sink.states.back().P_B;
  EXPECT_TRUE(P.allFinite());
  EXPECT_LE(P.diagonal().maxCoeff(), M_PI * M_PI * (1 + 1e-12));
  EXPECT_GE(P.diagonal().minCoeff(), M_PI * M_PI * (1 - 1e-12));
}

TEST(EngineKinematic, StampsJumpingBackThreeInARowStartAgainFromTheInitialStateAtTheFirst) {
  Recorder sink;
  ap::AttitudeEngine engine(kinematicConfig(), sink);
  for (int k = 0; k <= 50; ++k) engine.submit(rate(at(10.0 + 0.01 * k), Eigen::Vector3d::UnitX()));
  // A looped bag: the first two stamps from the earlier time are held, neither used nor
  // counted; the third (each going on from the one before) starts time again from the initial
  // state at the first of them, and all three are integrated: 0.02 s at 1 rad/s about x.
  engine.submit(rate(at(2.0), Eigen::Vector3d::UnitX()));
  engine.submit(rate(at(2.01), Eigen::Vector3d::UnitX()));
  EXPECT_EQ(engine.counters().resets, 0u);
  EXPECT_EQ(engine.counters().dropped_stale, 0u);
  EXPECT_EQ(sink.states.back().stamp, at(10.5));
  engine.submit(rate(at(2.02), Eigen::Vector3d::UnitX()));
  EXPECT_EQ(engine.counters().resets, 1u);
  EXPECT_EQ(engine.counters().jumps_back, 1u);
  EXPECT_EQ(engine.counters().dropped_stale, 0u);
  EXPECT_EQ(engine.counters().accepted, 51u + 3u);
  EXPECT_ROTATION_NEAR(sink.states.back().q_WB, aboutAxis(Eigen::Vector3d::UnitX(), 0.02), 1e-15);
  EXPECT_EQ(sink.states.back().stamp, at(2.02));
}

TEST(EngineKinematic, AStampYearsAheadIsAGapAndPrecisionIsKeptAfterIt) {
  Recorder sink;
  ap::AttitudeEngine engine(kinematicConfig(), sink);
  const Eigen::Vector3d w(0.0, 0.0, 0.5);
  engine.submit(rate(at(0.0), w));
  engine.submit(rate(at(0.01), w));
  // 2100-01-01: 74 years ahead (beyond a 32-bit count of seconds in a difference).
  const ap::Stamp far = 4102444800LL * kSecond;
  EXPECT_EQ(engine.timeBase().coreTime(at(0.01)), 0.01);  // the first input's second
  engine.submit(rate(far, w));
  EXPECT_EQ(engine.counters().gaps, 1u);
  // The state held there, the origin moved to its second (design.md §6.1).
  EXPECT_EQ(engine.timeBase().coreTime(far), 0.0);
  EXPECT_EQ(engine.timeBase().stampAt(0.0), std::optional<ap::Stamp>(far));
  const Eigen::Quaterniond held = sink.states.back().q_WB;
  for (int k = 1; k <= 100; ++k) engine.submit(rate(far + k * kSecond / 100, w));
  ASSERT_EQ(sink.states.back().stamp, far + kSecond);
  // One second at 0.5 rad/s after the held state, to round-off (not to 1e-7 s of stamp noise).
  EXPECT_ROTATION_NEAR(sink.states.back().q_WB, held * aboutAxis(w, 0.5), 1e-12);
}

TEST(EngineKinematic, BackFromAFarFutureStampPrecisionIsKept) {
  // Stamps jump to 2100 (a gap) and back (a reset): core time must be precise again after.
  Recorder sink;
  ap::AttitudeEngine engine(kinematicConfig(), sink);
  const Eigen::Vector3d w(0.0, 0.0, 0.5);
  engine.submit(rate(at(0.0), w));
  engine.submit(rate(at(0.1), w));
  engine.submit(rate(4102444800LL * kSecond, w));  // no clock known: accepted, a gap
  // Back, and it persists: a reset to the initial state, anchored at the first stamp of the run.
  for (double t : {0.2, 0.3, 0.4}) engine.submit(rate(at(t), w));
  EXPECT_EQ(engine.counters().resets, 1u);
  for (int k = 1; k <= 10; ++k) engine.submit(rate(at(0.4 + 0.1 * k), w));
  EXPECT_ROTATION_NEAR(sink.states.back().q_WB, aboutAxis(w, 0.5 * 1.2), 1e-13);
}

TEST(EngineKinematic, ClockGoingBackResetsAndForgetsTime) {
  Recorder sink;
  ap::AttitudeEngine engine(kinematicConfig(), sink);
  engine.clockTick(at(10.0));
  engine.submit(rate(at(10.0), Eigen::Vector3d::UnitZ()));
  engine.submit(rate(at(10.5), Eigen::Vector3d::UnitZ()));
  engine.clockTick(at(10.4));  // within the threshold: jitter, no reset
  EXPECT_EQ(engine.counters().resets, 0u);
  engine.clockTick(at(3.0));
  EXPECT_EQ(engine.counters().resets, 1u);
  engine.submit(rate(at(3.0), Eigen::Vector3d::UnitZ()));  // anchors again, published
  EXPECT_EQ(sink.states.back().stamp, at(3.0));
  EXPECT_ROTATION_NEAR(sink.states.back().q_WB, Eigen::Quaterniond::Identity(), 0.0);
}

TEST(EngineKinematic, SetStatePinsAndPublishes) {
  Recorder sink;
  ap::AttitudeEngine engine(kinematicConfig(), sink);
  const Eigen::Quaterniond q = aboutAxis(Eigen::Vector3d(1, 2, 3), 0.7);
  EXPECT_EQ(engine.setState(at(1.0), q, Eigen::Vector3d(0, 0, 1)), "");
  ASSERT_EQ(sink.states.size(), 1u);
  EXPECT_ROTATION_NEAR(sink.states[0].q_WB, q, 1e-15);
  EXPECT_NE(engine.setState(at(1.5), Eigen::Quaterniond(NAN, 0, 0, 0), Eigen::Vector3d::Zero()),
            "");
  EXPECT_NE(engine.setState(0, q, Eigen::Vector3d::Zero()), "");
}

// ---------------------------------------------------------------------------------------------
// Dynamic model: the publish grid
// ---------------------------------------------------------------------------------------------

TEST(EngineDynamic, PublishesEveryGridStampOnceAndOnlyGridStamps) {
  Recorder sink;
  ap::AttitudeEngine engine(spinningSphereConfig(), sink);
  runClock(engine, 0.0, 2.0, 0.007);  // ticks off the grid
  ASSERT_FALSE(sink.states.empty());
  EXPECT_TRUE(sink.stampsIncrease());
  for (const auto& s : sink.states) EXPECT_EQ((s.stamp - kEpoch) % (kSecond / 50), 0);
  // From the first tick's grid stamp to the last: all of them.
  const auto n = (sink.states.back().stamp - sink.states.front().stamp) / (kSecond / 50) + 1;
  EXPECT_EQ(static_cast<std::int64_t>(sink.states.size()), n);
  // Exact sphere: 0.2 rad/s about z from the first stamp.
  const double span = static_cast<double>(sink.states.back().stamp - sink.states[0].stamp) * 1e-9;
  EXPECT_ROTATION_NEAR(sink.states.back().q_WB, aboutAxis(Eigen::Vector3d::UnitZ(), 0.2 * span),
                       1e-12);
}

TEST(EngineDynamic, AClockStoppingOnAGridStampPublishesIt) {
  // The clock jumps 0.07 s (off the grid phase of any timer), then steps 0.01 s to a whole
  // second and stops there: that stamp is published on the tick that reaches it.
  Recorder sink;
  ap::AttitudeEngine engine(spinningSphereConfig(), sink);
  engine.clockTick(at(0.0));
  engine.clockTick(at(0.07));
  runClock(engine, 0.07, 1.0, 0.01);
  ASSERT_FALSE(sink.states.empty());
  EXPECT_EQ(sink.states.back().stamp, at(1.0));
}

TEST(EngineDynamic, TorqueFromRestMatchesTheClosedForm) {
  // From rest, a torque along a principal axis: w = T t / I, angle = T t^2 / (2 I).
  Recorder sink;
  ap::AttitudeEngine engine(torqueConfig(), sink);
  engine.clockTick(at(0.0));
  engine.submit(torque(at(0.0), Eigen::Vector3d(0.4, 0.0, 0.0)));
  runClock(engine, 0.0, 2.0, 0.01);
  const ap::EngineState* s = sink.stateAt(at(2.0));
  ASSERT_NE(s, nullptr);
  // rk4 at 0.02 s: measured 5.6e-17 (rate, a few ulps allowed) and 2.8e-13 rad.
  EXPECT_NEAR(s->w_B.x(), 0.4, 4 * DBL_EPSILON);
  EXPECT_ROTATION_NEAR(s->q_WB, aboutAxis(Eigen::Vector3d::UnitX(), 0.4), 6e-13);
  EXPECT_EQ(engine.counters().gaps, 0u);
}

TEST(EngineDynamic, AStarvedCallbackCatchesUpWithoutAGap) {
  // A timer that ran 3 s late (more than max_dt = 1 s) while the clock moved on smoothly:
  // poll() publishes every grid stamp in between and integrates the torque across them.
  Recorder sink;
  ap::AttitudeEngine engine(torqueConfig(), sink);
  engine.poll(at(0.0));
  engine.submit(torque(at(0.0), Eigen::Vector3d(0.4, 0.0, 0.0)));
  engine.poll(at(3.0));
  EXPECT_EQ(engine.counters().gaps, 0u);
  EXPECT_EQ(sink.states.size(), 151u);  // 0, 0.02, ..., 3.0
  const ap::EngineState* s = sink.stateAt(at(3.0));
  ASSERT_NE(s, nullptr);
  EXPECT_NEAR(s->w_B.x(), 0.6, 4 * DBL_EPSILON);  // measured 0.0
  // rk4: measured 3.2e-12 rad.
  EXPECT_ROTATION_NEAR(s->q_WB, aboutAxis(Eigen::Vector3d::UnitX(), 0.9), 1e-11);
}

TEST(EngineDynamic, ABurstOfClockTicksIsIntegratedWithoutAGap) {
  // /clock messages that queued up while the process was starved arrive in one burst: each
  // is a small step, so nothing is a gap.
  Recorder sink;
  ap::AttitudeEngine engine(torqueConfig(), sink);
  engine.clockTick(at(0.0));
  engine.submit(torque(at(0.0), Eigen::Vector3d(0.4, 0.0, 0.0)));
  runClock(engine, 0.0, 3.0, 0.01);
  EXPECT_EQ(engine.counters().gaps, 0u);
  const ap::EngineState* s = sink.stateAt(at(3.0));
  ASSERT_NE(s, nullptr);
  // rk4: measured 3.2e-12 rad.
  EXPECT_ROTATION_NEAR(s->q_WB, aboutAxis(Eigen::Vector3d::UnitX(), 0.9), 1e-11);
}

TEST(EngineDynamic, AClockJumpAheadIsAGapAndTheStateHolds) {
  Recorder sink;
  ap::AttitudeEngine engine(spinningSphereConfig(), sink);
  runClock(engine, 0.0, 1.0, 0.01);
  const Eigen::Quaterniond before = sink.states.back().q_WB;
  engine.clockTick(at(6.0));  // a bag skipped ahead by 5 s
  EXPECT_EQ(engine.counters().gaps, 1u);
  EXPECT_EQ(sink.states.back().stamp, at(6.0));
  EXPECT_ROTATION_NEAR(sink.states.back().q_WB, before, 1e-15);
  // No grid stamp inside the jump was published.
  for (const auto& s : sink.states) EXPECT_FALSE(s.stamp > at(1.0) && s.stamp < at(6.0));
}

TEST(EngineDynamic, InputsAheadOfTheClockWaitForIt) {
  Recorder sink;
  ap::AttitudeEngine engine(torqueConfig(), sink);
  engine.clockTick(at(0.0));
  engine.submit(torque(at(0.5), Eigen::Vector3d(0.4, 0.0, 0.0)));  // stamped ahead
  EXPECT_EQ(engine.pending(), 1u);
  EXPECT_TRUE(sink.applied.empty());
  runClock(engine, 0.0, 2.5, 0.01);
  EXPECT_EQ(engine.pending(), 0u);
  ASSERT_EQ(sink.applied.size(), 1u);
  // The torque acts from its stamp: 2 s of it by t = 2.5.
  const ap::EngineState* s = sink.stateAt(at(2.5));
  ASSERT_NE(s, nullptr);
  // rk4: measured 2.8e-13 rad.
  EXPECT_ROTATION_NEAR(s->q_WB, aboutAxis(Eigen::Vector3d::UnitX(), 0.4), 6e-13);
}

TEST(EngineDynamic, ALateInputActsFromTheLastGridPointAndIsCounted) {
  Recorder sink;
  ap::AttitudeEngine engine(torqueConfig(), sink);
  runClock(engine, 0.0, 1.0, 0.01);
  engine.clockTick(at(1.01));  // the clock between grid stamps; the propagator at 1.0
  engine.submit(torque(at(0.995), Eigen::Vector3d(0.4, 0.0, 0.0)));
  EXPECT_EQ(engine.counters().late, 1u);
  runClock(engine, 1.01, 2.0, 0.01);
  const ap::EngineState* s = sink.stateAt(at(2.0));
  ASSERT_NE(s, nullptr);
  EXPECT_NEAR(s->w_B.x(), 0.2, 4 * DBL_EPSILON);  // from the grid point 1.0 (measured 2.8e-17)
}

// design.md §6.5, §6.7: the engine is the one owner of each source's order. In the dynamic model
// a late torque newer than its source's previous acts from the last grid point; one at or
// before the previous, though later than the grid point and later than the previous rate (the
// rate is another source), is a straggler: dropped and counted, the torque in force unchanged.
// On a generic body (engine_fixtures.h): 0.4 N m along its first principal axis from 1.0 spins
// it about that axis alone, at 0.4 / 1.5 rad/s by 2.0; the dropped torques, along its second,
// would add 5 / 2.5 rad/s about that one.
TEST(EngineDynamic, ALateInputNotNewerThanItsSourcesPreviousIsDropped) {
  Recorder sink;
  ap::AttitudeEngine engine(genericTorqueConfig(), sink);
  const Eigen::Vector3d e1 = genericAxes().col(0), e2 = genericAxes().col(1);
  runClock(engine, 0.0, 1.0, 0.01);
  engine.clockTick(at(1.01));
  engine.submit(rate(at(0.999), Eigen::Vector3d::Zero()));
  engine.submit(torque(at(0.998), 0.4 * e1));
  engine.submit(torque(at(0.998), 5.0 * e2));  // repeated
  engine.submit(torque(at(0.997), 5.0 * e2));  // older
  EXPECT_EQ(engine.counters().late, 2u);
  EXPECT_EQ(engine.counters().dropped_stale, 2u);
  runClock(engine, 1.01, 2.0, 0.01);
  const ap::EngineState* s = sink.stateAt(at(2.0));
  ASSERT_NE(s, nullptr);
  EXPECT_LT((s->w_B - 0.4 / kGenericMoments[0] * e1).norm(), 1e-13);
}

// A late input acts from the last grid point, but is handed on (the node republishes an IMU
// message with it) with the state at its own stamp: spinning at 1 rad/s about z, the grid at
// 0.1 s, a rate stamped 0.05 s goes out with 0.05 rad (the closed form), not the 0.1 rad of the
// model's time. Between two grid states the orientation is interpolated along the geodesic,
// exact for a constant rate.
TEST(EngineDynamic, ALateInputIsHandedOnWithTheStateAtItsOwnStamp) {
  ap::EngineConfig config = spinningSphereConfig();
  config.dynamic->initial.w_B = Eigen::Vector3d(0.0, 0.0, 1.0);
  config.publish_rate = 100.0;
  Recorder sink;
  ap::AttitudeEngine engine(config, sink);
  engine.clockTick(at(0.0));  // the anchor: the state at 0 is the identity
  runClock(engine, 0.0, 0.1, 0.01);
  ASSERT_EQ(sink.states.back().stamp, at(0.1));
  for (double t : {0.05, 0.073}) {
    engine.submit(rate(at(t), Eigen::Vector3d(0.0, 0.0, 1.0)));
    ASSERT_FALSE(sink.applied_states.empty());
    EXPECT_EQ(sink.applied_states.back().stamp, at(t));
    EXPECT_ROTATION_NEAR(sink.applied_states.back().q_WB, aboutAxis(Eigen::Vector3d::UnitZ(), t),
                         1e-12);
  }
  EXPECT_EQ(engine.counters().late, 2u);
  // The state published goes on from the grid point, as before.
  runClock(engine, 0.1, 0.2, 0.01);
  EXPECT_ROTATION_NEAR(sink.states.back().q_WB, aboutAxis(Eigen::Vector3d::UnitZ(), 0.2), 1e-12);
}

// design.md §5.5, §6.6: after ~reset the dynamic model anchors at the first grid stamp it may
// publish, after the last one published, so the state published there is the initial state.
// A tick at the stamp already published anchors nothing: anchored there, the model would
// publish the initial state turned by 0.2 rad/s for 0.02 s at the next grid stamp.
TEST(EngineDynamic, AfterResetTheFirstStatePublishedIsTheInitialState) {
  Recorder sink;
  ap::AttitudeEngine engine(spinningSphereConfig(), sink);
  runClock(engine, 0.0, 1.0, 0.01);
  ASSERT_EQ(sink.states.back().stamp, at(1.0));
  engine.reset();
  engine.clockTick(at(1.0));
  EXPECT_EQ(sink.states.back().stamp, at(1.0));
  engine.clockTick(at(1.02));
  ASSERT_EQ(sink.states.back().stamp, at(1.02));
  EXPECT_ROTATION_NEAR(sink.states.back().q_WB, Eigen::Quaterniond::Identity(), 0.0);
}

TEST(EngineDynamic, TheClockGoingBackResetsAndPublishesTheInitialStateAtOnce) {
  Recorder sink;
  ap::AttitudeEngine engine(spinningSphereConfig(), sink);
  runClock(engine, 10.0, 12.0, 0.01);
  engine.clockTick(at(5.0));
  EXPECT_EQ(engine.counters().resets, 1u);
  EXPECT_EQ(sink.states.back().stamp, at(5.0));
  EXPECT_ROTATION_NEAR(sink.states.back().q_WB, Eigen::Quaterniond::Identity(), 0.0);
  runClock(engine, 5.0, 6.0, 0.01);
  EXPECT_ROTATION_NEAR(sink.states.back().q_WB, aboutAxis(Eigen::Vector3d::UnitZ(), 0.2), 1e-12);
}

TEST(EngineDynamic, InputsFarAheadNeverCarryThePropagatorAwayFromTheClock) {
  Recorder sink;
  ap::EngineConfig config = torqueConfig();
  config.max_pending = 16;
  config.max_future = ap::kMaxFuture;  // an hour: these inputs are allowed to wait
  ap::AttitudeEngine engine(config, sink);
  const ap::Stamp far = at(1000.0);
  // Right after a reset, with the clock known: a torque stamped 1000 s ahead waits for it.
  engine.clockTick(at(0.0));
  engine.reset();
  engine.submit(torque(far, Eigen::Vector3d(0.4, 0.0, 0.0)));
  runClock(engine, 0.0, 0.5, 0.01);
  EXPECT_EQ(sink.states.back().stamp, at(0.5));
  // A flood of them: the queue keeps the earliest, drops the rest, and the grid goes on.
  for (int k = 1; k <= 100; ++k) {
    engine.submit(torque(far + k * kSecond, Eigen::Vector3d(0.4, 0.0, 0.0)));
  }
  EXPECT_EQ(engine.pending(), 16u);
  EXPECT_GE(engine.counters().pending_overflow, 84u);
  runClock(engine, 0.5, 1.0, 0.01);
  EXPECT_EQ(sink.states.back().stamp, at(1.0));
  EXPECT_ROTATION_NEAR(sink.states.back().q_WB, Eigen::Quaterniond::Identity(), 0.0);
}

TEST(EngineDynamic, WorkPerCallIsBoundedAndTheRestFollows) {
  Recorder sink;
  ap::EngineConfig config = spinningSphereConfig();
  config.grid_budget = 10;
  ap::AttitudeEngine engine(config, sink);
  engine.poll(at(0.0));
  engine.poll(at(1.0));  // 50 grid stamps due, 10 per call
  EXPECT_EQ(sink.states.size(), 11u);
  EXPECT_EQ(engine.counters().deferred_ticks, 1u);
  for (int i = 0; i < 4; ++i) engine.poll(at(1.0));
  EXPECT_EQ(sink.states.size(), 51u);
  EXPECT_EQ(sink.states.back().stamp, at(1.0));
}

TEST(EngineDynamic, IntegratorWorkPerCallIsBoundedToo) {
  // A fine step (1e-4 s, 200 steps per 50 Hz grid stamp) and a work budget of 1000 steps:
  // five grid stamps per call, the rest follow, and the result is the same state.
  Recorder sink;
  ap::EngineConfig config = torqueConfig();
  config.dynamic->max_step = 1e-4;
  config.work_budget = 1000;
  ap::AttitudeEngine engine(config, sink);
  engine.poll(at(0.0));
  engine.submit(torque(at(0.0), Eigen::Vector3d(0.4, 0.0, 0.0)));
  engine.poll(at(1.0));
  EXPECT_LE(sink.states.size(), 7u);
  EXPECT_GE(engine.counters().deferred_ticks, 1u);
  for (int i = 0; i < 20; ++i) engine.poll(at(1.0));
  ASSERT_EQ(sink.states.back().stamp, at(1.0));
  EXPECT_EQ(sink.states.size(), 51u);
  // rk4: measured 8.8e-15 rad.
  EXPECT_ROTATION_NEAR(sink.states.back().q_WB, aboutAxis(Eigen::Vector3d::UnitX(), 0.1), 3e-14);
}

TEST(EngineDynamic, TheGridIsExactForRatesThatDoNotDivideASecond) {
  Recorder sink;
  ap::EngineConfig config = spinningSphereConfig();
  config.publish_rate = 300.0;  // 3333333.33 ns; k near 2026 in epoch time
  ap::AttitudeEngine engine(config, sink);
  for (std::int64_t k = 0; k < 1000; ++k) {
    const ap::Stamp g = engine.gridStamp(k + 534000000000LL);
    EXPECT_EQ(engine.gridIndexAtOrBefore(g), k + 534000000000LL);
    EXPECT_EQ(engine.gridIndexAtOrBefore(g - 1), k + 534000000000LL - 1);
  }
}

// Where a torque takes effect, on the spinning asymmetric body (gyroscopic coupling, a
// fixed-frame torque turning in the body): the state published at 2 s is the long-double
// reference's with the torque switched at the documented instant (docs/design.md §4.4, §6.7),
// and at least 1e-3 away from the reference's with the switch at the other candidate instants
// (the grid stamps around the stamp, and the stamp itself: measured 3.7e-3 ... 1.8e-2).
TEST(EngineDynamic, TorqueTimingOnASpinningBodyMatchesTheReference) {
  struct Case {
    const char* name;
    double max_step;
    double stamp;         // the fixed-frame torque's stamp
    double clock;         // the clock when it is submitted
    double takes_effect;  // where it must act
    double bound;
  };
  const std::vector<Case> cases{
      // Late: the propagator is at the grid stamp 1.0, a knot, committed after the stamp.
      {"late, after a grid point", 0.02, 0.995, 1.01, 1.0, 6e-9},  // measured 2.6e-9
      // Late, with max_step 0.015 the last knot before 1.0 is 0.99, before the stamp.
      {"late, no grid point since", 0.015, 0.995, 1.01, 0.995, 2e-9},  // measured 8.1e-10
      // Ahead of the clock, between grid stamps: waits, then acts from its own stamp.
      {"ahead", 0.02, 0.513, 0.3, 0.513, 4e-9},  // measured 1.8e-9
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    Recorder sink;
    ap::AttitudeEngine engine(spinningTorquedConfig(c.max_step), sink);
    engine.clockTick(at(0.0));
    engine.submit(torque(at(0.0), torqued_body::torque(ap::TorqueFrame::Body).tau));
    runClock(engine, 0.0, c.clock, 0.01);
    const bool late = c.stamp < c.clock;
    engine.submit(torque(at(c.stamp), torqued_body::torque(ap::TorqueFrame::Fixed).tau,
                         ap::TorqueFrame::Fixed));
    EXPECT_EQ(engine.counters().late, late ? 1u : 0u);
    EXPECT_EQ(engine.pending(), late ? 0u : 1u);
    runClock(engine, c.clock, 2.0, 0.01);
    const ap::EngineState* s = sink.stateAt(at(2.0));
    ASSERT_NE(s, nullptr);
    EXPECT_LE(stateError(*s, switchedReference(c.takes_effect, 2.0)), c.bound);
    for (const double wrong : {0.995, 1.0, 1.02, 0.5, 0.513, 0.52}) {
      if (std::abs(wrong - c.takes_effect) < 1e-12) continue;
      if (std::abs(wrong - c.stamp) > 0.03) continue;  // only the instants near this case's
      EXPECT_GE(stateError(*s, switchedReference(wrong, 2.0)), 1e-3) << wrong;
    }
  }
}
