// Every documented boundary of the core, on both sides: just inside is accepted, just outside is
// refused with the documented counter or message. The truths are the tables of docs/design.md:
// the time policy (§6), the door bounds of limits.h (§7.2), the covariance rules (§7.3) and the
// parameter ranges (§7.7, docs/parameters.md). A boundary stated with "at most" is inclusive, "more
// than" exclusive; the value just outside is the neighbouring double (or the neighbouring
// nanosecond for stamps).
#include <cmath>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "attitude_propagator/config/parameters.h"
#include "attitude_propagator/engine.h"
#include "attitude_propagator/estimation/orientation_covariance.h"
#include "attitude_propagator/limits.h"
#include "attitude_propagator/models/dynamic_propagator.h"
#include "attitude_propagator/models/kinematic_propagator.h"
#include "attitude_propagator/numerics/rigid_body.h"
#include "attitude_propagator/time/publish_grid.h"
#include "engine_fixtures.h"
#include "refused_parameters.h"

namespace {

namespace ap = attitude_propagator;
using engine_fixtures::aboutAxis;
using engine_fixtures::at;
using engine_fixtures::kSecond;
using engine_fixtures::Recorder;

double up(double x) { return std::nextafter(x, std::numeric_limits<double>::infinity()); }
double down(double x) { return std::nextafter(x, -std::numeric_limits<double>::infinity()); }

ap::Input rateAt(ap::Stamp stamp, const Eigen::Vector3d& w_B = Eigen::Vector3d::Zero()) {
  return engine_fixtures::rate(stamp, w_B);
}

// ---- Parameters (docs/design.md §7.2, §7.7) --------------------------------------------------

/// A parameter's range: values that must pass the validator and values it must refuse, naming
/// the parameter.
struct Range {
  std::string name;
  std::function<void(ap::Parameters&, double)> set;
  std::vector<double> inside;
  std::vector<double> outside;
  std::function<ap::Parameters()> base = [] { return ap::Parameters{}; };
};

ap::Parameters dynamicBase(double max_dt) {
  ap::Parameters p;
  p.inertia = {1.0, 1.0, 1.0};
  p.max_dt = max_dt;
  return p;
}

void expectRange(const Range& r) {
  for (double v : r.inside) {
    ap::Parameters p = r.base();
    r.set(p, v);
    EXPECT_NO_THROW(ap::validateParameters(p)) << r.name << " = " << ap::formatParameter(v);
  }
  for (double v : r.outside) {
    SCOPED_TRACE(r.name + " = " + ap::formatParameter(v));
    ap::Parameters p = r.base();
    r.set(p, v);
    expectRefused(p, r.name);
  }
}

TEST(Boundaries, EveryScalarParameterRangeOnBothSides) {
  const double tiny = std::numeric_limits<double>::denorm_min();
  const double inf = std::numeric_limits<double>::infinity();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const std::vector<Range> ranges = {
      {"publish_rate",
       [](ap::Parameters& p, double v) { p.publish_rate = v; },
       {ap::kMaxPublishRate, tiny},
       {up(ap::kMaxPublishRate), 0.0, nan}},
      {"max_dt",
       [](ap::Parameters& p, double v) { p.max_dt = v; },
       {ap::kMinMaxDt, ap::kMaxMaxDt},
       {down(ap::kMinMaxDt), up(ap::kMaxMaxDt), inf}},
      {"max_step",
       [](ap::Parameters& p, double v) { p.max_step = v; },
       {0.0, ap::kMinMaxStep, ap::kMaxMaxDt},
       {down(ap::kMinMaxStep), up(ap::kMaxMaxDt), -tiny}},
      {"tolerance",
       [](ap::Parameters& p, double v) { p.tolerance = v; },
       {ap::kMinTolerance, ap::kMaxTolerance},
       {down(ap::kMinTolerance), up(ap::kMaxTolerance)}},
      {"torque_timeout",
       [](ap::Parameters& p, double v) { p.torque_timeout = v; },
       {0.0, ap::kMaxTorqueTimeout},
       {-tiny, up(ap::kMaxTorqueTimeout)}},
      // A time: non-positive is refused (parameters.md).
      {"max_future",
       [](ap::Parameters& p, double v) { p.max_future = v; },
       {tiny, ap::kMaxFuture},
       {0.0, -tiny, up(ap::kMaxFuture)}},
      {"angular_velocity_stddev",
       [](ap::Parameters& p, double v) { p.angular_velocity_stddev = v; },
       {0.0, ap::kMaxRateStddev},
       {-tiny, up(ap::kMaxRateStddev)}},
      // A standard deviation in rad, at most pi (not pi^2: the variance's ceiling).
      {"initial_orientation_stddev",
       [](ap::Parameters& p, double v) { p.initial_orientation_stddev = v; },
       {0.0, M_PI},
       {-tiny, up(M_PI)}},
      {"fix_history",
       [](ap::Parameters& p, double v) { p.fix_history = v; },
       {tiny, ap::kMaxFixHistory},
       {0.0, up(ap::kMaxFixHistory)}},
      {"fix_gate",
       [](ap::Parameters& p, double v) { p.fix_gate = v; },
       {tiny, std::numeric_limits<double>::max()},
       {0.0, inf, nan}},
      {"fix_stddev",
       [](ap::Parameters& p, double v) { p.fix_stddev = v; },
       {tiny, M_PI},
       {0.0, up(M_PI)}},
      {"gyro_bias_random_walk",
       [](ap::Parameters& p, double v) { p.gyro_bias_random_walk = v; },
       {0.0, ap::kMaxRateStddev},
       {-tiny, up(ap::kMaxRateStddev)}},
      // Where the estimate moves (limits.h): 300 rad/s and above turned it off.
      {"gyro_bias_stddev",
       [](ap::Parameters& p, double v) { p.gyro_bias_stddev = v; },
       {0.0, ap::kMaxGyroBiasStddev},
       {-tiny, up(ap::kMaxGyroBiasStddev), 300.0, ap::kMaxRateStddev}},
      // |w| at most kMaxBodyRate: the norm of (w, 0, 0) is w exactly.
      {"initial_angular_velocity",
       [](ap::Parameters& p, double v) {
         p.initial_angular_velocity = {v, 0.0, 0.0};
       },
       {ap::kMaxBodyRate, -ap::kMaxBodyRate},
       {up(ap::kMaxBodyRate)}},
  };
  for (const Range& r : ranges) expectRange(r);
}

// rate_delay: at most the configured max_dt (not the largest max_dt).
TEST(Boundaries, RateDelayUpToTheConfiguredMaxDt) {
  expectRange({"rate_delay",
               [](ap::Parameters& p, double v) { p.rate_delay = v; },
               {0.0, 0.5},
               {-std::numeric_limits<double>::denorm_min(), up(0.5), 1.0},
               [] {
                 ap::Parameters p;
                 p.max_dt = 0.5;
                 return p;
               }});
  // The engine refuses the same range.
  Recorder sink;
  ap::EngineConfig c = engine_fixtures::kinematicConfig();
  c.kinematic.time_policy.max_dt = 0.5;
  c.rate_delay = 0.5;
  EXPECT_NO_THROW(ap::AttitudeEngine(c, sink));
  c.rate_delay = up(0.5);
  EXPECT_THROW(ap::AttitudeEngine(c, sink), std::invalid_argument);
}

// The dynamic model's rules across two parameters: publish_rate at least 1/max_dt, and
// max_dt / max_step at most kMaxGridStepsPerCall.
TEST(Boundaries, DynamicPublishRateAndGridStepsPerCall) {
  // 1/2 = 0.5 exactly: a tick every max_dt is still integrated.
  expectRange({"publish_rate",
               [](ap::Parameters& p, double v) { p.publish_rate = v; },
               {2.0, ap::kMaxPublishRate},
               {down(2.0)},
               [] { return dynamicBase(0.5); }});
  // 60 s / 6e-4 s = 1e5 grid steps per call, the bound; a step a part in 1e9 shorter exceeds it.
  expectRange({"max_step",
               [](ap::Parameters& p, double v) { p.max_step = v; },
               {6e-4, ap::kMaxMaxDt},
               {6e-4 * (1.0 - 1e-9)},
               [] { return dynamicBase(60.0); }});
  // max_dt = 1 s at the smallest max_step: 1e5 steps.
  expectRange({"max_step",
               [](ap::Parameters& p, double v) { p.max_step = v; },
               {ap::kMinMaxStep},
               {down(ap::kMinMaxStep)},
               [] { return dynamicBase(1.0); }});
}

TEST(Boundaries, InertiaMomentsWithinTheDoor) {
  auto sphere = [](double moment) { return std::vector<double>{moment, moment, moment}; };
  for (double inside : {ap::kMinInertia, ap::kMaxInertia}) {
    ap::Parameters p = dynamicBase(1.0);
    p.inertia = sphere(inside);
    EXPECT_NO_THROW(ap::validateParameters(p)) << inside;
    EXPECT_NO_THROW(ap::RigidBody::fromPrincipalMoments(Eigen::Vector3d::Constant(inside)));
  }
  for (double outside : {down(ap::kMinInertia), up(ap::kMaxInertia)}) {
    SCOPED_TRACE(outside);
    ap::Parameters p = dynamicBase(1.0);
    p.inertia = sphere(outside);
    expectRefused(p, "inertia");
    EXPECT_THROW(ap::RigidBody::fromPrincipalMoments(Eigen::Vector3d::Constant(outside)),
                 std::invalid_argument);
  }
}

TEST(Boundaries, StepBudgetCoversTheFinestGridAcrossMaxDt) {
  // §7.6, limits.h: a propagator call may spend step_budget units (one per fixed step); the
  // budget must cover max_dt / max_step + kBudgetHeadroomSteps, and the default 2^17 covers the
  // finest grid the validator accepts, kMaxGridStepsPerCall steps.
  EXPECT_EQ(ap::kDefaultStepBudget, std::uint64_t{1} << 17);
  EXPECT_GE(static_cast<double>(ap::kDefaultStepBudget),
            ap::kMaxGridStepsPerCall + ap::kBudgetHeadroomSteps);
  ap::DynamicConfig d;
  d.integrator = ap::Integrator::Rk4;
  d.max_step = ap::kMinMaxStep;
  d.time_policy.max_dt = ap::kMinMaxStep * ap::kMaxGridStepsPerCall;  // 1 s
  d.initial.w_B = Eigen::Vector3d(0.0, 0.0, 0.5);
  ap::DynamicPropagator p(d);
  EXPECT_EQ(p.advanceTo(0.0), ap::StampOutcome::Anchored);
  EXPECT_EQ(p.advanceTo(d.time_policy.max_dt), ap::StampOutcome::Advanced);
  // A torque-free sphere turns at its constant rate: 0.5 rad about z in 1 s.
  EXPECT_NEAR(p.state().q_WB.angularDistance(aboutAxis(Eigen::Vector3d::UnitZ(), 0.5)), 0.0, 1e-9);
  // Exactly representable: 1 s / 0.0625 s = 16 steps, + 8 = 24 units needed.
  d.max_step = 0.0625;
  d.step_budget = 24;
  EXPECT_NO_THROW(ap::DynamicPropagator{d});
  d.step_budget = 23;
  EXPECT_THROW(ap::DynamicPropagator{d}, std::invalid_argument);
}

// ---- Door bounds of the propagators and the engine (§7.2) ------------------------------------

TEST(Boundaries, RateSampleAtMostTheLargestBodyRate) {
  for (bool inside : {true, false}) {
    Recorder sink;
    ap::AttitudeEngine engine(engine_fixtures::kinematicConfig(), sink);
    const double w = inside ? ap::kMaxBodyRate : up(ap::kMaxBodyRate);
    engine.submit(rateAt(at(1.0), Eigen::Vector3d(0.0, w, 0.0)));
    EXPECT_EQ(engine.counters().accepted, inside ? 1u : 0u) << w;
    EXPECT_EQ(engine.counters().rejected_out_of_range, inside ? 0u : 1u) << w;
    EXPECT_EQ(sink.states.size(), inside ? 1u : 0u);

    ap::KinematicPropagator k{ap::KinematicConfig{}};
    EXPECT_EQ(k.addSample(1.0, Eigen::Vector3d(w, 0.0, 0.0)),
              inside ? ap::StampOutcome::Anchored : ap::StampOutcome::RejectedOutOfRange);
  }
}

TEST(Boundaries, SetAndInitialRateAtMostTheLargestBodyRate) {
  for (bool inside : {true, false}) {
    const Eigen::Vector3d w(0.0, 0.0, inside ? ap::kMaxBodyRate : up(ap::kMaxBodyRate));
    Recorder sink;
    ap::AttitudeEngine engine(engine_fixtures::kinematicConfig(), sink);
    EXPECT_EQ(engine.setState(at(1.0), Eigen::Quaterniond::Identity(), w).empty(), inside);

    ap::DynamicConfig d;
    d.initial.w_B = w;
    if (inside) {
      EXPECT_NO_THROW(ap::DynamicPropagator{d});
    } else {
      EXPECT_THROW(ap::DynamicPropagator{d}, std::invalid_argument);
    }
  }
}

TEST(Boundaries, GyroBiasAtMostTheLargestBodyRate) {
  for (bool inside : {true, false}) {
    const Eigen::Vector3d b(inside ? ap::kMaxBodyRate : up(ap::kMaxBodyRate), 0.0, 0.0);
    Recorder sink;
    ap::AttitudeEngine engine(engine_fixtures::kinematicConfig(), sink);
    EXPECT_EQ(engine.submitBias(at(1.0), b), inside);
    EXPECT_EQ(engine.counters().rejected_bias, inside ? 0u : 1u);

    ap::EngineConfig c = engine_fixtures::kinematicConfig();
    c.gyro_bias_B = b;
    if (inside) {
      EXPECT_NO_THROW(ap::AttitudeEngine(c, sink));
    } else {
      EXPECT_THROW(ap::AttitudeEngine(c, sink), std::invalid_argument);
    }
  }
}

TEST(Boundaries, TorqueAtMostKMaxTorque) {
  // kMaxTorque = I_max w_max / kMinMaxStep (limits.h).
  EXPECT_EQ(ap::kMaxTorque, ap::kMaxInertia * ap::kMaxStateRate / ap::kMinMaxStep);
  for (bool inside : {true, false}) {
    Recorder sink;
    ap::AttitudeEngine engine(engine_fixtures::torqueConfig(), sink);
    engine.clockTick(at(1.0));  // anchors; a torque stamped there is applied at once
    const double tau = inside ? ap::kMaxTorque : up(ap::kMaxTorque);
    engine.submit(engine_fixtures::torque(at(1.0), Eigen::Vector3d(0.0, 0.0, tau)));
    EXPECT_EQ(engine.counters().rejected_out_of_range, inside ? 0u : 1u) << tau;
  }
}

TEST(Boundaries, EngineFixAndFutureSettingsOnBothSides) {
  Recorder sink;
  auto with = [](const std::function<void(ap::EngineConfig&)>& set) {
    ap::EngineConfig c = engine_fixtures::kinematicConfig();
    set(c);
    return c;
  };
  auto accepted = [&sink](const ap::EngineConfig& c) {
    try {
      ap::AttitudeEngine engine(c, sink);
      return true;
    } catch (const std::invalid_argument&) {
      return false;
    }
  };
  EXPECT_TRUE(accepted(with([](auto& c) { c.fixes.history = ap::kMaxFixHistory; })));
  EXPECT_FALSE(accepted(with([](auto& c) { c.fixes.history = up(ap::kMaxFixHistory); })));
  EXPECT_FALSE(accepted(with([](auto& c) { c.fixes.history = 0.0; })));
  EXPECT_TRUE(accepted(with([](auto& c) { c.fixes.stddev = M_PI; })));
  EXPECT_FALSE(accepted(with([](auto& c) { c.fixes.stddev = up(M_PI); })));
  EXPECT_FALSE(accepted(with([](auto& c) { c.fixes.gate = 0.0; })));
  EXPECT_FALSE(accepted(with([](auto& c) { c.max_future = 0.0; })));
  EXPECT_TRUE(accepted(with([](auto& c) { c.max_future = 1e-9; })));
  EXPECT_TRUE(accepted(with([](auto& c) { c.fixes.gyro_bias_stddev = ap::kMaxGyroBiasStddev; })));
  EXPECT_FALSE(
      accepted(with([](auto& c) { c.fixes.gyro_bias_stddev = up(ap::kMaxGyroBiasStddev); })));
  EXPECT_TRUE(accepted(with([](auto& c) { c.max_future = ap::kMaxFuture; })));
  EXPECT_FALSE(accepted(with([](auto& c) { c.max_future = up(ap::kMaxFuture); })));
}

// ---- Covariances (§7.3) -----------------------------------------------------------------------

TEST(Boundaries, RateCovarianceRulesOnBothSides) {
  using Check = ap::RateCovarianceCheck;
  const Eigen::Matrix3d I = Eigen::Matrix3d::Identity();
  EXPECT_EQ(ap::checkRateCovariance(Eigen::Matrix3d::Zero()), Check::Ok);  // "not given"
  // Variances in [0, kMaxRateVariance].
  EXPECT_EQ(ap::checkRateCovariance(ap::kMaxRateVariance * I), Check::Ok);
  EXPECT_EQ(ap::checkRateCovariance(up(ap::kMaxRateVariance) * I), Check::VarianceTooLarge);
  Eigen::Matrix3d R = I;
  R(1, 1) = 0.0;
  EXPECT_EQ(ap::checkRateCovariance(R), Check::Ok);
  R(1, 1) = -std::numeric_limits<double>::denorm_min();
  EXPECT_EQ(ap::checkRateCovariance(R), Check::NegativeVariance);
  // Symmetric to 1e-6 of the largest entry (here 1).
  R = I;
  R(0, 1) = 0.5;
  R(1, 0) = 0.5 + 0.9e-6;
  EXPECT_EQ(ap::checkRateCovariance(R), Check::Ok);
  R(1, 0) = 0.5 + 1.1e-6;
  EXPECT_EQ(ap::checkRateCovariance(R), Check::NotSymmetric);
  // Correlations of magnitude at most one: exactly one is a (singular) covariance.
  R = I;
  R(0, 2) = R(2, 0) = -1.0;
  EXPECT_EQ(ap::checkRateCovariance(R), Check::Ok);
  R(0, 2) = R(2, 0) = -(1.0 + 2e-6);
  EXPECT_EQ(ap::checkRateCovariance(R), Check::NotACovariance);
  R = I;
  R(2, 2) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(ap::checkRateCovariance(R), Check::NonFinite);
}

TEST(Boundaries, NonFiniteRateOrCovarianceIsRejectedNonFinite) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (int which = 0; which < 2; ++which) {
    Recorder sink;
    ap::AttitudeEngine engine(engine_fixtures::kinematicConfig(), sink);
    ap::Input in = rateAt(at(1.0), Eigen::Vector3d(0.1, 0.0, 0.0));
    if (which == 0) in.value.y() = nan;
    if (which == 1) in.rate_covariance_B(2, 2) = std::numeric_limits<double>::infinity();
    engine.submit(in);
    EXPECT_EQ(engine.counters().rejected_non_finite, 1u) << which;
    EXPECT_EQ(engine.counters().accepted, 0u) << which;
    EXPECT_TRUE(sink.states.empty()) << which;
  }
}

