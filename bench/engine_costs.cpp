// engineSubmitCost/<setting>: the cost per IMU message of AttitudeEngine::submit, the path every
// decoded rate takes in the node and in propagate_bag (source timeline, rate_delay, stamp
// filter, bias, the propagator's step, the orientation covariance, the state handed to the
// sink). Part of bench_step_costs (registered here, run by its main).
//
//   engineSubmitCost/default        the parameters' defaults (integrator auto, instantaneous rates)
//   engineSubmitCost/sensor_clock   the same with stamp_filter: sensor_clock
//   engineSubmitCost/*_jittered     receipt stamps: nominal 200 Hz plus up to 0.4 ms of latency
//
// The stamps and rates cycle through tables (cheap to read, not constant); time keeps increasing.
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdint>
#include <vector>

#include "attitude_propagator/config/parameters.h"
#include "attitude_propagator/engine.h"

namespace {

namespace ap = attitude_propagator;

constexpr std::int64_t kPeriodNs = 5'000'000;  // a 200 Hz gyro
constexpr std::size_t kTable = 1024;

class NullSink : public ap::EngineSink {
 public:
  void publishState(const ap::EngineState& state) override {
    benchmark::DoNotOptimize(state.q_WB.coeffs().data());
  }
  void inputApplied(const ap::Input&, const ap::EngineState&) override {}
  void note(const ap::EngineNote&) override {}
};

// A coning-like body rate (docs/numerics.md §8), rad/s.
Eigen::Vector3d rateAt(double t) {
  return Eigen::Vector3d(-0.0347, -0.69 * std::sin(6.9 * t), 0.69 * std::cos(6.9 * t));
}

// Latency of receipt stamps: a fixed pseudo-random pattern in [0, 0.4] ms.
std::int64_t latencyNs(std::size_t i, bool jittered) {
  if (!jittered) return 0;
  return static_cast<std::int64_t>((i * 2654435761u) % 400) * 1000;
}

void engineSubmitCost(benchmark::State& state, const char* stamp_filter, bool jittered) {
  ap::Parameters parameters;
  parameters.stamp_filter = stamp_filter;
  NullSink sink;
  ap::AttitudeEngine engine(ap::engineConfig(ap::validateParameters(parameters)), sink);
  std::vector<Eigen::Vector3d> rates(kTable);
  for (std::size_t i = 0; i < kTable; ++i) rates[i] = rateAt(i * 1e-9 * kPeriodNs);
  ap::Input input;
  input.source = ap::Source::Imu;
  std::int64_t k = 1;
  for (auto _ : state) {
    const std::size_t i = static_cast<std::size_t>(k) & (kTable - 1);
    input.stamp = k * kPeriodNs + latencyNs(i, jittered);
    input.value = rates[i];
    engine.submit(input);
    ++k;
  }
}

BENCHMARK_CAPTURE(engineSubmitCost, default, "none", false);
BENCHMARK_CAPTURE(engineSubmitCost, sensor_clock, "sensor_clock", false);
BENCHMARK_CAPTURE(engineSubmitCost, default_jittered, "none", true);
BENCHMARK_CAPTURE(engineSubmitCost, sensor_clock_jittered, "sensor_clock", true);

}  // namespace
