#include "kinematic_sweep.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

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

// Reproducible noise: a 64-bit LCG (Knuth's MMIX constants) and Box-Muller.
struct Noise {
  std::uint64_t state;
  double uniform() {
    state = state * 6364136223846793005ULL + 1442695040888963407ULL;
    return static_cast<double>(state >> 11) * 0x1.0p-53;
  }
  double normal() {
    const double u1 = 1.0 - uniform(), u2 = uniform();
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
  }
};

// Point samples k dt; with jitter > 0 each stamp after the anchor is late or early by a normal
// receipt delay of that RMS (the rate is still the one at k dt).
std::vector<RateSample> sampleScene(const KinematicScene& scene, double dt, long steps,
                                    double jitter = 0.0) {
  Noise noise{1};
  std::vector<RateSample> samples(steps + 1);
  for (long k = 0; k <= steps; ++k) {
    const double t = k * dt;
    samples[k] = {t + (k > 0 && jitter > 0.0 ? jitter * noise.normal() : 0.0), scene.rate(t)};
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
    // At the stamp the state holds at (the sample's, unless a jittered one was dropped).
    last = ap::rotationAngle(propagator.orientation(), scene.attitude(propagator.time()));
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
  for (double jitter : {0.0, 1e-4, 1e-3}) {  // receipt-stamped drivers add 0.1-2 ms
    for (int i = 0; i <= 16; ++i) {
      const double omega_dt = 1e-3 * std::pow(10.0, i / 4.0);  // 1e-3 .. 10, four per decade
      const double dt = omega_dt / scene.max_rate;
      const long steps = std::max(1L, std::lround(duration / dt));
      const auto samples = sampleScene(scene, dt, steps, jitter);
      for (Integrator method : methodsFor(ap::Model::Kinematic)) {
        Result r = baseResult(scene, method, dt, steps);
        r.jitter_s = jitter;
        measureErrors(method, scene, samples, r);
        r.status = classify(r);
        writeRow(out, r);
      }
    }
  }
}

}  // namespace bench

// ---------------------------------------------------------------------------------------------
// Real streams. Each stream model turns the scene's closed-form rate into what a gyro driver
// delivers; the error is measured against the closed form at the stamp each state is reported
// at (what a tf listener sees).
// ---------------------------------------------------------------------------------------------