// ---- Late fixes: the quaternion and covariance doors (§6.9) ----------------------------------

/// A kinematic engine at rest at 1 s (zero rates from 0 to 1 s at 100 Hz), P_B = 0.
struct RestingEngine {
  Recorder sink;
  ap::AttitudeEngine engine;
  explicit RestingEngine(const ap::EngineConfig& c = engine_fixtures::kinematicConfig())
      : engine(c, sink) {
    for (int k = 0; k <= 100; ++k) engine.submit(rateAt(at(0.01 * k)));
  }
};

TEST(Boundaries, FixQuaternionUnitWithinTolerance) {
  // |q| within kFixUnitTolerance = 1e-5 of 1: a scale 0.9e-5 off is accepted, 1.1e-5 off not.
  for (double off : {0.9e-5, -0.9e-5, 1.1e-5, -1.1e-5}) {
    RestingEngine e;
    const Eigen::Quaterniond q(Eigen::Quaterniond::Identity().coeffs() * (1.0 + off));
    const bool inside = std::abs(off) < ap::kFixUnitTolerance;
    EXPECT_EQ(e.engine.submitFix(at(1.0), q, Eigen::Matrix3d::Zero()),
              inside ? ap::FixOutcome::Accepted : ap::FixOutcome::BadQuaternion)
        << off;
    EXPECT_EQ(e.engine.counters().fixes_bad_quaternion, inside ? 0u : 1u) << off;
  }
}

