// A simulated gyro on the coning motion with late absolute fixes (docs/design.md §6.9): the
// scene of the fix tests (test_fixes.cpp) and of the fixes chart (bench_sweep --fixes,
// docs/benchmarks.md), shared so both see the same streams.
#pragma once

#include <cmath>
#include <functional>
#include <random>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Geometry>

#include "attitude_propagator/engine.h"
#include "attitude_propagator/numerics/coning_motion.h"
#include "attitude_propagator/numerics/quaternion.h"
#include "engine_fixtures.h"

namespace simulated_gyro {

namespace ap = attitude_propagator;

constexpr double kDegPerHour = M_PI / 180.0 / 3600.0;  // rad/s

struct GyroRun {
  double rms_after_60 = 0.0;  ///< rad, RMS of the attitude error's angle after 60 s
  double mean_nees = 0.0;     ///< of the attitude after 60 s
  double bias_error_120 = 0.0;
  double bias_error_end = 0.0;
  Eigen::Vector3d final_error_W = Eigen::Vector3d::Zero();  ///< Log(q_est q_true^-1)
  Eigen::Vector3d predicted_drift_W = Eigen::Vector3d::Zero();
  std::vector<ap::FixOutcome> outlier_outcomes;
  ap::EngineCounters counters;
};

// 200 Hz gyro: the coning rate, a constant bias of 10 deg/h and white noise of 0.1 deg/sqrt(h)
// angle random walk; fixes at 5 Hz stamped 1.3 ms after a sample with 1 mrad noise, handed in
// 150 ms late; `outliers`: that fraction of them 0.5 rad off instead.
/// Called once per sample, after the fixes handed in with it: the time, the engine's state,
/// the true attitude and the true bias.
using Trace = std::function<void(double t, const ap::EngineState& s,
                                 const Eigen::Quaterniond& truth, const Eigen::Vector3d& bias)>;

inline GyroRun simulateGyro(double seconds, bool fixes, bool estimate_bias, double outliers,
                            const Trace& trace = nullptr) {
  const double h = 0.005;
  const double arw = 0.1 * M_PI / 180.0 / 60.0;  // rad/sqrt(s)
  const double rate_sigma = arw / std::sqrt(h);  // per sample
  const double fix_sigma = 1e-3;
  const Eigen::Vector3d bias = 10.0 * kDegPerHour * Eigen::Vector3d(1.0, -0.5, 0.8).normalized();
  const ap::ConingMotion cone;
  ap::EngineConfig config = engine_fixtures::kinematicConfig();
  config.kinematic.integrator = ap::Integrator::Cf4;
  config.kinematic.initial_q_WB = cone.attitude(0.0);
  config.rate_stddev = rate_sigma;
  config.initial_orientation_stddev = 0.0;
  config.fixes.mode = ap::FixMode::Fuse;
  config.fixes.estimate_gyro_bias = estimate_bias;
  config.fixes.gyro_bias_random_walk = 1e-7;  // the truth's bias is constant
  config.fixes.gyro_bias_stddev = 2.424e-5;   // a tactical gyro's prior, 5 deg/h
  engine_fixtures::Recorder sink;
  sink.states.reserve(static_cast<std::size_t>(seconds / h) + 2);
  ap::AttitudeEngine engine(config, sink);
  std::mt19937_64 rng(20240611);
  std::normal_distribution<double> normal(0.0, 1.0);
  auto gaussian = [&]() { return Eigen::Vector3d(normal(rng), normal(rng), normal(rng)); };
  std::mt19937_64 outlier_rng(7);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);

  struct Fix {
    double t;
    Eigen::Quaterniond q;
    bool outlier;
  };
  std::vector<Fix> queued;
  GyroRun run;
  double sum_sq = 0.0, sum_nees = 0.0;
  std::size_t n_after_60 = 0;
  const int steps = static_cast<int>(std::lround(seconds / h));
  int next_fix = 0;
  for (int k = 0; k <= steps; ++k) {
    const double t = h * k;
    engine.submit(engine_fixtures::rate(engine_fixtures::at(t),
                                        cone.bodyRate(t) + bias + rate_sigma * gaussian()));
    run.predicted_drift_W += h * (cone.attitude(t) * bias);
    // Fixes are measured 1.3 ms after a sample and handed in 150 ms later.
    const double fix_t = 0.2 * next_fix + 0.0013;
    if (fix_t < t) {
      // The same draws with and without outliers, so the good fixes are the same.
      const Eigen::Vector3d noise = fix_sigma * gaussian();
      const Eigen::Vector3d direction = gaussian().normalized();
      const bool outlier = uniform(outlier_rng) < outliers && next_fix > 0;
      const Eigen::Vector3d off = outlier ? Eigen::Vector3d(0.5 * direction) : noise;
      queued.push_back({fix_t, cone.attitude(fix_t) * ap::expMap(off), outlier});
      ++next_fix;
    }
    while (fixes && !queued.empty() && queued.front().t + 0.15 <= t) {
      const ap::FixOutcome o =
          engine.submitFix(engine_fixtures::at(queued.front().t), queued.front().q,
                           fix_sigma * fix_sigma * Eigen::Matrix3d::Identity());
      if (queued.front().outlier) run.outlier_outcomes.push_back(o);
      queued.erase(queued.begin());
    }
    const ap::EngineState s = engine.state();
    if (trace) trace(t, s, cone.attitude(t), bias);
    if (t > 60.0) {
      const Eigen::Vector3d e = ap::logMap(s.q_WB.conjugate() * cone.attitude(t));
      sum_sq += e.squaredNorm();
      sum_nees += e.dot(s.P_B.ldlt().solve(e));
      ++n_after_60;
    }
    if (k == static_cast<int>(std::lround(120.0 / h))) {
      run.bias_error_120 = (s.gyro_bias_estimate_B - bias).norm();
    }
  }
  const ap::EngineState s = engine.state();
  run.rms_after_60 = std::sqrt(sum_sq / static_cast<double>(n_after_60));
  run.mean_nees = sum_nees / static_cast<double>(n_after_60);
  run.bias_error_end = (s.gyro_bias_estimate_B - bias).norm();
  run.final_error_W = ap::logMap(s.q_WB * cone.attitude(seconds).conjugate());
  run.counters = engine.counters();
  return run;
}

}  // namespace simulated_gyro
