// Late absolute attitude fixes (docs/design.md §6.9, docs/numerics.md §7.1): a fix applied at
// its stamp and the rates since replayed, against the same fix on time; the multiplicative EKF
// against its closed form; the gyro bias estimate, the gate and the error model against a
// simulated gyro on the coning motion's closed form; bad fixes; the history's bounds.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "attitude_propagator/config/parameters.h"
#include "attitude_propagator/engine.h"
#include "attitude_propagator/limits.h"
#include "attitude_propagator/numerics/coning_motion.h"
#include "attitude_propagator/numerics/quaternion.h"
#include "engine_fixtures.h"
#include "simulated_gyro.h"

namespace {

namespace ap = attitude_propagator;
using engine_fixtures::aboutAxis;
using engine_fixtures::at;
using engine_fixtures::kSecond;
using engine_fixtures::Recorder;
using simulated_gyro::GyroRun;
using simulated_gyro::kDegPerHour;
using simulated_gyro::simulateGyro;

ap::Input rate(double t, const Eigen::Vector3d& w_B) {
  ap::Input in;
  in.source = ap::Source::Imu;
  in.stamp = at(t);
  in.value = w_B;
  return in;
}

ap::EngineConfig fixConfig(ap::Integrator integrator, ap::FixMode mode, bool estimate_bias) {
  ap::EngineConfig c = engine_fixtures::kinematicConfig();
  c.kinematic.integrator = integrator;
  c.rate_stddev = 0.01;
  c.initial_orientation_stddev = 0.05;
  c.fixes.mode = mode;
  c.fixes.estimate_gyro_bias = estimate_bias;
  c.fixes.gyro_bias_stddev = 1e-3;
  return c;
}

// ---- (a) a late fix gives the state the same fix would have given on time ------------------

// Streams 200 Hz coning rates for 1 s, with a first fix at 0.1 s (the history starts there) and
// a fix at `fix_t`, handed in after the sample at `submit_t`. Returns the newest state.
ap::EngineState runWithFix(const ap::EngineConfig& config, double fix_t, double submit_t,
                           Recorder& sink) {
  const ap::ConingMotion cone;
  ap::AttitudeEngine engine(config, sink);
  const Eigen::Matrix3d R = engine_fixtures::correlatedFixCovariance();
  const Eigen::Quaterniond offset = ap::expMap(Eigen::Vector3d(0.02, -0.01, 0.015));
  bool sent = false;
  for (int k = 0; k <= 200; ++k) {
    const double t = 0.005 * k;
    engine.submit(rate(t, cone.bodyRate(t)));
    if (k == 20) {
      EXPECT_EQ(engine.submitFix(at(0.1), cone.attitude(0.1) * offset, R),
                config.fixes.mode == ap::FixMode::Fuse ? ap::FixOutcome::Accepted
                                                       : ap::FixOutcome::Reset);
    }
    if (!sent && t >= submit_t - 1e-9) {
      const std::size_t published = sink.states.size();
      engine.submitFix(at(fix_t), cone.attitude(fix_t) * offset.conjugate(), R);
      EXPECT_EQ(sink.states.size(), published) << "a fix publishes nothing itself";
      sent = true;
    }
  }
  EXPECT_TRUE(sink.stampsIncrease());
  if (submit_t <= 1.0) {
    EXPECT_TRUE(sent);
    EXPECT_EQ(engine.counters().fixes_accepted, 2u);
  }
  return engine.state();
}

struct ReplayCase {
  ap::Integrator integrator;
  ap::FixMode mode;
  bool estimate_bias;
};

class LateFix : public ::testing::TestWithParam<ReplayCase> {};

TEST_P(LateFix, NewestStateIsTheOnTimeOne) {
  const ReplayCase c = GetParam();
  const ap::EngineConfig config = fixConfig(c.integrator, c.mode, c.estimate_bias);
  for (double fix_t : {0.5, 0.5025}) {  // at a sample, and between two
    Recorder on_time_sink, late_sink, without_sink;
    // On time: handed in with the first sample at or after its stamp. Late: 100 ms later.
    const double on_time = std::ceil(fix_t / 0.005 - 1e-9) * 0.005;
    const ap::EngineState on_time_state = runWithFix(config, fix_t, on_time, on_time_sink);
    const ap::EngineState late_state = runWithFix(config, fix_t, on_time + 0.1, late_sink);
    EXPECT_LE(ap::rotationAngle(on_time_state.q_WB, late_state.q_WB), 1e-12) << fix_t;
    EXPECT_LE((on_time_state.P_B - late_state.P_B).cwiseAbs().maxCoeff(), 1e-15) << fix_t;
    EXPECT_LE((on_time_state.gyro_bias_estimate_B - late_state.gyro_bias_estimate_B).norm(), 1e-15);
    // The fix matters: without it the state differs by far more than round-off.
    const ap::EngineState without = runWithFix(config, fix_t, 10.0, without_sink);
    EXPECT_GT(ap::rotationAngle(without.q_WB, late_state.q_WB), 1e-3);
    // The states published before the late fix was handed in are the same in both runs, and
    // after it the late run's states are the on-time run's.
    ASSERT_EQ(on_time_sink.states.size(), late_sink.states.size());
    const ap::EngineState& last_on_time = on_time_sink.states.back();
    EXPECT_LE(ap::rotationAngle(last_on_time.q_WB, late_sink.states.back().q_WB), 1e-12);
  }
}

// Two fixes with different offsets, at 0.4 s and between two samples at 0.5025 s (after the
// first fix at 0.1 s that starts the history), each handed in after the sample at its `submit`
// time. Returns the newest state; `counters` gets the engine's.
ap::EngineState runTwoFixes(const ap::EngineConfig& config, double submit_early, double submit_late,
                            ap::EngineCounters& counters) {
  const ap::ConingMotion cone;
  Recorder sink;
  ap::AttitudeEngine engine(config, sink);
  const Eigen::Matrix3d R = engine_fixtures::correlatedFixCovariance();
  const Eigen::Quaterniond early = cone.attitude(0.4) * ap::expMap({0.02, -0.01, 0.015});
  const Eigen::Quaterniond late = cone.attitude(0.5025) * ap::expMap({-0.015, 0.02, 0.01});
  for (int k = 0; k <= 200; ++k) {
    const double t = 0.005 * k;
    engine.submit(rate(t, cone.bodyRate(t)));
    if (k == 20) engine.submitFix(at(0.1), cone.attitude(0.1), R);
    if (std::abs(t - submit_early) < 1e-9) engine.submitFix(at(0.4), early, R);
    if (std::abs(t - submit_late) < 1e-9) engine.submitFix(at(0.5025), late, R);
  }
  EXPECT_TRUE(sink.stampsIncrease());
  counters = engine.counters();
  return engine.state();
}

// An earlier fix that arrives after a later one (two sources, one slower): it is applied at its
// stamp and the later one again after it, so the newest state is the one both on time give
// (in reset mode the later fix wins, as on time); the outcome is counted once per fix.
TEST_P(LateFix, AnEarlierFixArrivingAfterALaterOneIsAppliedBeforeIt) {
  const ReplayCase c = GetParam();
  const ap::EngineConfig config = fixConfig(c.integrator, c.mode, c.estimate_bias);
  ap::EngineCounters on_time_counters, reversed_counters, early_only_counters;
  const ap::EngineState on_time = runTwoFixes(config, 0.4, 0.505, on_time_counters);
  const ap::EngineState reversed = runTwoFixes(config, 0.6, 0.505, reversed_counters);
  EXPECT_LE(ap::rotationAngle(on_time.q_WB, reversed.q_WB), 1e-12);
  EXPECT_LE((on_time.P_B - reversed.P_B).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_LE((on_time.gyro_bias_estimate_B - reversed.gyro_bias_estimate_B).norm(), 1e-15);
  EXPECT_EQ(on_time_counters.fixes_accepted, 3u);
  EXPECT_EQ(reversed_counters.fixes_accepted, 3u);
  EXPECT_EQ(reversed_counters.fixes_reset, on_time_counters.fixes_reset);
  // The later fix matters: with the early one alone the state differs by far more.
  const ap::EngineState early_only = runTwoFixes(config, 0.6, 10.0, early_only_counters);
  EXPECT_GT(ap::rotationAngle(early_only.q_WB, reversed.q_WB), 1e-3);
}

INSTANTIATE_TEST_SUITE_P(
    EveryIntegratorAndMode, LateFix,
    ::testing::Values(ReplayCase{ap::Integrator::Euler, ap::FixMode::Fuse, false},
                      ReplayCase{ap::Integrator::Euler, ap::FixMode::Reset, false},
                      ReplayCase{ap::Integrator::Rk4, ap::FixMode::Fuse, false},
                      ReplayCase{ap::Integrator::Rk4, ap::FixMode::Reset, false},
                      ReplayCase{ap::Integrator::Exp, ap::FixMode::Fuse, false},
                      ReplayCase{ap::Integrator::Exp, ap::FixMode::Reset, false},
                      ReplayCase{ap::Integrator::Exp2, ap::FixMode::Fuse, false},
                      ReplayCase{ap::Integrator::Exp2, ap::FixMode::Reset, false},
                      ReplayCase{ap::Integrator::Cf4, ap::FixMode::Fuse, false},
                      ReplayCase{ap::Integrator::Cf4, ap::FixMode::Reset, false},
                      ReplayCase{ap::Integrator::Cf4, ap::FixMode::Fuse, true},
                      ReplayCase{ap::Integrator::Exp2, ap::FixMode::Reset, true}));

// A fix stamped ahead of the newest rate waits, and is applied when the rates reach it: the
// same as handing it in then.
TEST(LateFix, AFixAheadOfTheRatesWaits) {
  const ap::EngineConfig config = fixConfig(ap::Integrator::Cf4, ap::FixMode::Fuse, false);
  Recorder early_sink;
  ap::EngineState early_state;
  {
    const ap::ConingMotion cone;
    ap::AttitudeEngine engine(config, early_sink);
    const Eigen::Matrix3d R = engine_fixtures::correlatedFixCovariance();
    const Eigen::Quaterniond offset = ap::expMap(Eigen::Vector3d(0.02, -0.01, 0.015));
    for (int k = 0; k <= 200; ++k) {
      const double t = 0.005 * k;
      engine.submit(rate(t, cone.bodyRate(t)));
      if (k == 20) engine.submitFix(at(0.1), cone.attitude(0.1) * offset, R);
      if (k == 60) {
        EXPECT_EQ(engine.submitFix(at(0.5025), cone.attitude(0.5025) * offset.conjugate(), R),
                  ap::FixOutcome::Waiting);
        EXPECT_EQ(engine.pendingFixes(), 1u);
      }
    }
    EXPECT_EQ(engine.pendingFixes(), 0u);
    EXPECT_EQ(engine.counters().fixes_accepted, 2u);
    early_state = engine.state();
  }
  Recorder on_time_sink;
  const ap::EngineState on_time = runWithFix(config, 0.5025, 0.505, on_time_sink);
  EXPECT_LE(ap::rotationAngle(on_time.q_WB, early_state.q_WB), 1e-12);
}

TEST(LateFix, TheWaitingQueueIsBounded) {
  Recorder sink;
  ap::AttitudeEngine engine(fixConfig(ap::Integrator::Exp, ap::FixMode::Fuse, false), sink);
  engine.submit(rate(0.0, Eigen::Vector3d::Zero()));
  const Eigen::Matrix3d R = 1e-4 * Eigen::Matrix3d::Identity();
  for (std::size_t j = 0; j < ap::kMaxPendingFixes; ++j) {
    EXPECT_EQ(engine.submitFix(at(0.1 + 0.01 * j), Eigen::Quaterniond::Identity(), R),
              ap::FixOutcome::Waiting);
  }
  EXPECT_EQ(engine.submitFix(at(0.5), Eigen::Quaterniond::Identity(), R),
            ap::FixOutcome::QueueFull);
  EXPECT_EQ(engine.submitFix(at(0.05), Eigen::Quaterniond::Identity(), R),
            ap::FixOutcome::Waiting);  // nearer: the furthest ahead goes instead
  EXPECT_EQ(engine.counters().fixes_queue_full, 2u);
  EXPECT_EQ(engine.pendingFixes(), ap::kMaxPendingFixes);
}

// The rule of every input (design.md §6.5): a fix stamped more than max_future ahead of a known
// clock is refused and counted, never left waiting for rates that may not come.
TEST(LateFix, AFixBeyondMaxFutureIsRefusedNotQueued) {
  Recorder sink;
  ap::EngineConfig config = fixConfig(ap::Integrator::Exp, ap::FixMode::Fuse, false);
  config.max_future = 1.0;
  ap::AttitudeEngine engine(config, sink);
  engine.submit(rate(0.0, Eigen::Vector3d::Zero()));
  engine.poll(at(0.0));
  const Eigen::Matrix3d R = 1e-4 * Eigen::Matrix3d::Identity();
  EXPECT_EQ(engine.submitFix(at(3600.0), Eigen::Quaterniond::Identity(), R),
            ap::FixOutcome::Future);
  EXPECT_EQ(engine.submitFix(at(1.0 + 1e-9), Eigen::Quaterniond::Identity(), R),
            ap::FixOutcome::Future);
  EXPECT_EQ(engine.counters().fixes_future, 2u);
  EXPECT_EQ(engine.pendingFixes(), 0u);
  EXPECT_EQ(engine.submitFix(at(1.0), Eigen::Quaterniond::Identity(), R),
            ap::FixOutcome::Waiting);  // at the bound
  EXPECT_STREQ(ap::fixOutcomeName(ap::FixOutcome::Future), "future");
}

// ---- the update itself against its closed form -----------------------------------------------

// P = p I and R = rho I: K = p / (p + rho) I, the estimate moves that fraction of the
// innovation in the body frame, P becomes p rho / (p + rho) I (numerics.md §7.1).
TEST(FixUpdate, FuseIsTheKalmanUpdateInTheBodyFrame) {
  ap::EngineConfig config = fixConfig(ap::Integrator::Exp, ap::FixMode::Fuse, false);
  config.rate_stddev = 0.0;
  config.initial_orientation_stddev = 0.03;
  const Eigen::Quaterniond q0 = aboutAxis(Eigen::Vector3d(0.3, -1.0, 0.5), 2.0);
  config.kinematic.initial_q_WB = q0;
  Recorder sink;
  ap::AttitudeEngine engine(config, sink);
  engine.submit(rate(0.0, Eigen::Vector3d::Zero()));
  const double p = 0.03 * 0.03, rho = 0.02 * 0.02;
  const Eigen::Vector3d v(0.01, -0.02, 0.005);
  EXPECT_EQ(engine.submitFix(at(0.0), q0 * ap::expMap(v), rho * Eigen::Matrix3d::Identity()),
            ap::FixOutcome::Accepted);
  const Eigen::Quaterniond expected = q0 * ap::expMap(p / (p + rho) * v);
  EXPECT_LE(ap::rotationAngle(engine.state().q_WB, expected), 1e-14);
  EXPECT_LE((engine.state().P_B - p * rho / (p + rho) * Eigen::Matrix3d::Identity())
                .cwiseAbs()
                .maxCoeff(),
            1e-18);
  // reset: the fix's attitude and covariance.
  config.fixes.mode = ap::FixMode::Reset;
  Recorder reset_sink;
  ap::AttitudeEngine reset(config, reset_sink);
  reset.submit(rate(0.0, Eigen::Vector3d::Zero()));
  EXPECT_EQ(reset.submitFix(at(0.0), q0 * ap::expMap(v), rho * Eigen::Matrix3d::Identity()),
            ap::FixOutcome::Reset);
  EXPECT_LE(ap::rotationAngle(reset.state().q_WB, q0 * ap::expMap(v)), 1e-14);
  EXPECT_LE((reset.state().P_B - rho * Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff(), 1e-18);
}

// A constant rate about z: the attitude is known in closed form at every instant, and the
// geodesic between two states is exact. A reset with the truth between two samples, after a
// wrong start, must leave the newest state on the truth.
TEST(FixUpdate, AFixBetweenSamplesActsAtItsOwnStamp) {
  const Eigen::Vector3d w(0.0, 0.0, 2.0);
  auto truth = [&w](double t) { return ap::expMap(w * t); };
  ap::EngineConfig config = fixConfig(ap::Integrator::Exp, ap::FixMode::Reset, false);
  config.kinematic.initial_q_WB = aboutAxis(Eigen::Vector3d::UnitX(), 0.3);  // wrong
  Recorder sink;
  ap::AttitudeEngine engine(config, sink);
  const Eigen::Matrix3d R = 1e-6 * Eigen::Matrix3d::Identity();
  for (int k = 0; k <= 100; ++k) {
    engine.submit(rate(0.01 * k, w));
    if (k == 0) engine.submitFix(at(0.0), config.kinematic.initial_q_WB, R);
    if (k == 40) {
      EXPECT_EQ(engine.submitFix(at(0.2537), truth(0.2537), R), ap::FixOutcome::Reset);
    }
  }
  EXPECT_LE(ap::rotationAngle(engine.state().q_WB, truth(1.0)), 1e-12);
}

// cf4 integrates its first intervals again from the anchor once its window is full: a fix in
// between must survive that re-integration.
TEST(FixUpdate, AFixDuringTheStartUpOfCf4Survives) {
  const Eigen::Vector3d w(0.4, -0.3, 1.1);
  // A true start that does not commute with the configured one, so a correction turned on the
  // wrong side of cf4's start-up anchor shows.
  const Eigen::Quaterniond q0 = aboutAxis(Eigen::Vector3d::UnitX(), 0.3);
  auto truth = [&w, &q0](double t) { return q0 * ap::expMap(w * t); };
  for (int fix_at : {0, 1}) {
    ap::EngineConfig config = fixConfig(ap::Integrator::Cf4, ap::FixMode::Reset, false);
    config.kinematic.initial_q_WB = aboutAxis(Eigen::Vector3d::UnitY(), 0.5);  // wrong
    Recorder sink;
    ap::AttitudeEngine engine(config, sink);
    const Eigen::Matrix3d R = 1e-6 * Eigen::Matrix3d::Identity();
    for (int k = 0; k <= 50; ++k) {
      engine.submit(rate(0.01 * k, w));
      // At the anchor or the sample after, before cf4 has the samples for its re-integration
      // from the anchor.
      if (k == fix_at) {
        EXPECT_EQ(engine.submitFix(at(0.01 * k), truth(0.01 * k), R), ap::FixOutcome::Reset);
      }
    }
    EXPECT_LE(ap::rotationAngle(engine.state().q_WB, truth(0.5)), 1e-10) << fix_at;
  }
}

// ---- (b), (c): a simulated gyro on the coning motion -----------------------------------------

TEST(GyroWithFixes, FuseWithBiasEstimateMeetsTheTargets) {
  const GyroRun run = simulateGyro(600.0, true, true, 0.0);
  std::printf(
      "[ fixes    ] rms after 60 s %.3g rad, mean NEES %.3f, bias error %.3g deg/h at "
      "120 s, %.3g deg/h at 600 s, %llu fixes accepted, %llu rejected\n",
      run.rms_after_60, run.mean_nees, run.bias_error_120 / kDegPerHour,
      run.bias_error_end / kDegPerHour,
      static_cast<unsigned long long>(run.counters.fixes_accepted),
      static_cast<unsigned long long>(run.counters.fixes_rejected_gate));
  EXPECT_LE(run.rms_after_60, 0.5 * 1e-3);
  EXPECT_LE(run.bias_error_120, 2.0 * kDegPerHour);
  EXPECT_LE(run.bias_error_end, 1.0 * kDegPerHour);
  EXPECT_GE(run.mean_nees, 1.5);
  EXPECT_LE(run.mean_nees, 4.5);
  // The history starts with the first fix, which arrives 150 ms late: too old.
  EXPECT_EQ(run.counters.fixes_too_old, 1u);
  EXPECT_EQ(run.counters.fixes_reset, 0u);
  EXPECT_GE(run.counters.fixes_accepted, 2990u);
}

// Over the accepted range of gyro_bias_stddev and gyro_bias_random_walk the estimate moves to
// the bias: a constant rate w plus a bias b at 100 Hz, fixes of the truth Exp(w t) at 10 Hz; the
// standard deviation it reports never exceeds the parameter's maximum (limits.h), with fixes or
// without (a random walk of 1000 rad/s/sqrt(s) for 10 s would reach 3162 rad/s).
TEST(GyroWithFixes, TheBiasEstimateMovesOverTheAcceptedRange) {
  const Eigen::Vector3d w(0.3, -0.2, 0.5), b(0.02, -0.01, 0.03);
  struct Case {
    double stddev, random_walk;
    bool fixes;
  };
  for (const Case c :
       {Case{ap::kMaxGyroBiasStddev, 0.0, true}, Case{1e-3, ap::kMaxRateStddev, true},
        Case{ap::kMaxGyroBiasStddev, ap::kMaxRateStddev, false}}) {
    SCOPED_TRACE(testing::Message() << c.stddev << " " << c.random_walk << " " << c.fixes);
    ap::EngineConfig config = fixConfig(ap::Integrator::Exp, ap::FixMode::Fuse, true);
    config.fixes.gyro_bias_stddev = c.stddev;
    config.fixes.gyro_bias_random_walk = c.random_walk;
    Recorder sink;
    ap::AttitudeEngine engine(config, sink);
    const Eigen::Matrix3d R = 1e-10 * Eigen::Matrix3d::Identity();
    for (int k = 0; k <= 1000; ++k) {
      const double t = 0.01 * k;
      engine.submit(rate(t, w + b));
      if (c.fixes && k % 10 == 0) engine.submitFix(at(t), ap::expMap(w * t), R);
      ASSERT_LE(engine.gyroBiasStddev().maxCoeff(), ap::kMaxGyroBiasStddev) << t;
    }
    if (c.fixes) {
      EXPECT_LE((engine.gyroBiasEstimate() - b).norm(), 0.05 * b.norm());
      EXPECT_GE(engine.counters().fixes_accepted, 95u);
    }
  }
}

// The shape of the recordings' bias benchmark (docs/real_data.md, bench/real_bias.sh) on a
// closed form: a constant rate w, truth Exp(w t); a gyro reading w + b plus white noise at
// 100 Hz; an "AHRS" reading the truth through its own white noise and, 5 s in every 60 s, a
// heading 0.5 rad off; one of its readings per second as a fix, stamped at the reading and
// handed in 0.1 s later; the bias settings of config/default.yaml. Where the gyro has a bias,
// estimating it lowers the error against the truth at every published state after the first
// 60 s, and the estimate ends within 4 of its own standard deviations of b; where it has none,
// the estimate ends within 4 of them of zero.
struct AhrsRun {
  double rms = 0.0;
  Eigen::Vector3d bias = Eigen::Vector3d::Zero(), stddev = Eigen::Vector3d::Zero();
};

/// The body's motion: its body rate and its attitude, a closed form of each other.
struct AhrsMotion {
  std::function<Eigen::Vector3d(double)> rate;
  std::function<Eigen::Quaterniond(double)> attitude;
};

AhrsMotion constantRate() {
  const Eigen::Vector3d w(0.1, -0.05, 0.2);
  return {[w](double) { return w; }, [w](double t) { return ap::expMap(w * t); }};
}

/// A cone 1 rad wide, turned once in 12.6 s: the body's axes sweep every direction of the world,
/// so a bias estimated or subtracted in the wrong frame does not stay a constant there.
AhrsMotion wideCone() {
  ap::ConingMotion cone;
  cone.beta = 1.0;
  cone.omega = 0.5;
  return {[cone](double t) { return cone.bodyRate(t); },
          [cone](double t) { return cone.attitude(t); }};
}

AhrsRun runWithLateAhrs(const Eigen::Vector3d& b, bool estimate,
                        const AhrsMotion& motion = constantRate()) {
  constexpr double kGyroNoise = 0.003, kAhrsNoise = 0.02, kRate = 100.0, kDuration = 300.0;
  ap::EngineConfig config = fixConfig(ap::Integrator::Exp, ap::FixMode::Fuse, estimate);
  config.rate_stddev = kGyroNoise;
  config.fixes.gyro_bias_stddev = 0.01;
  config.fixes.gyro_bias_random_walk = 1e-5;
  Recorder sink;
  ap::AttitudeEngine engine(config, sink);
  std::mt19937 random(7);
  std::normal_distribution<double> gyro(0.0, kGyroNoise), ahrs(0.0, kAhrsNoise);
  const Eigen::Matrix3d R = kAhrsNoise * kAhrsNoise * Eigen::Matrix3d::Identity();
  const auto& truth = motion.attitude;
  struct Due {
    double t;
    Eigen::Quaterniond q;
  };
  std::vector<Due> due;
  const int samples = static_cast<int>(kDuration * kRate);
  for (int k = 0; k <= samples; ++k) {
    const double t = k / kRate;
    engine.submit(
        rate(t, motion.rate(t) + b + Eigen::Vector3d(gyro(random), gyro(random), gyro(random))));
    for (auto f = due.begin(); f != due.end();) {
      if (t >= f->t + 0.1 - 1e-9) {
        engine.submitFix(at(f->t), f->q, R);
        f = due.erase(f);
      } else {
        ++f;
      }
    }
    if (k % static_cast<int>(kRate) == 0) {
      const double heading = std::fmod(t, 60.0) > 30.0 && std::fmod(t, 60.0) < 35.0 ? 0.5 : 0.0;
      const Eigen::Vector3d n(ahrs(random), ahrs(random), ahrs(random));
      due.push_back({t, ap::expMap(Eigen::Vector3d(0.0, 0.0, heading)) * truth(t) * ap::expMap(n)});
    }
  }
  double sum = 0.0;
  int n = 0;
  for (const ap::EngineState& s : sink.states) {
    const double t = static_cast<double>(s.stamp - at(0.0)) * 1e-9;
    if (t < 60.0) continue;
    const double e = ap::rotationAngle(s.q_WB, truth(t));
    sum += e * e;
    ++n;
  }
  EXPECT_GE(n, static_cast<int>(0.9 * (kDuration - 60.0) * kRate));
  return {std::sqrt(sum / std::max(1, n)), engine.gyroBiasEstimate(), engine.gyroBiasStddev()};
}

TEST(GyroWithFixes, ALateOncePerSecondAhrsTeachesTheBiasThereIs) {
  const Eigen::Vector3d b(0.002, -0.003, 0.004);
  const AhrsRun without = runWithLateAhrs(b, false), with = runWithLateAhrs(b, true);
  std::printf(
      "[ fixes    ] 1 Hz AHRS 0.1 s late: rms %.4g rad with the estimate, %.4g without; "
      "estimate %.3g %.3g %.3g rad/s\n",
      with.rms, without.rms, with.bias.x(), with.bias.y(), with.bias.z());
  EXPECT_LT(with.rms, without.rms);
  for (int i = 0; i < 3; ++i) EXPECT_LE(std::abs(with.bias(i) - b(i)), 4.0 * with.stddev(i)) << i;
  const AhrsRun unbiased = runWithLateAhrs(Eigen::Vector3d::Zero(), true);
  for (int i = 0; i < 3; ++i) EXPECT_LE(std::abs(unbiased.bias(i)), 4.0 * unbiased.stddev(i)) << i;
}

// The same on a wide cone, where the body's axes turn through the world: the bias is the body's
// (the gyro's), so it is learned, and its estimate helps, only if it is estimated and subtracted
// in the body frame all along.
TEST(GyroWithFixes, ALateAhrsTeachesTheBodyFramesBiasOnAWideCone) {
  const Eigen::Vector3d b(0.002, -0.003, 0.004);
  const AhrsRun without = runWithLateAhrs(b, false, wideCone());
  const AhrsRun with = runWithLateAhrs(b, true, wideCone());
  std::printf(
      "[ fixes    ] wide cone, 1 Hz AHRS 0.1 s late: rms %.4g rad with the estimate, %.4g "
      "without; estimate %.3g %.3g %.3g rad/s\n",
      with.rms, without.rms, with.bias.x(), with.bias.y(), with.bias.z());
  EXPECT_LT(with.rms, without.rms);
  for (int i = 0; i < 3; ++i) EXPECT_LE(std::abs(with.bias(i) - b(i)), 4.0 * with.stddev(i)) << i;
  // The cone's turns average a world-frame bias out: the estimate sees each body axis' own.
  EXPECT_LE(with.stddev.maxCoeff(), 0.25 * b.cwiseAbs().minCoeff());
}

// Without fixes the attitude drifts as the bias integrated along the true attitude says:
// Log(q_est q_true^-1) = int C_WB(t) b dt, to the angle random walk (0.1 deg/sqrt(h) over 600 s
// is 0.7 mrad) and second-order terms.
TEST(GyroWithFixes, WithoutFixesItDriftsAsTheBiasSays) {
  const GyroRun run = simulateGyro(600.0, false, false, 0.0);
  std::printf("[ fixes    ] drift %.4g rad, predicted %.4g rad\n", run.final_error_W.norm(),
              run.predicted_drift_W.norm());
  EXPECT_GT(run.predicted_drift_W.norm(), 0.01);
  EXPECT_LE((run.final_error_W - run.predicted_drift_W).norm(),
            0.02 * run.predicted_drift_W.norm() + 3e-3);
}

// (c) 5 % of the fixes 0.5 rad off: each one rejected by the gate, and the attitude as good as
// without them (the same good fixes less the outliers).
TEST(GyroWithFixes, OutliersAreRejected) {
  const GyroRun clean = simulateGyro(120.0, true, true, 0.0);
  const GyroRun dirty = simulateGyro(120.0, true, true, 0.05);
  ASSERT_GE(dirty.outlier_outcomes.size(), 15u);
  for (ap::FixOutcome o : dirty.outlier_outcomes) EXPECT_EQ(o, ap::FixOutcome::RejectedGate);
  EXPECT_GE(dirty.counters.fixes_rejected_gate, dirty.outlier_outcomes.size());
  EXPECT_EQ(dirty.counters.fixes_reset, 0u);
  std::printf("[ fixes    ] rms %.3g rad with outliers, %.3g rad without\n", dirty.rms_after_60,
              clean.rms_after_60);
  EXPECT_LE(dirty.rms_after_60, 1.2 * clean.rms_after_60);
}

// After kFixRejectionRun fixes in a row rejected by the gate, the next one that fails resets.
TEST(GyroWithFixes, ARunOfRejectionsEndsInAReset) {
  ap::EngineConfig config = fixConfig(ap::Integrator::Exp, ap::FixMode::Fuse, false);
  config.rate_stddev = 0.0;
  config.initial_orientation_stddev = 0.001;
  Recorder sink;
  ap::AttitudeEngine engine(config, sink);
  const Eigen::Matrix3d R = 1e-6 * Eigen::Matrix3d::Identity();
  const Eigen::Quaterniond truth = aboutAxis(Eigen::Vector3d::UnitZ(), 1.0);  // far off
  for (int k = 0; k <= ap::kFixRejectionRun; ++k) {
    engine.submit(rate(0.01 * k, Eigen::Vector3d::Zero()));
    const ap::FixOutcome expected =
        k < ap::kFixRejectionRun ? ap::FixOutcome::RejectedGate : ap::FixOutcome::Reset;
    EXPECT_EQ(engine.submitFix(at(0.01 * k), truth, R), expected) << k;
  }
  EXPECT_EQ(engine.counters().fixes_rejected_gate,
            static_cast<std::uint64_t>(ap::kFixRejectionRun));
  EXPECT_EQ(engine.counters().fixes_reset, 1u);
  EXPECT_LE(ap::rotationAngle(engine.state().q_WB, truth), 1e-14);
}

// ---- (d) bad fixes ---------------------------------------------------------------------------

TEST(BadFixes, EachIsRejectedCountedAndTheStateUntouched) {
  ap::EngineConfig config = fixConfig(ap::Integrator::Cf4, ap::FixMode::Fuse, true);
  Recorder sink;
  ap::AttitudeEngine engine(config, sink);
  const ap::ConingMotion cone;
  for (int k = 0; k <= 40; ++k) engine.submit(rate(0.005 * k, cone.bodyRate(0.005 * k)));
  const Eigen::Matrix3d R = 1e-4 * Eigen::Matrix3d::Identity();
  const Eigen::Quaterniond q = cone.attitude(0.1);
  const double nan = std::nan("");
  struct Bad {
    Eigen::Quaterniond q;
    Eigen::Matrix3d R;
    ap::FixOutcome outcome;
  };
  Eigen::Matrix3d asymmetric = R, negative = R, huge = R, correlated = R, non_finite = R;
  asymmetric(0, 1) = 1e-5;
  negative(2, 2) = -1e-4;
  huge(1, 1) = 10.0;  // above pi^2
  correlated(0, 1) = correlated(1, 0) = 2e-4;
  non_finite(0, 0) = nan;
  const std::vector<Bad> bad{
      {Eigen::Quaterniond(nan, 0, 0, 0), R, ap::FixOutcome::BadQuaternion},
      {Eigen::Quaterniond(1.1, 0, 0, 0), R, ap::FixOutcome::BadQuaternion},
      {Eigen::Quaterniond(0, 0, 0, 0), R, ap::FixOutcome::BadQuaternion},
      {Eigen::Quaterniond(1.0, 0, 0, 1e-300 * 1e10), non_finite, ap::FixOutcome::BadCovariance},
      {q, asymmetric, ap::FixOutcome::BadCovariance},
      {q, negative, ap::FixOutcome::BadCovariance},
      {q, huge, ap::FixOutcome::BadCovariance},
      {q, correlated, ap::FixOutcome::BadCovariance},
  };
  const ap::EngineState before = engine.state();
  for (const Bad& b : bad) {
    EXPECT_EQ(engine.submitFix(at(0.1), b.q, b.R), b.outcome) << ap::fixOutcomeName(b.outcome);
  }
  // Too old: before the history started (the first fix starts it).
  EXPECT_EQ(engine.submitFix(at(0.1), q, R), ap::FixOutcome::TooOld);
  const ap::EngineState after = engine.state();
  EXPECT_EQ(after.q_WB.coeffs(), before.q_WB.coeffs());
  EXPECT_EQ(after.P_B, before.P_B);
  EXPECT_EQ(after.gyro_bias_estimate_B, before.gyro_bias_estimate_B);
  EXPECT_EQ(after.gyro_bias_stddev_B, before.gyro_bias_stddev_B);
  const ap::EngineCounters& c = engine.counters();
  EXPECT_EQ(c.fixes_bad_quaternion, 3u);
  EXPECT_EQ(c.fixes_bad_covariance, 5u);
  EXPECT_EQ(c.fixes_too_old, 1u);
  EXPECT_EQ(c.fixes_accepted, 0u);
  EXPECT_STREQ(ap::fixOutcomeName(ap::FixOutcome::BadCovariance), "bad_covariance");
}

// ---- (e) the history's bounds ----------------------------------------------------------------

TEST(FixHistory, AFixExactlyFixHistoryOldIsTakenOneNanosecondOlderIsNot) {
  ap::EngineConfig config = fixConfig(ap::Integrator::Exp2, ap::FixMode::Fuse, false);
  config.fixes.history = 0.5;
  Recorder sink;
  ap::AttitudeEngine engine(config, sink);
  const Eigen::Matrix3d R = 1e-4 * Eigen::Matrix3d::Identity();
  const Eigen::Vector3d w(0.1, 0.2, -0.3);
  for (int k = 0; k <= 200; ++k) {
    engine.submit(rate(0.005 * k, w));
    if (k == 0) engine.submitFix(at(0.0), Eigen::Quaterniond::Identity(), R);
  }
  // The newest rate is at 1.0 s.
  const Eigen::Quaterniond q = ap::expMap(0.5 * w);
  EXPECT_EQ(engine.submitFix(at(0.5) - 1, q, R), ap::FixOutcome::TooOld);
  EXPECT_EQ(engine.submitFix(at(0.5), q, R), ap::FixOutcome::Accepted);
  EXPECT_EQ(engine.submitFix(at(0.5) + 1, q, R), ap::FixOutcome::Accepted);
  EXPECT_EQ(engine.counters().fixes_too_old, 1u);
  EXPECT_LE(engine.fixHistorySize(), 102u);
}

// A fix stamped before kMaxFixesReapplied applied fixes is applied (and they again after it);
// before one more it is too old, counted, and the state untouched. Reset mode, the fixes on the
// closed form of a constant rate, so no gate decides.
TEST(FixHistory, AnEarlierFixIsAppliedBeforeAtMostEightLaterOnes) {
  ASSERT_EQ(ap::kMaxFixesReapplied, 8u);
  const ap::EngineConfig config = fixConfig(ap::Integrator::Exp2, ap::FixMode::Reset, false);
  Recorder sink;
  ap::AttitudeEngine engine(config, sink);
  const Eigen::Matrix3d R = 1e-4 * Eigen::Matrix3d::Identity();
  const Eigen::Vector3d w(0.1, 0.2, -0.3);
  auto truth = [&w](double t) { return ap::expMap(t * w); };
  for (int k = 0; k <= 200; ++k) {
    engine.submit(rate(0.005 * k, w));
    if (k == 0) engine.submitFix(at(0.0), truth(0.0), R);  // starts the history
  }
  // Nine more, in order: at 0.5 s, then eight from 0.55 s.
  ASSERT_EQ(engine.submitFix(at(0.5), truth(0.5), R), ap::FixOutcome::Reset);
  for (int i = 0; i < 8; ++i) {
    const double t = 0.55 + 0.04 * i;
    ASSERT_EQ(engine.submitFix(at(t), truth(t), R), ap::FixOutcome::Reset) << t;
  }
  // One nanosecond before the fix at 0.5 s: nine applied fixes after it.
  const ap::EngineState before = engine.state();
  EXPECT_EQ(engine.submitFix(at(0.5) - 1, truth(0.5) * ap::expMap({0.1, 0, 0}), R),
            ap::FixOutcome::TooOld);
  EXPECT_EQ(engine.counters().fixes_too_old, 1u);
  EXPECT_EQ(engine.state().q_WB.coeffs(), before.q_WB.coeffs());
  // At 0.5 s itself, after the fix there (equal stamps keep their order of arrival): eight.
  EXPECT_EQ(engine.submitFix(at(0.5), truth(0.5), R), ap::FixOutcome::Reset);
  EXPECT_EQ(engine.counters().fixes_accepted, 11u);
  EXPECT_LE(ap::rotationAngle(engine.state().q_WB, truth(1.0)), 1e-12);
}

// Two fixes of the same stamp act in their order of arrival, as they would on time: in reset
// mode the second one's attitude is the state, whether a fix stamped earlier arrives after
// both or not.
TEST(FixHistory, FixesOfEqualStampsKeepTheirOrderOfArrival) {
  const ap::EngineConfig config = fixConfig(ap::Integrator::Exp2, ap::FixMode::Reset, false);
  const Eigen::Matrix3d R = 1e-4 * Eigen::Matrix3d::Identity();
  const Eigen::Vector3d w(0.1, 0.2, -0.3);
  auto truth = [&w](double t) { return ap::expMap(t * w); };
  const Eigen::Quaterniond first = truth(0.5) * ap::expMap({0.05, 0, 0});
  for (bool earlier_after : {false, true}) {
    Recorder sink;
    ap::AttitudeEngine engine(config, sink);
    for (int k = 0; k <= 200; ++k) {
      engine.submit(rate(0.005 * k, w));
      if (k == 0) engine.submitFix(at(0.0), truth(0.0), R);
    }
    engine.submitFix(at(0.5), first, R);
    engine.submitFix(at(0.5), truth(0.5), R);
    if (earlier_after) engine.submitFix(at(0.3), truth(0.3), R);
    EXPECT_LE(ap::rotationAngle(engine.state().q_WB, truth(1.0)), 1e-12) << earlier_after;
  }
}

TEST(FixHistory, TheMemoryBoundCapsTheInputsKept) {
  ap::EngineConfig config = fixConfig(ap::Integrator::Exp, ap::FixMode::Fuse, false);
  config.fixes.history = ap::kMaxFixHistory;
  config.kinematic.time_policy.max_dt = 1.0;
  Recorder sink;
  ap::AttitudeEngine engine(config, sink);
  const Eigen::Matrix3d R = 1e-4 * Eigen::Matrix3d::Identity();
  const double h = 0.001;  // 1 kHz: 10 s would be 10 000 inputs
  const int steps = 6000;
  for (int k = 0; k <= steps; ++k) {
    engine.submit(rate(h * k, Eigen::Vector3d::Zero()));
    if (k == 0) engine.submitFix(at(0.0), Eigen::Quaterniond::Identity(), R);
  }
  EXPECT_EQ(engine.fixHistorySize(), ap::kMaxFixHistorySamples);
  const double oldest_kept = h * (steps - static_cast<double>(ap::kMaxFixHistorySamples) + 1);
  EXPECT_EQ(engine.submitFix(at(oldest_kept - h), Eigen::Quaterniond::Identity(), R),
            ap::FixOutcome::TooOld);
  EXPECT_EQ(engine.submitFix(at(oldest_kept), Eigen::Quaterniond::Identity(), R),
            ap::FixOutcome::Accepted);
  std::printf("[ fixes    ] one history entry: %zu bytes; at most %zu entries: %.2f MB\n",
              sizeof(ap::FixHistoryEntry), ap::kMaxFixHistorySamples,
              static_cast<double>(sizeof(ap::FixHistoryEntry) * ap::kMaxFixHistorySamples) / 1e6);
}

TEST(FixHistory, ParametersOutsideTheirRangesRefuseStart) {
  auto refused = [](const std::function<void(ap::Parameters&)>& set, const std::string& name) {
    ap::Parameters p;
    set(p);
    try {
      ap::validateParameters(p);
    } catch (const std::invalid_argument& e) {
      const std::string what = e.what();
      EXPECT_EQ(what.rfind(name + ":", 0), 0u) << what;
      EXPECT_NE(what.find("accepted"), std::string::npos) << what;
      return true;
    }
    return false;
  };
  EXPECT_TRUE(refused([](ap::Parameters& p) { p.fix_stddev = 0.0; }, "fix_stddev"));
  EXPECT_TRUE(refused([](ap::Parameters& p) { p.gyro_bias_stddev = -1e-9; }, "gyro_bias_stddev"));
  EXPECT_TRUE(refused([](ap::Parameters& p) { p.fix_history = 10.001; }, "fix_history"));
  EXPECT_TRUE(refused([](ap::Parameters& p) { p.fix_history = 0.0; }, "fix_history"));
  EXPECT_TRUE(refused([](ap::Parameters& p) { p.fix_gate = 0.0; }, "fix_gate"));
  EXPECT_TRUE(refused([](ap::Parameters& p) { p.fix_mode = "replace"; }, "fix_mode"));
  EXPECT_TRUE(
      refused([](ap::Parameters& p) { p.gyro_bias_random_walk = -1.0; }, "gyro_bias_random_walk"));
  EXPECT_TRUE(refused(
      [](ap::Parameters& p) {
        p.estimate_gyro_bias = true;
        p.inertia = {1.0, 2.0, 3.0};
      },
      "estimate_gyro_bias"));
  EXPECT_FALSE(refused([](ap::Parameters& p) { p.fix_history = ap::kMaxFixHistory; }, ""));
  ap::Parameters p;
  p.fix_mode = "reset";
  p.estimate_gyro_bias = true;
  const ap::EngineConfig c = ap::engineConfig(ap::validateParameters(p));
  EXPECT_EQ(c.fixes.mode, ap::FixMode::Reset);
  EXPECT_TRUE(c.fixes.estimate_gyro_bias);
  // MEMS-sized defaults (docs/parameters.md): a prior of 0.57 deg/s covers the zero-rate offsets
  // MEMS gyros specify (0.5 to 5 deg/s before, well under 1 deg/s after a calibration at rest).
  EXPECT_DOUBLE_EQ(c.fixes.gyro_bias_stddev, 0.01);
  EXPECT_NEAR(c.fixes.gyro_bias_stddev * 180.0 / M_PI, 0.573, 0.001);
  EXPECT_DOUBLE_EQ(c.fixes.gyro_bias_random_walk, 1e-5);
  // The engine's own defaults are the parameters': one default, whichever way it is built.
  EXPECT_DOUBLE_EQ(ap::FixConfig{}.gyro_bias_stddev, c.fixes.gyro_bias_stddev);
  EXPECT_DOUBLE_EQ(ap::FixConfig{}.gyro_bias_random_walk, c.fixes.gyro_bias_random_walk);
}

// The cost of a replay: a fix 1 s late on a 200 Hz stream replays 200 inputs. Printed, not
// asserted (docs/benchmarks.md has no timing assertions in tests either). 20 of them at one
// instant stay within the replay budget of their second (replay_budget.h: 4096 + 20 x 200).
TEST(FixHistory, PrintsTheCostOfAOneSecondReplay) {
  ap::EngineConfig config = fixConfig(ap::Integrator::Cf4, ap::FixMode::Fuse, true);
  config.fixes.history = 1.5;
  Recorder sink;
  ap::AttitudeEngine engine(config, sink);
  const ap::ConingMotion cone;
  const Eigen::Matrix3d R = 1e-4 * Eigen::Matrix3d::Identity();
  double t = 0.0;
  for (int k = 0; k <= 300; ++k, t = 0.005 * k) {
    engine.submit(rate(t, cone.bodyRate(t)));
    if (k == 0) engine.submitFix(at(0.0), cone.attitude(0.0), R);
  }
  const int repeats = 20;
  const auto start = std::chrono::steady_clock::now();
  for (int j = 0; j < repeats; ++j) {
    engine.submitFix(at(0.5), cone.attitude(0.5), R);  // the newest is at 1.5 s
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("[ fixes    ] a 1 s replay at 200 Hz (cf4, bias estimated): %.1f us\n",
              1e6 * seconds / repeats);
  EXPECT_EQ(engine.counters().fixes_accepted, static_cast<std::uint64_t>(repeats + 1));
}

}  // namespace