TEST(Boundaries, FixVarianceAtMostPiSquared) {
  for (bool inside : {true, false}) {
    RestingEngine e;
    const double v = inside ? ap::kMaxOrientationVariance : up(ap::kMaxOrientationVariance);
    const ap::FixOutcome outcome = e.engine.submitFix(at(1.0), Eigen::Quaterniond::Identity(),
                                                      v * Eigen::Matrix3d::Identity());
    EXPECT_EQ(outcome, inside ? ap::FixOutcome::Accepted : ap::FixOutcome::BadCovariance);
    EXPECT_EQ(e.engine.counters().fixes_bad_covariance, inside ? 0u : 1u);
  }
}

// ---- Time policy (§6) -------------------------------------------------------------------------

TEST(Boundaries, FutureStampAtMostMaxFutureAhead) {
  for (bool inside : {true, false}) {
    Recorder sink;
    ap::AttitudeEngine engine(engine_fixtures::kinematicConfig(), sink);  // max_future 1 s
    engine.clockTick(at(10.0));
    engine.submit(rateAt(at(11.0) + (inside ? 0 : 1)));
    EXPECT_EQ(engine.counters().accepted, inside ? 1u : 0u);
    EXPECT_EQ(engine.counters().rejected_future, inside ? 0u : 1u);
    EXPECT_EQ(engine.counters().dropped_stale, 0u);
  }
}

