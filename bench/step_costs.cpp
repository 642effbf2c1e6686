// bench_step_costs: the cost of one step of every integrator with Google Benchmark.
//
// Each benchmark is one dependent chain (the next step starts from the last result), as in a
// propagator, so the figure is latency, not throughput of independent steps. Pitfalls kept out
// (docs/numerics.md §9): the state changes every iteration so nothing is constant-folded, results
// go through benchmark::DoNotOptimize, and every step is renormalised as the propagators do.
//
//   kinematicStep/<method>   one kinematicStep on a four-sample window, then normalise
//   addSample/<method>       KinematicPropagator::addSample, the node's path per message
//   addSample/cf4_interval_average[_sensor_clock]   the same on averaged samples (and with the
//                            stamp filter)
//   dynamicStep/<method>     DynamicStepper::stepPrincipal on the free body (dopri5: one
//                            output step of 0.01 s at tolerance 1e-9; exact: its cached
//                            closed form, evaluated at the next time)
//   exact/<form>             one TorqueFreeMotion::evaluate at a new time
//   engineSample/<model>[_fix_history]   one rate input (kinematic: cf4, the bias estimated) or
//                            one clock tick publishing a grid stamp (dynamic: rk4, a torque
//                            held) through AttitudeEngine, without fixes and with the fix
//                            history kept (one fix at the start): the per-sample cost of the
//                            history, as a ratio of the two in the same run. The kinematic
//                            one with a tactical gyro's bias prior (2.4e-5 rad/s, no random
//                            walk), so that the attitude covariance stays below its cap over
//                            the whole run (kinematicFixConfig)
//   engineSample/kinematic_cf4_at_cap   the same with the default (MEMS) prior and random walk:
//                            over the run's thousands of seconds without a fix the attitude
//                            variance reaches its cap pi^2, and every step then clamps it (an
//                            eigendecomposition, orientation_covariance.h)
//   fixReplay/<model>        one late fix 1 s behind the newest state: kinematic, 200 Hz rates
//                            (200 inputs replayed); dynamic, a 100 Hz grid with torques and
//                            rates (the steps of 1 s replayed). Between two, outside the timing,
//                            the rates move on by a second, so that each replay falls in a
//                            second of stamp time of its own and the replay budget
//                            (replay_budget.h) never refuses one: the replay is measured
#include <benchmark/benchmark.h>

#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "attitude_propagator/engine.h"
#include "attitude_propagator/models/kinematic_propagator.h"
#include "attitude_propagator/numerics/dynamic_step.h"
#include "attitude_propagator/numerics/kinematic_step.h"
#include "attitude_propagator/numerics/torque_free_motion.h"
#include "dynamic_scenes.h"
#include "methods.h"

