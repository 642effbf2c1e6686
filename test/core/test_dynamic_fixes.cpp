// Late absolute fixes in the dynamic model (docs/design.md §6.9): the fix acts on the attitude at
// its own stamp, the angular velocity stays the model's, and the torques and advances since are
// replayed. Truths: the same fix handed in on time (every dynamic integrator that takes a
// torque, both modes), the torque-free motion of an independent long-double reference, the
// Kalman update's closed form, and the history's rules.
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "attitude_propagator/engine.h"
#include "attitude_propagator/numerics/quaternion.h"
#include "engine_fixtures.h"
#include "free_body_reference.h"
#include "integrator_cases.h"
#include "torqued_body.h"

namespace {

namespace ap = attitude_propagator;
using engine_fixtures::at;
using engine_fixtures::Recorder;

constexpr double kTick = 0.005;  // s: the clock ticks at 200 Hz, the grid is at 100 Hz

ap::EngineConfig dynamicFixConfig(ap::Integrator integrator, ap::FixMode mode) {
  ap::EngineConfig c;
  c.model = ap::Model::Dynamic;
  ap::DynamicConfig d;
  d.body = torqued_body::body();  // B is not the principal frame
  d.initial = torqued_body::initial();
  d.integrator = integrator;
  d.torque_input = integrator != ap::Integrator::Exact;
  d.max_step = 0.01;
  c.dynamic = d;
  c.publish_rate = 100.0;
  c.initial_orientation_stddev = 0.05;
  c.fixes.mode = mode;
  return c;
}

// Torques change at these stamps (grid stamps are multiples of 10 ms; 0.4123 is also a fix's
// stamp), alternately in the body and the fixed frame: a fixed-frame torque turns in the body
// with the attitude, so a correction of the attitude changes what it does afterwards.
struct TorqueSample {
  double t;
  ap::TorqueFrame frame;
  double scale;
};
const std::vector<TorqueSample> kTorques{{0.0, ap::TorqueFrame::Body, 1.0},
                                         {0.237, ap::TorqueFrame::Fixed, 1.0},
                                         {0.4123, ap::TorqueFrame::Body, -0.7},
                                         {0.5512, ap::TorqueFrame::Fixed, 1.5},
                                         {0.8, ap::TorqueFrame::Body, 0.4}};

struct Fix {
  double t;
  double submit_t;  ///< handed in right after the clock tick at this time
  Eigen::Quaterniond q;
};

// Ticks the clock from 0 to 1 s, each torque handed in one tick before its stamp, each fix
// right after the tick at its submit_t. Returns the newest state; `outcomes` gets the fixes'.
ap::EngineState runDynamic(const ap::EngineConfig& config, const std::vector<Fix>& fixes,
                           Recorder& sink, std::vector<ap::FixOutcome>* outcomes = nullptr) {
  ap::AttitudeEngine engine(config, sink);
  const Eigen::Matrix3d R = engine_fixtures::correlatedFixCovariance();
  const bool torqued = config.dynamic->torque_input;
  for (int k = 0; k <= 200; ++k) {
    const double t = kTick * k;
    for (const TorqueSample& s : kTorques) {
      if (torqued && s.t > t - 1e-9 && s.t <= t + kTick - 1e-9) {
        engine.submit(
            engine_fixtures::torque(at(s.t), s.scale * torqued_body::torque(s.frame).tau, s.frame));
      }
    }
    engine.clockTick(at(t));
    for (const Fix& f : fixes) {
      if (std::abs(f.submit_t - t) < 1e-9) {
        const std::size_t published = sink.states.size();
        const ap::FixOutcome o = engine.submitFix(at(f.t), f.q, R);
        if (outcomes) outcomes->push_back(o);
        EXPECT_EQ(sink.states.size(), published) << "a fix publishes nothing itself";
      }
    }
  }
  EXPECT_EQ(engine.pendingFixes(), 0u);
  EXPECT_TRUE(sink.stampsIncrease());  // nothing older than a published state is published
  return engine.state();
}

struct DynamicCase {
  ap::Integrator integrator;
  ap::FixMode mode;
};

std::vector<DynamicCase> torqueIntegratorsAndModes() {
  std::vector<DynamicCase> cases;
  for (ap::Integrator m : integrator_cases::methodsWhere(
           ap::Model::Dynamic, [](const ap::IntegratorInfo& row) { return row.takes_torque; })) {
    cases.push_back({m, ap::FixMode::Fuse});
    cases.push_back({m, ap::FixMode::Reset});
  }
  return cases;
}

std::string caseName(const ::testing::TestParamInfo<DynamicCase>& info) {
  return ap::integratorName(info.param.integrator) + "_" + ap::fixModeName(info.param.mode);
}

class DynamicLateFix : public ::testing::TestWithParam<DynamicCase> {};

// On time: handed in with the first clock tick at or after its stamp. Late: 100 ms later, after
// a torque changed (0.5512) for the fixes at 0.5 and 0.5037. The first fix (0.1, on time) starts
// the history.
TEST_P(DynamicLateFix, NewestStateIsTheOnTimeOne) {
  const DynamicCase c = GetParam();
  const ap::EngineConfig config = dynamicFixConfig(c.integrator, c.mode);
  const Eigen::Quaterniond offset = ap::expMap(Eigen::Vector3d(0.02, -0.01, 0.015));
  const Eigen::Quaterniond q_first = torqued_body::initial().q_WB * offset;
  // The fix's attitude only needs to be plausible (inside the gate): the truth here is the
  // on-time run. The state published at the grid stamp at or before the fix, turned a little.
  Recorder reference_sink;
  runDynamic(config, {{0.1, 0.1, q_first}}, reference_sink);
  // at a grid stamp, between two, at a torque's stamp
  for (double fix_t : {0.5, 0.5037, 0.4123}) {
    const double on_time = std::ceil(fix_t / kTick - 1e-9) * kTick;
    const ap::EngineState* near = reference_sink.stateAt(at(std::floor(fix_t * 100.0) / 100.0));
    ASSERT_NE(near, nullptr);
    const Eigen::Quaterniond q_fix = near->q_WB * offset.conjugate();
    Recorder on_time_sink, late_sink, without_sink;
    std::vector<ap::FixOutcome> on_time_outcomes, late_outcomes;
    const ap::EngineState on_time_state = runDynamic(
        config, {{0.1, 0.1, q_first}, {fix_t, on_time, q_fix}}, on_time_sink, &on_time_outcomes);
    const ap::EngineState late_state = runDynamic(
        config, {{0.1, 0.1, q_first}, {fix_t, on_time + 0.1, q_fix}}, late_sink, &late_outcomes);
    const ap::FixOutcome applied =
        c.mode == ap::FixMode::Fuse ? ap::FixOutcome::Accepted : ap::FixOutcome::Reset;
    ASSERT_EQ(late_outcomes.size(), 2u);
    EXPECT_EQ(late_outcomes[0], applied);
    EXPECT_EQ(late_outcomes[1], applied) << fix_t;
    // A fix at the stamp the model holds at (a grid stamp it just published) acts at once; one
    // between grid stamps waits for the next.
    EXPECT_EQ(on_time_outcomes[1], fix_t == 0.5 ? applied : ap::FixOutcome::Waiting) << fix_t;
    EXPECT_LE(ap::rotationAngle(on_time_state.q_WB, late_state.q_WB), 1e-12) << fix_t;
    EXPECT_LE((on_time_state.w_B - late_state.w_B).norm(), 1e-12) << fix_t;
    EXPECT_LE((on_time_state.P_B - late_state.P_B).cwiseAbs().maxCoeff(), 1e-15) << fix_t;
    // The fix matters: without it the state differs by far more than round-off.
    const ap::EngineState without =
        runDynamic(config, {{0.1, 0.1, q_first}, {fix_t, 10.0, q_fix}}, without_sink);
    EXPECT_GT(ap::rotationAngle(without.q_WB, late_state.q_WB), 1e-3) << fix_t;
    // The same grid stamps are published in both runs, and the last ones agree.
    ASSERT_EQ(on_time_sink.states.size(), late_sink.states.size());
    EXPECT_EQ(on_time_sink.states.back().stamp, late_sink.states.back().stamp);
    EXPECT_LE(ap::rotationAngle(on_time_sink.states.back().q_WB, late_sink.states.back().q_WB),
              1e-12);
  }
}

// An earlier fix (at a torque's stamp) that arrives after a later one (between grid stamps):
// applied at its stamp and the later one again after it, the newest state is the one both on
// time give.
TEST_P(DynamicLateFix, AnEarlierFixArrivingAfterALaterOneIsAppliedBeforeIt) {
  const DynamicCase c = GetParam();
  const ap::EngineConfig config = dynamicFixConfig(c.integrator, c.mode);
  const Eigen::Quaterniond q_first =
      torqued_body::initial().q_WB * ap::expMap(Eigen::Vector3d(0.02, -0.01, 0.015));
  Recorder reference_sink;
  runDynamic(config, {{0.1, 0.1, q_first}}, reference_sink);
  auto fixNear = [&](double t, const Eigen::Vector3d& offset) {
    const ap::EngineState* near = reference_sink.stateAt(at(std::floor(t * 100.0) / 100.0));
    EXPECT_NE(near, nullptr) << t;
    return near ? Eigen::Quaterniond(near->q_WB * ap::expMap(offset)) : q_first;
  };
  const Eigen::Quaterniond early = fixNear(0.4123, {0.02, -0.01, 0.015});
  const Eigen::Quaterniond later = fixNear(0.5037, {-0.015, 0.02, 0.01});
  Recorder on_time_sink, reversed_sink, early_only_sink;
  std::vector<ap::FixOutcome> reversed_outcomes;
  const ap::EngineState on_time = runDynamic(
      config, {{0.1, 0.1, q_first}, {0.4123, 0.415, early}, {0.5037, 0.505, later}}, on_time_sink);
  const ap::EngineState reversed =
      runDynamic(config, {{0.1, 0.1, q_first}, {0.5037, 0.505, later}, {0.4123, 0.6, early}},
                 reversed_sink, &reversed_outcomes);
  const ap::FixOutcome applied =
      c.mode == ap::FixMode::Fuse ? ap::FixOutcome::Accepted : ap::FixOutcome::Reset;
  ASSERT_EQ(reversed_outcomes.size(), 3u);
  EXPECT_EQ(reversed_outcomes[2], applied);
  EXPECT_LE(ap::rotationAngle(on_time.q_WB, reversed.q_WB), 1e-12);
  EXPECT_LE((on_time.w_B - reversed.w_B).norm(), 1e-12);
  EXPECT_LE((on_time.P_B - reversed.P_B).cwiseAbs().maxCoeff(), 1e-15);
  // The later fix matters: with the early one alone the state differs by far more.
  const ap::EngineState early_only =
      runDynamic(config, {{0.1, 0.1, q_first}, {0.4123, 0.6, early}}, early_only_sink);
  EXPECT_GT(ap::rotationAngle(early_only.q_WB, reversed.q_WB), 1e-3);
}

INSTANTIATE_TEST_SUITE_P(EveryTorqueIntegratorAndMode, DynamicLateFix,
                         ::testing::ValuesIn(torqueIntegratorsAndModes()), caseName);

// The fix corrects the attitude only: under body torques the angular velocity's motion does not
// depend on the attitude, so with and without the fix it is the same.
TEST(DynamicFix, TheAngularVelocityStaysTheModels) {
  ap::EngineConfig config = dynamicFixConfig(ap::Integrator::Rk4, ap::FixMode::Reset);
  Recorder with_sink, without_sink;
  ap::AttitudeEngine with(config, with_sink), without(config, without_sink);
  const Eigen::Quaterniond far = engine_fixtures::aboutAxis(Eigen::Vector3d(1, 2, 3), 2.0);
  for (int k = 0; k <= 100; ++k) {
    for (ap::AttitudeEngine* e : {&with, &without}) {
      if (k == 10) e->submit(engine_fixtures::torque(at(0.0537), Eigen::Vector3d(0.3, -0.5, 0.2)));
      e->clockTick(at(kTick * k));
    }
    if (k == 20) with.submitFix(at(0.1), far, 1e-6 * Eigen::Matrix3d::Identity());
    if (k == 60) {
      EXPECT_EQ(with.submitFix(at(0.2037), far, 1e-6 * Eigen::Matrix3d::Identity()),
                ap::FixOutcome::Reset);
    }
  }
  EXPECT_GT(ap::rotationAngle(with.state().q_WB, without.state().q_WB), 0.1);
  // Only the knots the fixes add (a step split in two) separate them: rk4's error, not a rate.
  EXPECT_LE((with.state().w_B - without.state().w_B).norm(), 1e-9);
  EXPECT_LE(std::abs(with.state().kinetic_energy - without.state().kinetic_energy), 1e-9);
}

// A torque-free body, started from a wrong attitude: a reset with the true attitude between two
// grid stamps, handed in 100 ms late, leaves the newest state on the true motion (Bulirsch-Stoer
// in long double on the full inertia tensor, free_body_reference.h).
TEST(DynamicFix, TorqueFreeBodyFollowsTheTrueMotionAfterALateReset) {
  const ap::DynamicState truth0 = torqued_body::initial();
  free_body_reference::TensorReference reference(torqued_body::tensor_B(), truth0);
  const ap::DynamicState at_fix = reference.advanceTo(0.5037);
  const ap::DynamicState at_end = reference.advanceTo(1.0);
  for (ap::Integrator m : {ap::Integrator::Exact, ap::Integrator::Dopri5}) {
    ap::EngineConfig config = dynamicFixConfig(m, ap::FixMode::Reset);
    config.dynamic->initial.q_WB = truth0.q_WB * ap::expMap(Eigen::Vector3d(0.3, -0.2, 0.1));
    config.dynamic->tolerance = 1e-12;
    Recorder sink;
    ap::AttitudeEngine engine(config, sink);
    for (int k = 0; k <= 200; ++k) {
      engine.clockTick(at(kTick * k));
      if (k == 0)
        engine.submitFix(at(0.0), config.dynamic->initial.q_WB, 1e-6 * Eigen::Matrix3d::Identity());
      if (k == 122) {  // 0.61 s
        EXPECT_EQ(engine.submitFix(at(0.5037), at_fix.q_WB, 1e-6 * Eigen::Matrix3d::Identity()),
                  ap::FixOutcome::Reset);
      }
    }
    EXPECT_LE(ap::rotationAngle(engine.state().q_WB, at_end.q_WB), 1e-9) << ap::integratorName(m);
    EXPECT_LE((engine.state().w_B - at_end.w_B).norm(), 1e-9) << ap::integratorName(m);
  }
}

// The dynamic model propagates no orientation covariance (node.md): P_B holds its anchor value
// (initial_orientation_stddev^2 I) and, after a fuse, the posterior. With P = p I and R = rho I
// the update is the closed form K = p / (p + rho), P+ = p rho / (p + rho) I (numerics.md §7.1),
// and P+ then holds until the next fix.
TEST(DynamicFix, FuseUsesTheHeldCovariance) {
  ap::EngineConfig config = dynamicFixConfig(ap::Integrator::Rk4, ap::FixMode::Fuse);
  const double p = 0.05 * 0.05, rho = 0.02 * 0.02;
  Recorder sink;
  ap::AttitudeEngine engine(config, sink);
  engine.clockTick(at(0.0));
  engine_fixtures::runClock(engine, 0.0, 0.3, kTick);
  const Eigen::Quaterniond q_prior = engine.state().q_WB;
  const Eigen::Vector3d v(0.01, -0.02, 0.005);
  EXPECT_EQ(engine.submitFix(at(0.3), q_prior * ap::expMap(v), rho * Eigen::Matrix3d::Identity()),
            ap::FixOutcome::Accepted);
  EXPECT_LE(ap::rotationAngle(engine.state().q_WB, q_prior * ap::expMap(p / (p + rho) * v)), 1e-14);
  const Eigen::Matrix3d posterior = p * rho / (p + rho) * Eigen::Matrix3d::Identity();
  EXPECT_LE((engine.state().P_B - posterior).cwiseAbs().maxCoeff(), 1e-18);
  engine_fixtures::runClock(engine, 0.3, 0.8, kTick);
  EXPECT_LE((engine.state().P_B - posterior).cwiseAbs().maxCoeff(), 1e-18);
  // Beyond the gate: rejected, and the newest state exactly what it was.
  const ap::EngineState before = engine.state();
  EXPECT_EQ(engine.submitFix(at(0.6537), before.q_WB * ap::expMap(Eigen::Vector3d(1.0, 0, 0)),
                             rho * Eigen::Matrix3d::Identity()),
            ap::FixOutcome::RejectedGate);
  EXPECT_EQ(engine.state().q_WB.coeffs(), before.q_WB.coeffs());
  EXPECT_EQ(engine.state().w_B, before.w_B);
  engine_fixtures::runClock(engine, 0.8, 0.9, kTick);
  EXPECT_EQ(engine.counters().fixes_rejected_gate, 1u);
}

// ROS time jumping back resets the model: the history goes with it, so a fix stamped before the
// new anchor is too old, even where the old timeline had a state at its stamp.
TEST(DynamicFix, AJumpBackClearsTheHistory) {
  ap::EngineConfig config = dynamicFixConfig(ap::Integrator::Rk4, ap::FixMode::Reset);
  config.fixes.history = 3.0;
  Recorder sink;
  ap::AttitudeEngine engine(config, sink);
  const Eigen::Matrix3d R = 1e-6 * Eigen::Matrix3d::Identity();
  const Eigen::Quaterniond q = engine_fixtures::aboutAxis(Eigen::Vector3d(1, 0, 1), 1.0);
  engine.clockTick(at(0.0));
  EXPECT_EQ(engine.submitFix(at(0.0), q, R), ap::FixOutcome::Reset);
  engine_fixtures::runClock(engine, 0.0, 3.0, kTick);
  EXPECT_EQ(engine.submitFix(at(1.2), q, R), ap::FixOutcome::Reset);  // 1.8 s late: kept
  engine_fixtures::runClock(engine, 1.5, 2.0, kTick);  // back by 1.5 s: a reset at 1.5
  EXPECT_EQ(engine.counters().resets, 1u);
  const ap::EngineState before = engine.state();
  EXPECT_EQ(engine.submitFix(at(1.2), q, R), ap::FixOutcome::TooOld);
  EXPECT_EQ(engine.state().q_WB.coeffs(), before.q_WB.coeffs());
  EXPECT_EQ(engine.submitFix(at(1.7), q, R), ap::FixOutcome::Reset);
}

// The fixes applied before a reset are not applied again after it: a fix stamped after the
// reset but before one applied before it acts alone (the same run without that one is the
// truth).
TEST(DynamicFix, AResetForgetsTheAppliedFixes) {
  const ap::EngineConfig config = dynamicFixConfig(ap::Integrator::Dopri5, ap::FixMode::Reset);
  const Eigen::Matrix3d R = 1e-6 * Eigen::Matrix3d::Identity();
  const Eigen::Quaterniond q = engine_fixtures::aboutAxis(Eigen::Vector3d(1, 0, 1), 1.0);
  const Eigen::Quaterniond q_old = engine_fixtures::aboutAxis(Eigen::Vector3d(0, 1, 0), -0.5);
  auto run = [&](bool fix_before_the_reset) {
    Recorder sink;
    ap::AttitudeEngine engine(config, sink);
    engine.clockTick(at(0.0));
    EXPECT_EQ(engine.submitFix(at(0.0), q, R), ap::FixOutcome::Reset);
    engine_fixtures::runClock(engine, 0.0, 3.0, kTick);
    if (fix_before_the_reset) {
      EXPECT_EQ(engine.submitFix(at(2.8), q_old, R), ap::FixOutcome::Reset);
    }
    engine_fixtures::runClock(engine, 1.5, 3.0, kTick);  // back by 1.5 s: a reset at 1.5
    EXPECT_EQ(engine.counters().resets, 1u);
    EXPECT_EQ(engine.submitFix(at(2.5), q, R), ap::FixOutcome::Reset);  // before 2.8
    return engine.state();
  };
  const ap::EngineState alone = run(false);
  const ap::EngineState after_another = run(true);
  EXPECT_LE(ap::rotationAngle(alone.q_WB, after_another.q_WB), 1e-12);
}

// Each entry of the dynamic model's history: its size, and the memory bound (printed).
TEST(DynamicFix, HistoryMemory) {
  ap::EngineConfig config = dynamicFixConfig(ap::Integrator::Dopri5, ap::FixMode::Fuse);
  Recorder sink;
  ap::AttitudeEngine engine(config, sink);
  engine.clockTick(at(0.0));
  engine.submitFix(at(0.0), engine.state().q_WB, Eigen::Matrix3d::Zero());
  engine_fixtures::runClock(engine, 0.0, 2.0, kTick);
  // 1 s of fix_history at a 100 Hz grid: an entry per grid stamp, and the one before.
  EXPECT_LE(engine.fixHistorySize(), 102u);
  EXPECT_GE(engine.fixHistorySize(), 100u);
  std::printf(
      "[ fixes    ] one history entry: %zu bytes, the dynamic propagator's state %zu "
      "more; at most %zu entries\n",
      sizeof(ap::FixHistoryEntry), ap::DynamicPropagator::stateBytes(), ap::kMaxFixHistorySamples);
}

}  // namespace