TEST(Boundaries, GapOfExactlyMaxDtIsIntegrated) {
  // §6.2: t_last < t <= t_last + max_dt advances; beyond, the state is held (a gap).
  for (bool inside : {true, false}) {
    Recorder sink;
    ap::AttitudeEngine engine(engine_fixtures::kinematicConfig(), sink);  // max_dt 1 s
    const Eigen::Vector3d w(0.0, 0.0, 0.3);
    engine.submit(rateAt(at(1.0), w));
    engine.submit(rateAt(at(2.0) + (inside ? 0 : 1), w));
    EXPECT_EQ(engine.counters().gaps, inside ? 0u : 1u);
    EXPECT_EQ(engine.counters().accepted, 2u);
    // Integrated: a turn of 0.3 rad about z (constant rate); held: none.
    const double angle = 2.0 * std::acos(std::min(1.0, std::abs(engine.state().q_WB.w())));
    EXPECT_NEAR(angle, inside ? 0.3 : 0.0, 1e-6);
  }
}

TEST(Boundaries, StampEqualToTheLastIsStale) {
  for (bool sensor_clock : {false, true}) {
    Recorder sink;
    ap::EngineConfig c = engine_fixtures::kinematicConfig();
    if (sensor_clock) c.kinematic.stamp_filter = ap::StampFilter::SensorClock;
    ap::AttitudeEngine engine(c, sink);
    engine.submit(rateAt(at(1.25)));
    engine.submit(rateAt(at(1.25)));
    // Without the filter a repeated stamp is a straggler; with it, a FIFO read (numerics.md §3).
    EXPECT_EQ(engine.counters().dropped_stale, sensor_clock ? 0u : 1u);
    EXPECT_EQ(engine.counters().accepted, sensor_clock ? 2u : 1u);
    engine.submit(rateAt(at(1.25) - 1));
    EXPECT_EQ(engine.counters().dropped_stale, sensor_clock ? 1u : 2u);
  }
}

