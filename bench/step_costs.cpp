// bench_step_costs: the cost of one step of every integrator with Google Benchmark.
//
// Each benchmark is one dependent chain (the next step starts from the last result), as in a
// propagator, so the figure is latency, not throughput of independent steps. Pitfalls kept out
// (REFERENCE §6): the state changes every iteration so nothing is constant-folded, results go
// through benchmark::DoNotOptimize, and every step is renormalised as the propagators do.
//
//   kinematicStep/<method>   one kinematicStep on a four-sample window, then normalise
//   addSample/<method>       KinematicPropagator::addSample, the node's path per message
#include <benchmark/benchmark.h>

#include <string>
#include <vector>

#include "attitude_propagator/kinematic_propagator.h"
#include "attitude_propagator/kinematic_step.h"
#include "methods.h"

namespace {

namespace ap = attitude_propagator;
using ap::Integrator;

constexpr double kDt = 1.0 / 200.0;  // s, a 200 Hz gyro

// A coning-like body rate (REFERENCE §2), rad/s.
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

void addSampleCost(benchmark::State& state, Integrator method) {
  // Rates cycle through a table (cheap to read, not constant); time keeps increasing.
  std::vector<Eigen::Vector3d> rates(1024);
  for (std::size_t i = 0; i < rates.size(); ++i) rates[i] = rateAt(i * kDt);
  ap::KinematicConfig config;
  config.integrator = method;
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
    benchmark::RegisterBenchmark(("addSample/" + name).c_str(), addSampleCost, m);
  }
}

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  registerKinematic();
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
