#include "kinematic_sweep.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <set>
#include <string>
#include <utility>

#include "../test/core/gyro_streams.h"
#include "attitude_propagator/models/kinematic_propagator.h"
#include "attitude_propagator/numerics/quaternion.h"
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
  // Exponential, mean and standard deviation 1: never negative.
  double exponential() { return -std::log(1.0 - uniform()); }
};

// A receipt stamp is the sample's time plus a latency that is never negative: no driver
// receives a sample before it is taken. The latency is drawn exponential with mean and standard
// deviation `jitter` (the wait in a queue: memoryless, most draws short, its floor 0 where its
// density is highest), as the tests' streams draw it (test/core/sampling.h, latencyRandom). So
// the figure named jitter is the latency's spread, as a normal jitter's RMS was, and the stamps
// are also late by that much on average. No constant part is added: a transport delay every
// sample shares only shifts every stamp, which `rate_delay` removes.
double receiptLatency(Noise& noise, double jitter) { return jitter * noise.exponential(); }

// Point samples k dt; with jitter > 0 each stamp after the anchor is received late by an
// exponential latency of mean and standard deviation `jitter` (the rate is still the one at k dt).
std::vector<RateSample> sampleScene(const KinematicScene& scene, double dt, long steps,
                                    double jitter = 0.0) {
  Noise noise{1};
  std::vector<RateSample> samples(steps + 1);
  for (long k = 0; k <= steps; ++k) {
    const double t = k * dt;
    samples[k] = {t + (k > 0 && jitter > 0.0 ? receiptLatency(noise, jitter) : 0.0), scene.rate(t)};
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

enum class Filter { None, Butterworth, Sinc3 };

struct StreamModel {
  std::string name;
  double rate_hz = 200.0;
  bool averaged = false;  // the gyro delivers interval means
  // ... stamped at the interval's end, midpoint or start (what the data are)
  ap::AverageStamp stamped = ap::AverageStamp::End;
  double jitter = 0.0;            // s, receipt latency (exponential: mean and std deviation)
  double drop = 0.0;              // probability a sample is lost
  bool mems = false;              // angle random walk and 16-bit quantization
  Filter lowpass = Filter::None;  // an on-chip filter before the stamp
  int fifo_batch = 0;             // > 0: FIFO reads of this many samples, receipt-stamped
  gyro_streams::Fifo fifo_form = gyro_streams::Fifo::Repeated;
  double rate_after_hz = 0.0;  // > 0: the rate changes to this halfway through
  // The settings the stream is read with.
  ap::RateSamples setting = ap::RateSamples::Instantaneous;
  ap::AverageStamp average_stamp = ap::AverageStamp::End;
  ap::StampFilter filter = ap::StampFilter::None;
  double rate_delay = 0.0;  // s, `rate_delay`: every stamp moved back by it (as the engine does)
  int max_gap_fill = 4;
};

// Noisy MEMS gyro: angle random walk 0.1 deg/sqrt(h), 16-bit output over +-2000 deg/s.
constexpr double kArw = 0.1 * M_PI / 180.0 / 60.0;        // rad/sqrt(s)
constexpr double kLsb = 4000.0 / 65536.0 * M_PI / 180.0;  // rad/s
constexpr double kDeg2000 = 2000.0 * M_PI / 180.0;        // rad/s

// The on-chip filters: a 2nd-order Butterworth at ODR/4 (digital, bilinear), and a sinc^3
// decimator by 8 from an internal rate of 8 ODR. Group delays from their coefficients.
const gyro_streams::Butterworth2 kButterworth(0.25);
const gyro_streams::SincDecimator kSinc3(3, 8);
// FIFO reads of 10 samples, the read's latency spread by 0.2 ms RMS.
constexpr int kFifoBatch = 10;
constexpr double kFifoLatency = 2e-4;

std::vector<StreamModel> streamModels() {
  using RS = ap::RateSamples;
  using AS = ap::AverageStamp;
  std::vector<StreamModel> m;
  m.reserve(64);  // the references add() returns stay valid
  auto add = [&m](const std::string& name) -> StreamModel& {
    m.emplace_back();
    m.back().name = name;
    return m.back();
  };
  // Clean point samples and interval means at the rates gyros are read at.
  for (double hz : {100.0, 200.0, 400.0, 1000.0}) {
    add("point").rate_hz = hz;
    StreamModel& averaged = add("averaged_end");
    averaged.rate_hz = hz;
    averaged.averaged = true;
    averaged.setting = RS::IntervalAverage;
  }
  add("averaged_end_as_point").averaged = true;  // the means read as point samples
  for (AS position : {AS::Mid, AS::Start}) {
    // Read as end-stamped means (average_stamp left at its default).
    StreamModel& as_end = add("averaged_" + ap::averageStampName(position) + "_as_end");
    as_end.averaged = true;
    as_end.stamped = position;
    as_end.setting = RS::IntervalAverage;
    StreamModel& s = add("averaged_" + ap::averageStampName(position));
    s.averaged = true;
    s.stamped = position;
    s.setting = RS::IntervalAverage;
    s.average_stamp = position;
  }
  add("jitter_0.1ms").jitter = 1e-4;
  StreamModel& filtered = add("jitter_0.1ms_sensor_clock");
  filtered.jitter = 1e-4;
  filtered.filter = ap::StampFilter::SensorClock;
  for (ap::StampFilter filter : {ap::StampFilter::None, ap::StampFilter::SensorClock}) {
    const bool on = filter == ap::StampFilter::SensorClock;
    StreamModel& heavy = add(on ? "jitter_1ms_400Hz_sensor_clock" : "jitter_1ms_400Hz");
    heavy.jitter = 1e-3;
    heavy.rate_hz = 400.0;
    heavy.filter = filter;
  }
  StreamModel& drops = add("drops_5pct_averaged");
  drops.averaged = true;
  drops.drop = 0.05;
  drops.setting = RS::IntervalAverage;
  m.push_back(drops);
  m.back().name = "drops_5pct_averaged_no_fill";
  m.back().max_gap_fill = 0;
  StreamModel& mems = add("mems_averaged");
  mems.averaged = true;
  mems.mems = true;
  mems.setting = RS::IntervalAverage;
  m.push_back(mems);
  m.back().name = "mems_averaged_jitter_0.1ms_sensor_clock";
  m.back().jitter = 1e-4;
  m.back().filter = ap::StampFilter::SensorClock;
  // Rates through an on-chip filter, read without and with `rate_delay` at its group delay.
  for (Filter lowpass : {Filter::Butterworth, Filter::Sinc3}) {
    const bool bw = lowpass == Filter::Butterworth;
    const double delay = (bw ? kButterworth.dcDelay() : kSinc3.delay() / kSinc3.ratio) / 200.0;
    const std::string name = bw ? "butterworth2_odr4" : "sinc3_r8";
    add(name).lowpass = lowpass;
    StreamModel& delayed = add(name + "_rate_delay");
    delayed.lowpass = lowpass;
    delayed.rate_delay = delay;
  }
  // FIFO reads stamped at receipt, both forms, without and with the stamp filter.
  for (gyro_streams::Fifo form : {gyro_streams::Fifo::Repeated, gyro_streams::Fifo::Spaced}) {
    for (ap::StampFilter filter : {ap::StampFilter::None, ap::StampFilter::SensorClock}) {
      const bool repeated = form == gyro_streams::Fifo::Repeated;
      const bool on = filter == ap::StampFilter::SensorClock;
      StreamModel& s = add(std::string("fifo10_") + (repeated ? "repeated" : "spaced") +
                           (on ? "_sensor_clock" : ""));
      s.fifo_batch = kFifoBatch;
      s.fifo_form = form;
      s.filter = filter;
    }
  }
  // 200 -> 1000 Hz halfway, hardware stamps, without and with the stamp filter (it restarts).
  add("rate_change_200_1000Hz").rate_after_hz = 1000.0;
  StreamModel& change = add("rate_change_200_1000Hz_sensor_clock");
  change.rate_after_hz = 1000.0;
  change.filter = ap::StampFilter::SensorClock;
  return m;
}

bool isRandom(const StreamModel& model) {
  return model.jitter > 0.0 || model.drop > 0.0 || model.mems || model.fifo_batch > 0;
}

// The true instants samples are taken at: k / rate_hz, or after a rate change k / rate_after_hz
// from halfway on.
std::vector<double> sampleTimes(const KinematicScene& scene, const StreamModel& model) {
  const long n = std::lround(scene.duration * model.rate_hz);
  std::vector<double> times;
  const long before = model.rate_after_hz > 0.0 ? n / 2 : n;
  for (long k = 0; k <= before; ++k) times.push_back(k / model.rate_hz);
  if (model.rate_after_hz > 0.0) {
    const double t0 = times.back();
    const long after = std::lround((scene.duration - t0) * model.rate_after_hz);
    for (long k = 1; k <= after; ++k) times.push_back(t0 + k / model.rate_after_hz);
  }
  return times;
}

// Sample k is taken at times[k]. The anchor keeps its exact stamp and rate so every method
// starts from the truth (a filtered stream's anchor carries the filter's output). `taken`, if
// given, receives the instant each delivered sample was taken at.
std::vector<RateSample> makeStream(const KinematicScene& scene, const StreamModel& model,
                                   std::uint64_t seed, std::vector<double>* taken = nullptr) {
  Noise noise{seed};
  const double h = 1.0 / model.rate_hz;
  std::vector<double> times = sampleTimes(scene, model);
  std::vector<double> fifo;
  if (model.fifo_batch > 0) {
    fifo = gyro_streams::fifoStamps(model.rate_hz, model.fifo_batch, model.fifo_form, kFifoLatency,
                                    seed, static_cast<long>(times.size()) - 1);
    times.resize(fifo.size());
  }
  std::vector<Eigen::Vector3d> butterworth;
  if (model.lowpass == Filter::Butterworth) {
    const long preroll = std::lround(2.0 * model.rate_hz);  // no start-up transient
    std::vector<Eigen::Vector3d> truth;
    for (long k = -preroll; k < static_cast<long>(times.size()); ++k) {
      truth.push_back(scene.rate(k * h));
    }
    butterworth = kButterworth.filter(truth);
    butterworth.erase(butterworth.begin(), butterworth.begin() + preroll);
  }
  std::vector<RateSample> samples;
  for (std::size_t k = 0; k < times.size(); ++k) {
    const double t = times[k];
    const double period = k > 0 ? t - times[k - 1] : h;
    Eigen::Vector3d w = model.averaged ? intervalMean(scene, t - period, t) : scene.rate(t);
    if (model.lowpass == Filter::Butterworth) w = butterworth[k];
    if (model.lowpass == Filter::Sinc3) w = kSinc3.output(scene.rate, t, kSinc3.ratio / h);
    const double offset = model.stamped == ap::AverageStamp::Mid     ? 0.5 * period
                          : model.stamped == ap::AverageStamp::Start ? period
                                                                     : 0.0;
    double stamp = (model.fifo_batch > 0 ? fifo[k] : t) - offset;
    if (k > 0) {
      if (model.mems) {
        for (int i = 0; i < 3; ++i) {
          const double noisy = w[i] + kArw / std::sqrt(h) * noise.normal();
          w[i] = std::clamp(kLsb * std::round(noisy / kLsb), -kDeg2000, kDeg2000);
        }
      }
      if (model.jitter > 0.0) {
        stamp += receiptLatency(noise, model.jitter);
      } else {
        noise.normal();  // the draw a symmetric jitter took: the other streams stay as they were
      }
      if (k > 3 && noise.uniform() < model.drop) continue;
    }
    samples.push_back({stamp - model.rate_delay, w});
    if (taken != nullptr) taken->push_back(t - offset);
  }
  return samples;
}

// Error the stream's noise alone leaves (1 sigma), rad, for a scene of duration T read at h:
// MEMS: angle random walk and quantization after T, sqrt(ARW^2 T + (LSB^2/12) h T).
// Receipt latency, unfiltered: sample k (taken at t_k) is stamped s_k = t_k + e_k, e_0 = 0.
// Integrating its rate over the stamped intervals turns the world by sum (s_{k+1} - s_k) w_k;
// summed by parts that is the truth's turn to t_N plus e_N w_N (which the truth at the reported
// stamp s_N has too) minus sum e_k h dw_W/dt(t_k). So the error is -sum e_k h dw_W/dt, with
// |dw_W/dt| = |dw_B/dt| (w_W = R w_B, R' = R [w_B]x). The exponential latency splits into its
// mean mu = sigma, the same for every sample, and a zero-mean part of standard deviation sigma:
//   the zero-mean part adds up as a random walk: sigma |dw/dt|_rms sqrt(h T) after T;
//   the mean sums to mu (w_W(t) - w_W(0)): every stamp but the anchor's is late by mu, so the
//   first interval carries mu w_W(0) too much and each state is compared with the truth mu
//   later; taken as the largest along the path, mu max_t |w_W(t) - w_W(0)|, as err_rad is.
// The two are independent and added in quadrature. With the stamp filter no floor is given:
// the filter estimates the sample's time plus the least latency (near 0 for an exponential),
// removing most of both.
double noiseFloor(const KinematicScene& scene, const StreamModel& model) {
  const double h = 1.0 / model.rate_hz, T = scene.duration;
  double floor2 = 0.0;
  if (model.mems) floor2 += kArw * kArw * T + kLsb * kLsb / 12.0 * h * T;
  if (model.jitter > 0.0 && model.filter == ap::StampFilter::None) {
    const double sigma = model.jitter, mu = model.jitter;  // exponential: mean = deviation
    const Eigen::Vector3d w0_W = scene.attitude(0.0) * scene.rate(0.0);
    double sum = 0.0, drift = 0.0;
    const int n = 1000;
    for (int i = 0; i < n; ++i) {
      const double t = T * i / n, dt = 1e-5;
      sum += ((scene.rate(t + dt) - scene.rate(t - dt)) / (2 * dt)).squaredNorm();
      drift = std::max(drift, (scene.attitude(t) * scene.rate(t) - w0_W).norm());
    }
    floor2 += sigma * sigma * (sum / n) * h * T + mu * mu * drift * drift;
  }
  return floor2 > 0.0 ? std::sqrt(floor2) : NAN;
}

// A stamp filter learns the sensor clock over its first seconds; the error is also taken
// after this share of the run, when the clock model has settled (5 s of the 20 s scenes).
constexpr double kSettledShare = 0.25;

struct StreamError {
  double worst = 0.0;          // the largest error after the start-up samples
  double worst_settled = 0.0;  // ... after kSettledShare of the run
  std::set<Integrator> used;   // the methods that integrated a step (`auto`: its choices)
  double jitter = NAN;         // `auto`: its rule's jitter measure at the end
  // With the stamp filter: the most a filtered stamp was later than its receipt stamp (the
  // filter's causality: 0), and the median of the filtered stamp less the instant the sample
  // was taken, once settled (the least latency it keeps; a phase error of that times |w|).
  double filter_later = NAN;
  double filter_offset = NAN;
  double filter_fallbacks = NAN;  // times it fell back to the receipt stamps (misfit)
};

// The stamp the propagator anchors at: the first sample's, or, for a start- or mid-stamped
// mean read as such, the end of its interval (the next stamp, or halfway to it). Every state is
// compared with the truth at the stamp it is reported at (time()), whatever the reading: a
// mean read at the wrong position is an error there, as a tf listener sees it.
double anchorStamp(const StreamModel& model, const std::vector<RateSample>& samples) {
  switch (model.average_stamp) {
    case ap::AverageStamp::Start:
      return samples[1].t;
    case ap::AverageStamp::Mid:
      return 0.5 * (samples[0].t + samples[1].t);
    case ap::AverageStamp::End:
      break;
  }
  return samples.front().t;
}

StreamError streamError(const KinematicScene& scene, const StreamModel& model, Integrator method,
                        const std::vector<RateSample>& samples, const std::vector<double>& taken) {
  ap::KinematicConfig config;
  config.integrator = method;
  config.initial_q_WB = scene.attitude(anchorStamp(model, samples));
  config.rate_samples = model.setting;
  config.average_stamp = model.average_stamp;
  config.stamp_filter = model.filter;
  config.max_gap_fill = model.max_gap_fill;
  ap::KinematicPropagator propagator(config);
  StreamError error;
  const double settled = samples.front().t + kSettledShare * scene.duration;
  std::vector<double> offsets;
  for (std::size_t k = 0; k < samples.size(); ++k) {
    if (propagator.addSample(samples[k].t, samples[k].w_B) == ap::StampOutcome::Advanced) {
      error.used.insert(propagator.integrator());
      if (model.filter != ap::StampFilter::None && propagator.time() >= settled) {
        offsets.push_back(propagator.time() - taken[k]);
      }
    }
    if (static_cast<long>(k) < kStartUpSamples || !propagator.anchored()) continue;
    const double e = ap::rotationAngle(propagator.orientation(), scene.attitude(propagator.time()));
    error.worst = std::max(error.worst, e);
    if (propagator.time() >= settled) error.worst_settled = std::max(error.worst_settled, e);
  }
  if (propagator.autoRule() != nullptr) error.jitter = propagator.autoRule()->jitterMeasure();
  if (const ap::SensorClockFilter* filter = propagator.stampFilter()) {
    error.filter_later = filter->largestLater();
    error.filter_fallbacks = static_cast<double>(filter->fallbacks());
    if (!offsets.empty()) {
      std::sort(offsets.begin(), offsets.end());
      error.filter_offset = offsets[offsets.size() / 2];
    }
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
      "scene,stream,method,auto,rate_hz,rate_samples,average_stamp,stamp_filter,rate_delay_s,"
      "max_gap_fill,seeds,err_rad,err_rad_max,floor_rad,err_settled_rad,auto_used,auto_jitter\n",
      out);
  constexpr int kSeeds = 5;  // median over seeds for the random streams
  std::vector<Integrator> methods = methodsFor(ap::Model::Kinematic);
  methods.push_back(Integrator::Auto);  // last: its choice marks the method rows above
  for (const KinematicScene& scene : scenes) {
    for (const StreamModel& model : streamModels()) {
      const int seeds = isRandom(model) ? kSeeds : 1;
      std::vector<std::vector<RateSample>> streams;
      std::vector<std::vector<double>> taken(seeds);
      for (int s = 1; s <= seeds; ++s)
        streams.push_back(makeStream(scene, model, s, &taken[s - 1]));
      double filter_later = 0.0;                             // over every method and seed
      std::vector<double> filter_offsets, filter_fallbacks;  // auto's, per seed
      std::set<Integrator> chosen;  // what auto integrated with, on any seed
      std::vector<std::pair<std::string, std::string>> rows;  // either side of the auto column
      for (Integrator method : methods) {
        std::vector<double> errors, settled, jitters;
        for (std::size_t i = 0; i < streams.size(); ++i) {
          const StreamError e = streamError(scene, model, method, streams[i], taken[i]);
          if (std::isfinite(e.filter_later)) filter_later = std::max(filter_later, e.filter_later);
          if (method == Integrator::Auto && std::isfinite(e.filter_offset)) {
            filter_offsets.push_back(e.filter_offset);
            filter_fallbacks.push_back(e.filter_fallbacks);
          }
          errors.push_back(e.worst);
          settled.push_back(e.worst_settled);
          jitters.push_back(e.jitter);
          if (method == Integrator::Auto) chosen.insert(e.used.begin(), e.used.end());
        }
        std::sort(errors.begin(), errors.end());
        std::string choice;
        for (Integrator c : chosen) choice += (choice.empty() ? "" : "+") + ap::integratorName(c);
        char row[512];
        std::snprintf(row, sizeof row, "%g,%s,%s,%s,%s,%d,%d,%s,%s,%s,%s,%s,%s\n", model.rate_hz,
                      ap::rateSamplesName(model.setting).c_str(),
                      ap::averageStampName(model.average_stamp).c_str(),
                      ap::stampFilterName(model.filter).c_str(), field(model.rate_delay).c_str(),
                      model.max_gap_fill, seeds, field(errors[errors.size() / 2]).c_str(),
                      field(errors.back()).c_str(), field(noiseFloor(scene, model)).c_str(),
                      field(median(settled)).c_str(), choice.c_str(),
                      field(median(jitters)).c_str());
        rows.emplace_back(scene.name + "," + model.name + "," + ap::integratorName(method), row);
      }
      if (model.filter != ap::StampFilter::None && !filter_offsets.empty()) {
        std::fprintf(stderr,
                     "bench: %s %s: filtered stamps at most %.3g ms later than received; "
                     "settled, %.3g ms after the sample was taken; %g fallbacks to the receipt "
                     "stamps (auto, median over seeds)\n",
                     scene.name.c_str(), model.name.c_str(), 1e3 * filter_later,
                     1e3 * median(filter_offsets), median(filter_fallbacks));
      }
      // A method row is marked when auto integrated a step with it (on any seed).
      for (std::size_t i = 0; i < methods.size(); ++i) {
        const bool marked = methods[i] == Integrator::Auto || chosen.count(methods[i]) > 0;
        std::fprintf(out, "%s,%d,%s", rows[i].first.c_str(), marked ? 1 : 0,
                     rows[i].second.c_str());
      }
    }
    std::fprintf(stderr, "bench: streams on %s done\n", scene.name.c_str());
  }
}

}  // namespace bench