// A FIFO read whose repeated stamp is the very first stamp on a whole second (core time 0: the
// origin is the whole second at or before the first stamp, §6.1). The sensor-clock filter keeps
// its stamps strictly increasing; next to 0 the next double is a denormal, a step cf4 (the
// default `auto`) cannot take (its result is not finite), so the filter steps by at least a
// picosecond (§6.8). Every sample of the read is a good, finite sample: accepted (§7.1).
TEST(Boundaries, FifoReadStampedOnAWholeSecondIsIntegrated) {
  Recorder sink;
  ap::EngineConfig c = engine_fixtures::kinematicConfig();
  c.kinematic.stamp_filter = ap::StampFilter::SensorClock;
  ap::AttitudeEngine engine(c, sink);
  for (int i = 0; i < 3; ++i) engine.submit(rateAt(at(1.0), Eigen::Vector3d(0.1, 0.2, 0.3)));
  EXPECT_EQ(engine.counters().rejected_non_finite, 0u);
  EXPECT_EQ(engine.counters().accepted, 3u);
}

TEST(Boundaries, AMeanStampedAtItsStartOrMidpointRepeatedIsStale) {
  // §6.2 for means stamped at their start or midpoint (numerics.md §3): a mean waits for the
  // next stamp, which ends its interval; a sample repeating the waiting stamp (t <= the last
  // stamp given) is stale and changes nothing.
  for (ap::AverageStamp position : {ap::AverageStamp::Mid, ap::AverageStamp::Start}) {
    ap::KinematicConfig config;
    config.rate_samples = ap::RateSamples::IntervalAverage;
    config.average_stamp = position;
    ap::KinematicPropagator k(config);
    const Eigen::Vector3d w(0.0, 0.0, 1.0);
    const double end = position == ap::AverageStamp::Mid ? 0.5 : 1.0;  // of the interval
    EXPECT_EQ(k.addSample(0.0, w), ap::StampOutcome::Waiting);
    EXPECT_EQ(k.addSample(0.01, w), ap::StampOutcome::Anchored);
    EXPECT_DOUBLE_EQ(k.time(), 0.01 * end);
    EXPECT_EQ(k.addSample(0.01, w), ap::StampOutcome::DroppedStale);
    EXPECT_EQ(k.addSample(0.01 - 1e-9, w), ap::StampOutcome::DroppedStale);
    EXPECT_DOUBLE_EQ(k.time(), 0.01 * end);
    EXPECT_EQ(k.addSample(0.02, w), ap::StampOutcome::Advanced);
    EXPECT_DOUBLE_EQ(k.time(), 0.01 + 0.01 * end);
    // One interval of 0.01 s at 1 rad/s about z.
    EXPECT_NEAR(k.orientation().angularDistance(aboutAxis(Eigen::Vector3d::UnitZ(), 0.01)), 0.0,
                1e-12);
  }
}

