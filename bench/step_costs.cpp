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
#include <benchmark/benchmark.h>

#include <stdexcept>
#include <string>
#include <vector>

#include "attitude_propagator/dynamic_step.h"
#include "attitude_propagator/kinematic_propagator.h"
#include "attitude_propagator/kinematic_step.h"
#include "attitude_propagator/torque_free_motion.h"
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

void addSampleCost(benchmark::State& state, Integrator method,
                   ap::RateSamples kind = ap::RateSamples::Instantaneous,
                   ap::StampFilter filter = ap::StampFilter::None) {
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
  for (auto _ : state) {
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
                                 ap::RateSamples::Instantaneous, ap::StampFilter::None);
  }
  // The real-stream paths, next to addSample/cf4 in the same run: averaged samples (delta-angle
  // cubic, gap check), and the same with the sensor-clock stamp filter.
  benchmark::RegisterBenchmark("addSample/cf4_interval_average", addSampleCost, Integrator::Cf4,
                               ap::RateSamples::IntervalAverage, ap::StampFilter::None);
  benchmark::RegisterBenchmark("addSample/cf4_interval_average_sensor_clock", addSampleCost,
                               Integrator::Cf4, ap::RateSamples::IntervalAverage,
                               ap::StampFilter::SensorClock);
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

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  registerKinematic();
  registerDynamic();
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