namespace {

namespace ap = attitude_propagator;
using ap::Integrator;

constexpr double kDt = 1.0 / 200.0;  // s, a 200 Hz gyro

// A coning-like body rate (docs/numerics.md §8), rad/s.
Eigen::Vector3d rateAt(double t) {
  return Eigen::Vector3d(-0.0347, -0.69 * std::sin(6.9 * t), 0.69 * std::cos(6.9 * t));
}

ap::RateWindow fullWindow() {
  ap::RateWindow window;
  for (int k = 0; k < 4; ++k) window.push({k * kDt, rateAt(k * kDt)});
  return window;
}

void kinematicStepCost(benchmark::State& state, Integrator method) {
  const ap::RateWindow window = fullWindow();
  Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
  for (auto _ : state) {
    q = ap::kinematicStep(method, q, window).normalized();
    benchmark::DoNotOptimize(q.coeffs().data());
  }
  benchmark::ClobberMemory();
}

/// `lost_every`: every so many samples one is not delivered (0: none), so that interval means
/// are filled in and auto's prediction for lost means runs (auto_integrator.h).
void addSampleCost(benchmark::State& state, Integrator method,
                   ap::RateSamples kind = ap::RateSamples::Instantaneous,
                   ap::StampFilter filter = ap::StampFilter::None, std::size_t lost_every = 0) {
  // Rates cycle through a table (cheap to read, not constant); time keeps increasing.
  std::vector<Eigen::Vector3d> rates(1024);
  for (std::size_t i = 0; i < rates.size(); ++i) rates[i] = rateAt(i * kDt);
  ap::KinematicConfig config;
  config.integrator = method;
  config.rate_samples = kind;
  config.stamp_filter = filter;
  ap::KinematicPropagator propagator(config);
  double t = 0.0;
  std::size_t i = 0;
  std::size_t n = 0;
  for (auto _ : state) {
    if (lost_every > 0 && ++n % lost_every == 0) t += kDt;  // the one before was lost
    propagator.addSample(t, rates[i]);
    t += kDt;
    i = (i + 1) & 1023;
    benchmark::DoNotOptimize(propagator.orientation().coeffs().data());
  }
}

void registerKinematic() {
  for (Integrator m : bench::methodsFor(ap::Model::Kinematic)) {
    const std::string name = ap::integratorName(m);
    benchmark::RegisterBenchmark(("kinematicStep/" + name).c_str(), kinematicStepCost, m);
    benchmark::RegisterBenchmark(("addSample/" + name).c_str(), addSampleCost, m,
                                 ap::RateSamples::Instantaneous, ap::StampFilter::None,
                                 std::size_t{0});
  }
  // The real-stream paths, next to addSample/cf4 in the same run: averaged samples (delta-angle
  // cubic, gap check), and the same with the sensor-clock stamp filter.
  benchmark::RegisterBenchmark("addSample/cf4_interval_average", addSampleCost, Integrator::Cf4,
                               ap::RateSamples::IntervalAverage, ap::StampFilter::None,
                               std::size_t{0});
  benchmark::RegisterBenchmark("addSample/cf4_interval_average_sensor_clock", addSampleCost,
                               Integrator::Cf4, ap::RateSamples::IntervalAverage,
                               ap::StampFilter::SensorClock, std::size_t{0});
  // auto on means with one lost in 37: fills, and from the first on the prediction that picks
  // cf4 or exp2 for lost means, beside auto on the same means with none lost.
  benchmark::RegisterBenchmark("addSample/auto_interval_average", addSampleCost, Integrator::Auto,
                               ap::RateSamples::IntervalAverage, ap::StampFilter::None,
                               std::size_t{0});
  benchmark::RegisterBenchmark("addSample/auto_interval_average_lossy", addSampleCost,
                               Integrator::Auto, ap::RateSamples::IntervalAverage,
                               ap::StampFilter::None, 37);
}

ap::RigidBody bodyOf(const bench::DynamicScene& scene) {
  return ap::RigidBody::fromPrincipalMoments(scene.moments,
                                             ap::RigidBody::TriangleInequality::Ignore);
}

void dynamicStepCost(benchmark::State& state, Integrator method) {
  const bench::DynamicScene scene = bench::freeBodyScene();
  const ap::DynamicStepper stepper(method, bodyOf(scene), 1e-9);
  ap::PrincipalState x = stepper.toPrincipal(scene.initial);
  const ap::PrincipalTorque torque;
  for (auto _ : state) {
    stepper.stepPrincipal(x, torque, 0.01);
    benchmark::DoNotOptimize(x.q_WP.coeffs().data());
  }
}

// The time advances every call (the argument reduction and the elliptic functions see new
// values), as in a propagator that evaluates at each stamp.
void exactCost(benchmark::State& state, const bench::DynamicScene& scene) {
  const ap::TorqueFreeMotion motion(bodyOf(scene), scene.initial);
  double t = 0.0;
  for (auto _ : state) {
    t += 0.01;
    ap::DynamicState x = motion.evaluate(t);
    benchmark::DoNotOptimize(x.q_WB.coeffs().data());
  }
}

void registerDynamic() {
  for (Integrator m : bench::methodsFor(ap::Model::Dynamic)) {
    const std::string name = ap::integratorName(m);
    benchmark::RegisterBenchmark(("dynamicStep/" + name).c_str(), dynamicStepCost, m);
  }
  for (const bench::DynamicScene& scene :
       {bench::freeBodyScene(), bench::dzhanibekovScene(), bench::symmetricTopScene()}) {
    try {
      const ap::TorqueFreeMotion probe(bodyOf(scene), scene.initial);
      benchmark::RegisterBenchmark(("exact/" + scene.name).c_str(), exactCost, scene);
    } catch (const std::logic_error&) {
      // a form the core does not provide yet: nothing to time
    }
  }
}

// ---- the engine with late fixes (docs/design.md §6.9) ----------------------------------------

constexpr ap::Stamp kEpoch = 1780000000LL * 1000000000LL;  // a 2026 ROS time

ap::Stamp stampOf(double t) { return kEpoch + static_cast<ap::Stamp>(std::llround(t * 1e9)); }

struct NullSink : ap::EngineSink {
  void publishState(const ap::EngineState& s) override { benchmark::DoNotOptimize(s.q_WB); }
  void inputApplied(const ap::Input&, const ap::EngineState&) override {}
  void note(const ap::EngineNote&) override {}
};

ap::Input rateInput(double t) {
  ap::Input in;
  in.source = ap::Source::Imu;
  in.stamp = stampOf(t);
  in.value = rateAt(t);
  return in;
}

ap::Input torqueInput(double t) {
  ap::Input in;
  in.source = ap::Source::Torque;
  in.stamp = stampOf(t);
  in.value = Eigen::Vector3d(0.3 * std::sin(t), -0.5, 0.2);
  return in;
}

// The bias prior and random walk decide how soon the attitude variance, growing without a fix
// by about (sigma_b t)^2 + q^2 t^3 / 3, reaches its cap pi^2, after which every step clamps it.
// Below the cap: a tactical prior and no random walk, about 1.3e5 s of stamp time (a run of
// several seconds of benchmark time covers 1e4). At the cap: the defaults (MEMS), there within
// about 300 s.
ap::EngineConfig kinematicFixConfig(bool at_cap = false) {
  ap::EngineConfig c;
  c.model = ap::Model::Kinematic;
  c.kinematic.integrator = Integrator::Cf4;
  c.rate_stddev = 1e-3;
  c.fixes.estimate_gyro_bias = true;
  if (!at_cap) {
    c.fixes.gyro_bias_stddev = 2.424e-5;
    c.fixes.gyro_bias_random_walk = 0.0;
  }
  c.fixes.history = 1.5;
  return c;
}

ap::EngineConfig dynamicFixConfig() {
  ap::EngineConfig c;
  c.model = ap::Model::Dynamic;
  ap::DynamicConfig d;
  d.body = ap::RigidBody::fromPrincipalMoments(Eigen::Vector3d(1.07, 2.10, 2.83));
  d.integrator = Integrator::Rk4;
  d.torque_input = true;
  d.max_step = 0.01;
  d.initial.w_B = Eigen::Vector3d(0.7, -0.4, 1.1);
  c.dynamic = d;
  c.publish_rate = 100.0;
  c.initial_orientation_stddev = 0.05;
  c.fixes.history = 1.5;
  return c;
}

const Eigen::Matrix3d kFixCovariance = 1e-6 * Eigen::Matrix3d::Identity();

/// One step of the model: a rate input (kinematic), or a torque and a clock tick at the grid
/// stamp (dynamic), at sample k.
void feed(ap::AttitudeEngine& engine, bool dynamic, long k) {
  if (!dynamic) {
    engine.submit(rateInput(k * kDt));
    return;
  }
  const double t = 0.01 * k;
  if (k % 10 == 0) engine.submit(torqueInput(t + 0.0037));  // a new torque every 0.1 s
  engine.clockTick(stampOf(t));
}

void engineSampleCost(benchmark::State& state, bool dynamic, bool history, bool at_cap = false) {
  NullSink sink;
  ap::AttitudeEngine engine(dynamic ? dynamicFixConfig() : kinematicFixConfig(at_cap), sink);
  long k = 0;
  feed(engine, dynamic, k++);
  if (history) engine.submitFix(stampOf(0.0), engine.state().q_WB, kFixCovariance);
  for (auto _ : state) {
    feed(engine, dynamic, k++);
    benchmark::DoNotOptimize(engine.state().q_WB.coeffs().data());
  }
  state.counters["history"] = static_cast<double>(engine.fixHistorySize());
}

void fixReplayCost(benchmark::State& state, bool dynamic) {
  NullSink sink;
  ap::AttitudeEngine engine(dynamic ? dynamicFixConfig() : kinematicFixConfig(), sink);
  const long per_second = dynamic ? 100 : 200;
  const double step = 1.0 / static_cast<double>(per_second);
  feed(engine, dynamic, 0);
  engine.submitFix(stampOf(0.0), engine.state().q_WB, kFixCovariance);
  long k = 0;
  Eigen::Quaterniond q = engine.state().q_WB;
  // The rates a second on (the first time 1.5 s), keeping the estimate a second before the
  // newest state: a fix there is inside the gate.
  auto moveOn = [&](long samples) {
    const long fix_at = k + samples - per_second;
    if (k == fix_at) q = engine.state().q_WB;
    while (k < fix_at + per_second) {
      feed(engine, dynamic, ++k);
      if (k == fix_at) q = engine.state().q_WB;
    }
  };
  moveOn(3 * per_second / 2);
  for (auto _ : state) {
    const ap::FixOutcome outcome =
        engine.submitFix(stampOf(static_cast<double>(k - per_second) * step), q, kFixCovariance);
    benchmark::DoNotOptimize(outcome);
    state.PauseTiming();
    moveOn(per_second);
    state.ResumeTiming();
  }
  state.counters["replayed"] = static_cast<double>(per_second);
  const ap::EngineCounters& c = engine.counters();
  state.counters["accepted"] = static_cast<double>(c.fixes_accepted);
  state.counters["gated"] = static_cast<double>(c.fixes_rejected_gate);
  state.counters["over_budget"] = static_cast<double>(c.fixes_over_budget);
  state.counters["too_old"] = static_cast<double>(c.fixes_too_old);
}

void registerFixes() {
  for (bool dynamic : {false, true}) {
    const std::string model = dynamic ? "dynamic_rk4" : "kinematic_cf4";
    benchmark::RegisterBenchmark(("engineSample/" + model).c_str(), engineSampleCost, dynamic,
                                 false, false);
    benchmark::RegisterBenchmark(("engineSample/" + model + "_fix_history").c_str(),
                                 engineSampleCost, dynamic, true, false);
    if (!dynamic) {
      benchmark::RegisterBenchmark("engineSample/kinematic_cf4_at_cap", engineSampleCost, false,
                                   false, true);
    }
    benchmark::RegisterBenchmark(("fixReplay/" + model).c_str(), fixReplayCost, dynamic)
        ->Unit(benchmark::kMicrosecond);
  }
}

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  registerKinematic();
  registerDynamic();
  registerFixes();
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