TEST(Boundaries, StragglerThresholdIsOneSecondInclusive) {
  // §6.5: a run from an earlier time counts only stamps more than 1 s before the newest.
  for (bool inside : {true, false}) {
    Recorder sink;
    ap::AttitudeEngine engine(engine_fixtures::kinematicConfig(), sink);
    engine.submit(rateAt(at(10.0)));
    const ap::Stamp offset = inside ? 0 : 1;  // 1 s exactly before the newest: a straggler
    for (double back : {1.02, 1.01, 1.0}) engine.submit(rateAt(at(10.0 - back) - offset));
    EXPECT_EQ(engine.counters().jumps_back, inside ? 0u : 1u);
    EXPECT_EQ(engine.counters().dropped_stale, inside ? 3u : 0u);  // a jump keeps its run
  }
}

TEST(Boundaries, JumpRunStampsAtMostMaxDtApart) {
  // §6.5: each stamp of the run later than the one before by at most max_dt (1 s).
  for (bool inside : {true, false}) {
    Recorder sink;
    ap::AttitudeEngine engine(engine_fixtures::kinematicConfig(), sink);
    engine.submit(rateAt(at(100.0)));
    const ap::Stamp extra = inside ? 0 : 1;
    for (int k = 0; k < 3; ++k) engine.submit(rateAt(at(10.0 + k) + k * extra));
    EXPECT_EQ(engine.counters().jumps_back, inside ? 1u : 0u);
  }
}

TEST(Boundaries, ClockStepBackOfOneSecondIsJitter) {
  // §6.5: ROS time going back by more than 1 s resets; 1 s or less is jitter.
  for (bool inside : {true, false}) {
    Recorder sink;
    ap::AttitudeEngine engine(engine_fixtures::kinematicConfig(), sink);
    engine.clockTick(at(10.0));
    engine.clockTick(at(9.0) - (inside ? 0 : 1));
    EXPECT_EQ(engine.counters().resets, inside ? 0u : 1u);
  }
}

