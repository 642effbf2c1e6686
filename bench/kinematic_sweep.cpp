#include "kinematic_sweep.h"

#include <algorithm>
#include <cmath>

#include "attitude_propagator/kinematic_propagator.h"
#include "attitude_propagator/quaternion.h"
#include "methods.h"

namespace bench {

namespace {

using ap::Integrator;
using ap::RateSample;

// States after the anchor that no causal method can get to fourth order: until four samples
// exist only lower-degree interpolants are available. cf4 integrates again from the anchor when
// the fourth sample arrives; the three earlier states are left out of the path error, as in
// test/core/test_kinematic_step.cpp.
constexpr long kStartUpSamples = 3;

// A step that changes |q| by more than this before renormalisation no longer resembles a
// rotation: the renormalised result is mostly an artefact ("loses the norm").
constexpr double kNormLost = 0.1;
// An attitude error beyond this is no longer an error estimate but a wrong answer.
constexpr double kDiverged = 1.0;

std::vector<RateSample> sampleScene(const KinematicScene& scene, double dt, long steps) {
  std::vector<RateSample> samples(steps + 1);
  for (long k = 0; k <= steps; ++k) {
    const double t = k * dt;
    samples[k] = {t, scene.rate(t)};
  }
  return samples;
}

ap::KinematicPropagator makePropagator(Integrator method, const Eigen::Quaterniond& q0) {
  ap::KinematicConfig config;
  config.integrator = method;
  config.initial_q_WB = q0;
  config.time_policy.max_dt = 1e3;  // the stability map uses steps far beyond the default
  return ap::KinematicPropagator(config);
}

// The propagation that is timed: the node's path (addSample), nothing else in the loop.
double propagate(Integrator method, const Eigen::Quaterniond& q0,
                 const std::vector<RateSample>& samples) {
  auto propagator = makePropagator(method, q0);
  for (const RateSample& s : samples) propagator.addSample(s.t, s.w_B);
  return propagator.orientation().w();
}

// The untimed pass: errors against the closed form at every sample.
void measureErrors(Integrator method, const KinematicScene& scene,
                   const std::vector<RateSample>& samples, Result& r) {
  auto propagator = makePropagator(method, scene.attitude(0.0));
  double worst = 0.0;
  double norm_err = 0.0;
  double last = 0.0;
  for (std::size_t k = 0; k < samples.size(); ++k) {
    propagator.addSample(samples[k].t, samples[k].w_B);
    norm_err = std::max(norm_err, std::abs(propagator.normError()));
    last = ap::rotationAngle(propagator.orientation(), scene.attitude(samples[k].t));
    if (static_cast<long>(k) >= kStartUpSamples || k + 1 == samples.size()) {
      worst = std::max(worst, last);
    }
  }
  r.err_rad = worst;
  r.final_err_rad = last;
  r.norm_err = norm_err;
}

std::string classify(const Result& r) {
  if (!std::isfinite(r.err_rad) || !std::isfinite(r.norm_err)) return "nonfinite";
  if (r.norm_err > kNormLost) return "norm_lost";
  if (r.final_err_rad > kDiverged) return "diverged";
  return "ok";
}

Integrator autoChoice() { return makePropagator(Integrator::Auto, {1, 0, 0, 0}).integrator(); }

Result baseResult(const KinematicScene& scene, Integrator method, double dt, long steps) {
  Result r;
  r.scene = scene.name;
  r.method = ap::integratorName(method);
  r.is_auto = method == autoChoice();
  r.dt = dt;
  r.omega_dt = dt * scene.max_rate;
  r.steps = steps;
  return r;
}

// All methods on one sampled scene: errors from one untimed pass each, costs interleaved.
void sweepOneStep(const KinematicScene& scene, double rate, const TimingOptions& timing,
                  std::FILE* out) {
  const double dt = 1.0 / rate;
  const long steps = std::lround(scene.duration * rate);
  const auto samples = sampleScene(scene, dt, steps);
  const Eigen::Quaterniond q0 = scene.attitude(0.0);
  const auto methods = methodsFor(ap::Model::Kinematic);
  std::vector<Run> runs;
  for (Integrator method : methods) {
    runs.push_back([method, q0, &samples] { return propagate(method, q0, samples); });
  }
  const std::vector<double> ns = medianNsPerStep(runs, steps, timing);
  for (std::size_t m = 0; m < methods.size(); ++m) {
    Result r = baseResult(scene, methods[m], dt, steps);
    measureErrors(methods[m], scene, samples, r);
    r.ns_per_step = ns[m];
    r.status = classify(r);
    writeRow(out, r);
  }
}

}  // namespace

bool checkClosedForm(const KinematicScene& scene) {
  const double h = 1e-6;
  for (double t : {0.0, 0.37, 1.9, scene.duration}) {
    const Eigen::Vector4d derivative =
        (scene.attitude(t + h).coeffs() - scene.attitude(t - h).coeffs()) / (2 * h);
    const Eigen::Vector4d expected =
        0.5 * (scene.attitude(t) * ap::pureQuaternion(scene.rate(t))).coeffs();
    if ((derivative - expected).norm() > 1e-6 * (1.0 + scene.max_rate)) {
      std::fprintf(stderr, "bench: closed form of %s fails dq/dt = q w/2 at t = %g\n",
                   scene.name.c_str(), t);
      return false;
    }
  }
  return true;
}

void runKinematicSweep(const std::vector<KinematicScene>& scenes, const TimingOptions& timing,
                       std::FILE* out) {
  for (const KinematicScene& scene : scenes) {
    for (double rate : scene.sample_rates) sweepOneStep(scene, rate, timing, out);
    std::fprintf(stderr, "bench: %s done\n", scene.name.c_str());
  }
}

void runKinematicStability(const KinematicScene& scene, double duration, std::FILE* out) {
  for (int i = 0; i <= 16; ++i) {
    const double omega_dt = 1e-3 * std::pow(10.0, i / 4.0);  // 1e-3 .. 10, four per decade
    const double dt = omega_dt / scene.max_rate;
    const long steps = std::max(1L, std::lround(duration / dt));
    const auto samples = sampleScene(scene, dt, steps);
    for (Integrator method : methodsFor(ap::Model::Kinematic)) {
      Result r = baseResult(scene, method, dt, steps);
      measureErrors(method, scene, samples, r);
      r.status = classify(r);
      writeRow(out, r);
    }
  }
}

}  // namespace bench
