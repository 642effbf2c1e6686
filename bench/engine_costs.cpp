// engineSubmitCost/<setting>: the cost per IMU message of AttitudeEngine::submit, the path every
// decoded rate takes in the node and in propagate_bag (source timeline, rate_delay, stamp
// filter, bias, the propagator's step, the orientation covariance, the state handed to the
// sink). Part of bench_step_costs (registered here, run by its main).
//
//   engineSubmitCost/default        the parameters' defaults (integrator auto, instantaneous rates)
//   engineSubmitCost/sensor_clock   the same with stamp_filter: sensor_clock
//   engineSubmitCost/*_jittered     receipt stamps: nominal 200 Hz plus up to 0.4 ms of latency
//
// engineAidedCost/<setting>: the cost per IMU sample of the kinematic engine fed a rate and the
// sample's acceleration (submit + submitAcceleration: the gravity direction fused at its stamp,
// docs/design.md §6.10), next to the same engine fed the rate alone, so one run gives the ratio
// (run with --benchmark_enable_random_interleaving so the two alternate):
//   engineAidedCost/gyro_only        the rate alone (the defaults, exp2 as the aided ones)
//   engineAidedCost/accel            use_accel
//   engineAidedCost/accel_bias       use_accel with estimate_gyro_bias (the 6x6 error state)
//   engineAidedCost/gyro_only_bias   the rate alone with estimate_gyro_bias
//
// The stamps and rates cycle through tables (cheap to read, not constant); time keeps increasing.
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdint>
#include <vector>

#include "../test/core/simulated_imu.h"
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

// A periodic attitude (period kTable samples, so the tables close on themselves and time can
// run on): its body rate and the specific force of a body at rest, f_B = C_BW (0, 0, g).
Eigen::Quaterniond periodicAttitude(double t) {
  const double w = 2.0 * M_PI / (kTable * 1e-9 * kPeriodNs);
  return Eigen::Quaterniond(
      Eigen::AngleAxisd(0.5 * std::sin(w * t + 1.0), Eigen::Vector3d::UnitZ()) *
      Eigen::AngleAxisd(0.2 * std::sin(2.0 * w * t), Eigen::Vector3d::UnitY()) *
      Eigen::AngleAxisd(0.3 * std::sin(w * t), Eigen::Vector3d::UnitX()));
}

void engineAidedCost(benchmark::State& state, bool use_accel, bool estimate_bias) {
  ap::Parameters parameters;
  ap::EngineConfig config = ap::engineConfig(ap::validateParameters(parameters));
  config.kinematic.integrator = ap::Integrator::Exp2;
  config.rate_stddev = 0.005;
  config.aiding.use_accel = use_accel;
  config.aiding.accel_stddev = 0.05;
  config.fixes.estimate_gyro_bias = estimate_bias;
  config.fixes.gyro_bias_stddev = 0.01;
  NullSink sink;
  ap::AttitudeEngine engine(config, sink);
  std::vector<Eigen::Vector3d> rates(kTable), forces(kTable);
  for (std::size_t i = 0; i < kTable; ++i) {
    const double t = i * 1e-9 * kPeriodNs;
    rates[i] = simulated_imu::bodyRate(periodicAttitude, t);
    forces[i] = periodicAttitude(t).conjugate() * Eigen::Vector3d(0, 0, ap::kStandardGravity);
  }
  // Started on the motion, so the gravity samples agree with the state from the first.
  engine.setState(0, periodicAttitude(0.0), rates[0]);
  ap::Input input;
  input.source = ap::Source::Imu;
  std::int64_t k = 1;
  for (auto _ : state) {
    const std::size_t i = static_cast<std::size_t>(k) & (kTable - 1);
    input.stamp = k * kPeriodNs;
    input.value = rates[i];
    engine.submit(input);
    if (use_accel) engine.submitAcceleration(input.stamp, forces[i], Eigen::Matrix3d::Zero());
    ++k;
  }
  // Every sample fused, none rejected: the cost is the update's, not a gate's.
  const ap::AidingCounters& a = engine.counters().accel;
  state.counters["accel_accepted_fraction"] =
      use_accel ? static_cast<double>(a.accepted) / static_cast<double>(k - 1) : 0.0;
}

BENCHMARK_CAPTURE(engineAidedCost, gyro_only, false, false);
BENCHMARK_CAPTURE(engineAidedCost, accel, true, false);
BENCHMARK_CAPTURE(engineAidedCost, gyro_only_bias, false, true);
BENCHMARK_CAPTURE(engineAidedCost, accel_bias, true, true);

}  // namespace