TEST(Boundaries, ClockJitterLeavesTheClockWhereItWas) {
  // The clock stays at 10 s after a step back to 9.5 s: an input stamped max_future after 10 s
  // is not too far ahead.
  Recorder sink;
  ap::AttitudeEngine engine(engine_fixtures::kinematicConfig(), sink);
  engine.clockTick(at(10.0));
  engine.clockTick(at(9.5));
  engine.submit(rateAt(at(11.0)));
  EXPECT_EQ(engine.counters().rejected_future, 0u);
  EXPECT_EQ(engine.counters().accepted, 1u);
  engine.poll(at(9.4));
  engine.submit(rateAt(at(11.0) + 1));
  EXPECT_EQ(engine.counters().rejected_future, 1u);
}

TEST(Boundaries, ClockJumpOfExactlyMaxDtPublishesEveryGridStamp) {
  // §5.3: under sim time a jump ahead by more than max_dt (1 s) is a gap, only the newest grid
  // stamp published; a step of exactly max_dt publishes every grid stamp (50 Hz: 50).
  for (bool inside : {true, false}) {
    Recorder sink;
    ap::AttitudeEngine engine(engine_fixtures::torqueConfig(), sink);
    engine.clockTick(at(1.0));
    const std::size_t before = sink.states.size();
    engine.clockTick(at(2.0) + (inside ? 0 : 1));
    EXPECT_EQ(sink.states.size() - before, inside ? 50u : 1u);
    EXPECT_EQ(sink.states.back().stamp, at(2.0));
  }
}

TEST(Boundaries, PollAfterAStallPublishesEveryGridStamp) {
  // §5.3: under wall time lateness is never a gap: every missed grid stamp is published.
  Recorder sink;
  ap::AttitudeEngine engine(engine_fixtures::torqueConfig(), sink);
  engine.poll(at(1.0));
  const std::size_t before = sink.states.size();
  engine.poll(at(6.0));
  EXPECT_EQ(sink.states.size() - before, 250u);
  EXPECT_EQ(engine.counters().gaps, 0u);
  EXPECT_TRUE(sink.stampsIncrease());
}

TEST(Boundaries, LateMeansStampedBeforeThePropagatorsTime) {
  // §6.7: an input stamped before the propagator's time is late; one stamped at it is not.
  for (bool at_time : {true, false}) {
    Recorder sink;
    ap::AttitudeEngine engine(engine_fixtures::torqueConfig(), sink);
    engine.clockTick(at(1.0));
    engine.submit(engine_fixtures::torque(at(1.0) - (at_time ? 0 : 1), Eigen::Vector3d::UnitZ()));
    EXPECT_EQ(engine.counters().accepted, 1u);
    EXPECT_EQ(engine.counters().late, at_time ? 0u : 1u);
  }
}

TEST(Boundaries, FixExactlyFixHistoryOldIsApplied) {
  // §6.9: the newest entry at or before newest - fix_history is kept, so a fix exactly that old
  // is applied; one a nanosecond older is too old.
  for (bool inside : {true, false}) {
    ap::EngineConfig c = engine_fixtures::kinematicConfig();
    c.fixes.history = 0.1;
    RestingEngine e(c);
    const Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
    EXPECT_EQ(e.engine.submitFix(at(1.0), q, Eigen::Matrix3d::Zero()), ap::FixOutcome::Accepted);
    for (int k = 101; k <= 150; ++k) e.engine.submit(rateAt(at(0.01 * k)));
    const ap::Stamp stamp = at(1.5) - 100000000 - (inside ? 0 : 1);
    EXPECT_EQ(e.engine.submitFix(stamp, q, Eigen::Matrix3d::Zero()),
              inside ? ap::FixOutcome::Accepted : ap::FixOutcome::TooOld);
    EXPECT_EQ(e.engine.counters().fixes_too_old, inside ? 0u : 1u);
  }
}

TEST(Boundaries, FixAtTheNewestStateAppliesAtOnceAndBeforeTheHistoryIsTooOld) {
  // §6.9: the first fix starts the history at the newest state. A fix stamped exactly there is
  // applied at once; after it, it waits; before it (the history's start), it is too old.
  RestingEngine e;
  const Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
  EXPECT_EQ(e.engine.submitFix(at(0.5), q, Eigen::Matrix3d::Zero()), ap::FixOutcome::TooOld);
  EXPECT_EQ(e.engine.counters().fixes_too_old, 1u);
  EXPECT_EQ(e.engine.submitFix(at(1.0), q, Eigen::Matrix3d::Zero()), ap::FixOutcome::Accepted);
  EXPECT_EQ(e.engine.submitFix(at(1.0) + 1, q, Eigen::Matrix3d::Zero()), ap::FixOutcome::Waiting);
  EXPECT_EQ(e.engine.counters().fixes_accepted, 1u);
  // A waiting fix is applied when a rate reaches its stamp exactly.
  e.engine.submit(rateAt(at(1.0) + 1));
  EXPECT_EQ(e.engine.pendingFixes(), 0u);
  EXPECT_EQ(e.engine.counters().fixes_accepted, 2u);
}