namespace bench {

namespace {

// Mean of the scene's rate over [a, b] by 5-point Gauss-Legendre (exact to degree 9).
Eigen::Vector3d intervalMean(const KinematicScene& scene, double a, double b) {
  static const double x[5] = {-0.9061798459386640, -0.5384693101056831, 0.0, 0.5384693101056831,
                              0.9061798459386640};
  static const double w[5] = {0.2369268850561891, 0.4786286704993665, 0.5688888888888889,
                              0.4786286704993665, 0.2369268850561891};
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (int i = 0; i < 5; ++i) sum += w[i] * scene.rate(0.5 * (a + b) + 0.5 * (b - a) * x[i]);
  return 0.5 * sum;
}

struct StreamModel {
  std::string name;
  double rate_hz = 200.0;
  bool averaged = false;   // the gyro delivers interval means
  bool mid_stamp = false;  // ... stamped at the interval's midpoint (else at its end)
  double jitter = 0.0;     // s, receipt jitter (standard deviation)
  double drop = 0.0;       // probability a sample is lost
  bool mems = false;       // angle random walk and 16-bit quantization
  ap::RateSamples setting = ap::RateSamples::Instantaneous;
  ap::StampFilter filter = ap::StampFilter::None;
  int max_gap_fill = 4;
};

// Noisy MEMS gyro: angle random walk 0.1 deg/sqrt(h), 16-bit output over +-2000 deg/s.
constexpr double kArw = 0.1 * M_PI / 180.0 / 60.0;        // rad/sqrt(s)
constexpr double kLsb = 4000.0 / 65536.0 * M_PI / 180.0;  // rad/s
constexpr double kDeg2000 = 2000.0 * M_PI / 180.0;        // rad/s

std::vector<StreamModel> streamModels() {
  using RS = ap::RateSamples;
  std::vector<StreamModel> m(11);
  m[0].name = "point";
  m[1].name = "averaged_end";
  m[1].averaged = true;
  m[1].setting = RS::IntervalAverage;
  m[2].name = "averaged_end_as_point";  // the same data read as point samples (the old default)
  m[2].averaged = true;
  m[3].name = "averaged_mid";
  m[3].averaged = true;
  m[3].mid_stamp = true;
  m[4].name = "jitter_0.1ms";
  m[4].jitter = 1e-4;
  m[5].name = "jitter_0.1ms_sensor_clock";
  m[5].jitter = 1e-4;
  m[5].filter = ap::StampFilter::SensorClock;
  m[6].name = "jitter_1ms_400Hz";
  m[6].jitter = 1e-3;
  m[6].rate_hz = 400.0;
  m[7].name = "drops_5pct_averaged";
  m[7].averaged = true;
  m[7].drop = 0.05;
  m[7].setting = RS::IntervalAverage;
  m[8] = m[7];
  m[8].name = "drops_5pct_averaged_no_fill";
  m[8].max_gap_fill = 0;
  m[9].name = "mems_averaged";
  m[9].averaged = true;
  m[9].mems = true;
  m[9].setting = RS::IntervalAverage;
  m[10] = m[9];
  m[10].name = "mems_averaged_jitter_0.1ms_sensor_clock";
  m[10].jitter = 1e-4;
  m[10].filter = ap::StampFilter::SensorClock;
  return m;
}

// Sample k is taken at k h. The anchor keeps its exact stamp and rate so every method starts
// from the truth.
std::vector<RateSample> makeStream(const KinematicScene& scene, const StreamModel& model,
                                   std::uint64_t seed) {
  Noise noise{seed};
  const double h = 1.0 / model.rate_hz;
  const long n = std::lround(scene.duration * model.rate_hz);
  std::vector<RateSample> samples;
  for (long k = 0; k <= n; ++k) {
    const double t = k * h;
    Eigen::Vector3d w = model.averaged ? intervalMean(scene, t - h, t) : scene.rate(t);
    double stamp = model.mid_stamp ? t - 0.5 * h : t;
    if (k > 0) {
      if (model.mems) {
        for (int i = 0; i < 3; ++i) {
          const double noisy = w[i] + kArw / std::sqrt(h) * noise.normal();
          w[i] = std::clamp(kLsb * std::round(noisy / kLsb), -kDeg2000, kDeg2000);
        }
      }
      stamp += model.jitter * noise.normal();
      if (k > 3 && noise.uniform() < model.drop) continue;
    }
    samples.push_back({stamp, w});
  }
  return samples;
}

// Error the stream's noise alone leaves after the scene's duration T (1 sigma), rad:
// MEMS: angle random walk and quantization, sqrt(ARW^2 T + (LSB^2/12) h T);
// jitter: each stamp error e moves the rate by dw/dt e, sigma |dw/dt|_rms sqrt(h T).
double noiseFloor(const KinematicScene& scene, const StreamModel& model) {
  const double h = 1.0 / model.rate_hz, T = scene.duration;
  double floor2 = 0.0;
  if (model.mems) floor2 += kArw * kArw * T + kLsb * kLsb / 12.0 * h * T;
  if (model.jitter > 0.0 && model.filter == ap::StampFilter::None) {
    double sum = 0.0;
    const int n = 1000;
    for (int i = 0; i < n; ++i) {
      const double t = T * i / n, dt = 1e-5;
      sum += ((scene.rate(t + dt) - scene.rate(t - dt)) / (2 * dt)).squaredNorm();
    }
    floor2 += model.jitter * model.jitter * (sum / n) * h * T;
  }
  return floor2 > 0.0 ? std::sqrt(floor2) : NAN;
}

// A stamp filter learns the sensor clock over its first seconds; the error is also taken
// after this share of the run, when the clock model has settled (5 s of the 20 s scenes).
constexpr double kSettledShare = 0.25;

struct StreamError {
  double worst = 0.0;          // the largest error after the start-up samples
  double worst_settled = 0.0;  // ... after kSettledShare of the run
};

StreamError streamError(const KinematicScene& scene, const StreamModel& model, Integrator method,
                        const std::vector<RateSample>& samples) {
  ap::KinematicConfig config;
  config.integrator = method;
  config.initial_q_WB = scene.attitude(samples.front().t);
  config.rate_samples = model.setting;
  config.stamp_filter = model.filter;
  config.max_gap_fill = model.max_gap_fill;
  ap::KinematicPropagator propagator(config);
  StreamError error;
  const double settled = samples.front().t + kSettledShare * scene.duration;
  for (std::size_t k = 0; k < samples.size(); ++k) {
    propagator.addSample(samples[k].t, samples[k].w_B);
    if (static_cast<long>(k) < kStartUpSamples) continue;
    // Midpoint stamps: the state at stamp s is the attitude half a period later.
    const double shift = model.mid_stamp ? 0.5 / model.rate_hz : 0.0;
    const double e =
        ap::rotationAngle(propagator.orientation(), scene.attitude(propagator.time() + shift));
    error.worst = std::max(error.worst, e);
    if (propagator.time() >= settled) error.worst_settled = std::max(error.worst_settled, e);
  }
  return error;
}

double median(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  return values[values.size() / 2];
}

}  // namespace

void runStreamSweep(const std::vector<KinematicScene>& scenes, std::FILE* out) {
  std::fputs(
      "scene,stream,method,auto,rate_hz,rate_samples,stamp_filter,max_gap_fill,seeds,"
      "err_rad,err_rad_max,floor_rad,err_settled_rad\n",
      out);
  constexpr int kSeeds = 5;  // median over seeds for the random streams
  for (const KinematicScene& scene : scenes) {
    for (const StreamModel& model : streamModels()) {
      const bool random = model.jitter > 0.0 || model.drop > 0.0 || model.mems;
      const int seeds = random ? kSeeds : 1;
      std::vector<std::vector<RateSample>> streams;
      for (int s = 1; s <= seeds; ++s) streams.push_back(makeStream(scene, model, s));
      for (Integrator method : methodsFor(ap::Model::Kinematic)) {
        std::vector<double> errors, settled;
        for (const auto& samples : streams) {
          const StreamError e = streamError(scene, model, method, samples);
          errors.push_back(e.worst);
          settled.push_back(e.worst_settled);
        }
        std::sort(errors.begin(), errors.end());
        std::fprintf(out, "%s,%s,%s,%d,%g,%s,%s,%d,%d,%s,%s,%s,%s\n", scene.name.c_str(),
                     model.name.c_str(), ap::integratorName(method).c_str(),
                     method == autoChoice() ? 1 : 0, model.rate_hz,
                     ap::rateSamplesName(model.setting).c_str(),
                     ap::stampFilterName(model.filter).c_str(), model.max_gap_fill, seeds,
                     field(errors[errors.size() / 2]).c_str(), field(errors.back()).c_str(),
                     field(noiseFloor(scene, model)).c_str(), field(median(settled)).c_str());
      }
    }
    std::fprintf(stderr, "bench: streams on %s done\n", scene.name.c_str());
  }
}

}  // namespace bench