TEST(Boundaries, FixGateComparesTheSquaredMahalanobisDistance) {
  // P_B = 0, R = sigma^2 I: an innovation of theta about one axis has r^T S^-1 r = (theta /
  // sigma)^2, accepted up to fix_gate. Gate 16: 3.9 sigma accepted, 4.1 sigma rejected.
  for (double sigmas : {3.9, 4.1}) {
    ap::EngineConfig c = engine_fixtures::kinematicConfig();
    c.fixes.gate = 16.0;
    c.fixes.stddev = 0.01;
    RestingEngine e(c);
    const Eigen::Quaterniond q = aboutAxis(Eigen::Vector3d(1.0, -2.0, 0.5), sigmas * 0.01);
    const bool inside = sigmas * sigmas <= 16.0;
    EXPECT_EQ(e.engine.submitFix(at(1.0), q, Eigen::Matrix3d::Zero()),
              inside ? ap::FixOutcome::Accepted : ap::FixOutcome::RejectedGate)
        << sigmas;
    EXPECT_EQ(e.engine.counters().fixes_rejected_gate, inside ? 0u : 1u);
  }
}

TEST(Boundaries, FixWithoutCovarianceUsesFixStddevSquared) {
  // §6.9: all zeros means fix_stddev^2 I; in reset mode P_B becomes the fix's covariance, the
  // prior (here initial_orientation_stddev = 0.3 rad) forgotten.
  ap::EngineConfig c = engine_fixtures::kinematicConfig();
  c.fixes.mode = ap::FixMode::Reset;
  c.fixes.stddev = 0.02;
  c.initial_orientation_stddev = 0.3;
  RestingEngine e(c);
  EXPECT_TRUE(e.engine.state().P_B.isApprox(0.09 * Eigen::Matrix3d::Identity(), 1e-12));
  const Eigen::Quaterniond q = aboutAxis(Eigen::Vector3d(0.0, 1.0, 1.0), 0.7);
  EXPECT_EQ(e.engine.submitFix(at(1.0), q, Eigen::Matrix3d::Zero()), ap::FixOutcome::Reset);
  EXPECT_TRUE(e.engine.state().P_B.isApprox(4e-4 * Eigen::Matrix3d::Identity(), 1e-12))
      << e.engine.state().P_B;
  EXPECT_LT(e.engine.state().q_WB.angularDistance(q), 1e-12);
  // A fix with its own covariance: P_B is that covariance.
  const Eigen::Matrix3d R = Eigen::Vector3d(1e-4, 4e-4, 9e-4).asDiagonal();
  EXPECT_EQ(e.engine.submitFix(at(1.0), q, R), ap::FixOutcome::Reset);
  EXPECT_TRUE(e.engine.state().P_B.isApprox(R, 1e-12)) << e.engine.state().P_B;
  EXPECT_EQ(e.engine.counters().fixes_accepted, 2u);
  EXPECT_EQ(e.engine.counters().fixes_reset, 2u);
}

// ---- The publish grid (§5.3) -----------------------------------------------------------------

TEST(Boundaries, GridStampsAreRoundedNanosecondsAndTheirOwnIndex) {
  // g_k = round(k 1e9 / rate) ns, computed here in integers: (2 k 1e9 + rate) / (2 rate) for
  // whole rates. The index at or before g_k is k; a nanosecond before it, k - 1.
  for (std::int64_t rate : {3, 7, 30, 50, 100, 333, 1000}) {
    for (std::int64_t k = 0; k <= 2000; ++k) {
      const ap::Stamp expected = (2 * k * kSecond + rate) / (2 * rate);
      const ap::Stamp g = ap::gridStamp(k, static_cast<double>(rate));
      ASSERT_EQ(g, expected) << rate << " Hz, k = " << k;
      ASSERT_EQ(ap::gridIndexAtOrBefore(g, static_cast<double>(rate)), k) << rate << " " << k;
      ASSERT_EQ(ap::gridIndexAtOrBefore(g - 1, static_cast<double>(rate)), k - 1)
          << rate << " " << k;
    }
  }
  // At an epoch stamp too (k near 1.78e9 * rate).
  const std::int64_t k0 = 1780000000LL * 30;
  for (std::int64_t k = k0; k < k0 + 100; ++k) {
    const ap::Stamp g = ap::gridStamp(k, 30.0);
    // 2 k 1e9 exceeds 64 bits here.
    const auto expected =
        static_cast<ap::Stamp>((static_cast<__int128>(2 * k) * kSecond + 30) / 60);
    ASSERT_EQ(g, expected);
    ASSERT_EQ(ap::gridIndexAtOrBefore(g, 30.0), k);
  }
}

}  // namespace
