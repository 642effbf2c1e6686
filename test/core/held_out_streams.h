// The held-out streams of `integrator: auto` (test_auto_held_out.cpp,
// test_auto_held_out_second.cpp, test_auto_held_out_third.cpp): motions with a closed-form
// attitude, the streams a driver delivers from them, and the judgement of `auto` against the best
// fixed kinematic method on the same samples (docs/real_streams.md, "How the `auto` rule was
// validated").
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <set>
#include <string>
#include <vector>

#include "attitude_propagator/models/kinematic_propagator.h"
#include "attitude_propagator/numerics/coning_motion.h"
#include "attitude_propagator/numerics/quaternion.h"
#include "attitude_propagator/numerics/rigid_body.h"
#include "attitude_propagator/numerics/torque_free_motion.h"
#include "gyro_streams.h"
#include "sampling.h"

namespace held_out {

namespace ap = attitude_propagator;
using ap::AverageStamp;
using ap::Integrator;
using ap::RateSamples;
using ap::StampFilter;

// ---- Motions: a closed-form attitude q_WB(t) and the body rate that generates it -------------

struct Motion {
  std::string name;
  std::function<Eigen::Quaterniond(double)> attitude;
  std::function<Eigen::Vector3d(double)> rate;
  double band = 1.0;  // rad/s: the highest frequency in the rate an interval mean must resolve
};

/// A torque-free rigid body from its exact solution (Jacobi elliptic functions for a triaxial
/// body).
inline Motion freeBody(const std::string& name, const Eigen::Vector3d& moments,
                       const Eigen::Vector3d& w0, const Eigen::Quaterniond& q0) {
  ap::DynamicState x0;
  x0.q_WB = q0;
  x0.w_B = w0;
  const ap::TorqueFreeMotion body(ap::RigidBody::fromPrincipalMoments(moments), x0);
  // The rate's components are Jacobi elliptic functions of the body period; resolving 20 rad/s
  // gives means exact to 1e-11 (MotionsRatesGenerateTheirAttitudes).
  return {name, [body](double t) { return body.evaluate(t).q_WB; },
          [body](double t) { return body.evaluate(t).w_B; }, 20.0};
}

/// An angle a t + sum_i A_i sin(2 pi f_i t + p_i) and its derivative.
struct Sines {
  double drift = 0.0;                        // a, rad/s
  std::vector<std::array<double, 3>> terms;  // A_i (rad), f_i (Hz), p_i (rad)
  double angle(double t) const {
    double a = drift * t;
    for (const auto& s : terms) a += s[0] * std::sin(2.0 * M_PI * s[1] * t + s[2]);
    return a;
  }
  double rate(double t) const {
    double r = drift;
    for (const auto& s : terms) {
      r += s[0] * 2.0 * M_PI * s[1] * std::cos(2.0 * M_PI * s[1] * t + s[2]);
    }
    return r;
  }
};

/// Yaw, pitch and roll each a sum of sinusoids: q(t) = q_off (x) Exp(psi z) (x) Exp(theta y) (x)
/// Exp(phi x). Each factor turns about a fixed axis, so d/dt Exp(a e) = 1/2 Exp(a e) (x) (0, a' e)
/// and dq/dt = 1/2 q (x) (0, w_B) with
///   w_B = (q_theta q_phi)^-1 (psi' z) + q_phi^-1 (theta' y) + phi' x.
struct EulerSines {
  Eigen::Quaterniond offset;
  Sines yaw, pitch, roll;
  Eigen::Quaterniond attitude(double t) const {
    return offset * Eigen::AngleAxisd(yaw.angle(t), Eigen::Vector3d::UnitZ()) *
           Eigen::AngleAxisd(pitch.angle(t), Eigen::Vector3d::UnitY()) *
           Eigen::AngleAxisd(roll.angle(t), Eigen::Vector3d::UnitX());
  }
  Eigen::Vector3d bodyRate(double t) const {
    const Eigen::Quaterniond q_pitch(Eigen::AngleAxisd(pitch.angle(t), Eigen::Vector3d::UnitY()));
    const Eigen::Quaterniond q_roll(Eigen::AngleAxisd(roll.angle(t), Eigen::Vector3d::UnitX()));
    return (q_pitch * q_roll).conjugate() * (yaw.rate(t) * Eigen::Vector3d::UnitZ()) +
           q_roll.conjugate() * (pitch.rate(t) * Eigen::Vector3d::UnitY()) +
           roll.rate(t) * Eigen::Vector3d::UnitX();
  }
};

// ---- Streams: what a driver delivers from the motion ------------------------------------------

enum class Filter { None, Butterworth, Sinc };

struct StreamSpec {
  std::string name;
  double rate_hz = 250.0;
  double rate_after_hz = 0.0;                // > 0: the rate changes to this halfway through
  bool averaged = false;                     // the gyro delivers interval means ...
  AverageStamp stamped = AverageStamp::End;  // ... stamped at the interval's end, mid or start
  double jitter = 0.0;                       // s, receipt jitter (standard deviation)
  double latency = 0.0;  // s: received after a latency >= 0, half-normal latency |N(0, 1)|
  double drop = 0.0;     // probability a sample is lost ...
  int burst = 1;         // ... and with it up to burst - 1 after it (uniformly 0 .. burst - 1)
  int drop_every = 0;    // > 0: every sample whose index is a multiple of it is lost
  bool mems = false;     // angle random walk and 16-bit quantisation
  Filter lowpass = Filter::None;
  int fifo_batch = 0;  // > 0: FIFO reads of this many samples
  gyro_streams::Fifo fifo_form = gyro_streams::Fifo::Repeated;
  // How the stream is read.
  RateSamples setting = RateSamples::Instantaneous;
  AverageStamp average_stamp = AverageStamp::End;
  StampFilter stamp_filter = StampFilter::None;
  double rate_delay = 0.0;  // s: every stamp moved back by it, as the engine does
  // A miss the rule is known to have here (docs/real_streams.md, "How the `auto` rule was
  // validated"): printed with its figures, not asserted, until the rule is changed.
  bool known_miss = false;
  bool random() const { return jitter > 0.0 || drop > 0.0 || mems || fifo_batch > 0; }
};

/// Appends a stream named `name` at `hz` to `specs` (point samples, every other field its
/// default) and returns it to be set further.
inline StreamSpec& addStream(std::vector<StreamSpec>& specs, const std::string& name, double hz) {
  specs.emplace_back();
  specs.back().name = name;
  specs.back().rate_hz = hz;
  return specs.back();
}

/// The stream as interval means, taken as such (rate_samples: interval_average).
inline StreamSpec& asMeans(StreamSpec& s) {
  s.averaged = true;
  s.setting = RateSamples::IntervalAverage;
  return s;
}

constexpr double kDuration = 10.0;  // s
// The on-chip filters: a 2nd-order Butterworth at ODR/5 (bilinear) and a sinc^2 decimator by 5.
const gyro_streams::Butterworth2 kButterworth(0.2);
const gyro_streams::SincDecimator kSinc(2, 5);
constexpr double kFifoLatency = 3e-4;  // s, the spread of a FIFO read's latency
// MEMS: angle random walk 0.3 deg/sqrt(h), 16-bit output over +-1000 deg/s.
constexpr double kArw = 0.3 * M_PI / 180.0 / 60.0;        // rad/sqrt(s)
constexpr double kLsb = 2000.0 / 65536.0 * M_PI / 180.0;  // rad/s
constexpr double kFullScale = 1000.0 * M_PI / 180.0;      // rad/s

struct Sample {
  double stamp;
  Eigen::Vector3d w_B;
};

/// The mean of the motion's rate over [a, b] in `pieces` equal parts, each by 5-point
/// Gauss-Legendre (sampling.h).
inline Eigen::Vector3d meanOver(const Motion& motion, double a, double b, int pieces) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (int i = 0; i < pieces; ++i) {
    sum += intervalMean(motion.rate, a + (b - a) * i / pieces, a + (b - a) * (i + 1) / pieces);
  }
  return sum / pieces;
}

/// The parts over which the rate's highest frequency turns by at most 0.5 rad: the relative
/// error of each part's rule is then about 0.5^10 / 10^9, 1e-12 (sampling.h).
inline int piecesFor(const Motion& motion, double a, double b) {
  return std::max(1, static_cast<int>(std::ceil(motion.band * (b - a) / 0.5)));
}

inline Eigen::Vector3d meanOver(const Motion& motion, double a, double b) {
  return meanOver(motion, a, b, piecesFor(motion, a, b));
}

/// The truth check every held-out set starts with: the motion's interval means agree with the
/// same mean on eight times the pieces, and its rate generates its attitude, q' = q ⊗ (0, ω)/2,
/// by a central difference. `period` is the interval of the means checked.
inline void expectRatesGenerateAttitudes(const Motion& m, double period) {
  for (double t : {0.05, 1.3, 2.8, 6.1, 9.2}) {
    const double a = t - period;
    const Eigen::Vector3d mean = meanOver(m, a, t);
    EXPECT_LE((mean - meanOver(m, a, t, 8 * piecesFor(m, a, t))).norm(), 1e-11 * mean.norm())
        << m.name << " t = " << t;
  }
  for (double t : {0.0, 0.37, 2.9, 7.71, kDuration}) {
    const double d = 1e-6;
    const Eigen::Vector4d derivative =
        (m.attitude(t + d).coeffs() - m.attitude(t - d).coeffs()) / (2.0 * d);
    const Eigen::Vector4d expected = 0.5 * (m.attitude(t) * ap::pureQuaternion(m.rate(t))).coeffs();
    EXPECT_LE((derivative - expected).norm(), 1e-7 * (1.0 + m.rate(t).norm()))
        << m.name << " t = " << t;
  }
}

/// Sample k is taken at k / rate_hz (after a rate change: at the change's stamp plus k /
/// rate_after_hz); the anchor keeps its exact stamp and rate, so every method starts from the
/// truth.
inline std::vector<Sample> makeStream(const Motion& motion, const StreamSpec& spec,
                                      std::uint64_t seed) {
  std::uint64_t state = seed;
  const double h = 1.0 / spec.rate_hz;
  const long n = std::lround(kDuration * spec.rate_hz);
  std::vector<double> times;
  for (long k = 0; k <= (spec.rate_after_hz > 0.0 ? n / 2 : n); ++k) times.push_back(k * h);
  if (spec.rate_after_hz > 0.0) {
    const double t0 = times.back();
    const long after = std::lround((kDuration - t0) * spec.rate_after_hz);
    for (long k = 1; k <= after; ++k) times.push_back(t0 + k / spec.rate_after_hz);
  }
  std::vector<double> fifo;
  if (spec.fifo_batch > 0) {
    fifo = gyro_streams::fifoStamps(spec.rate_hz, spec.fifo_batch, spec.fifo_form, kFifoLatency,
                                    seed, static_cast<long>(times.size()) - 1);
    times.resize(fifo.size());
  }
  std::vector<Eigen::Vector3d> butterworth;
  if (spec.lowpass == Filter::Butterworth) {
    const long preroll = std::lround(2.0 * spec.rate_hz);  // no start-up transient
    std::vector<Eigen::Vector3d> input;
    for (long k = -preroll; k < static_cast<long>(times.size()); ++k) {
      input.push_back(motion.rate(k * h));
    }
    butterworth = kButterworth.filter(input);
    butterworth.erase(butterworth.begin(), butterworth.begin() + preroll);
  }
  std::vector<Sample> samples;
  int burst_left = 0;  // samples still to lose in a burst
  for (std::size_t k = 0; k < times.size(); ++k) {
    const double t = times[k];
    const double period = k > 0 ? t - times[k - 1] : h;
    Eigen::Vector3d w = spec.averaged ? meanOver(motion, t - period, t) : motion.rate(t);
    if (spec.lowpass == Filter::Butterworth) w = butterworth[k];
    if (spec.lowpass == Filter::Sinc) w = kSinc.output(motion.rate, t, kSinc.ratio * spec.rate_hz);
    const double offset = spec.stamped == AverageStamp::Mid     ? 0.5 * period
                          : spec.stamped == AverageStamp::Start ? period
                                                                : 0.0;
    double stamp = (spec.fifo_batch > 0 ? fifo[k] : t) - offset;
    if (k > 0) {
      if (spec.mems) {
        for (int i = 0; i < 3; ++i) {
          const double noisy = w[i] + kArw / std::sqrt(h) * normalRandom(state);
          w[i] = std::clamp(kLsb * std::round(noisy / kLsb), -kFullScale, kFullScale);
        }
      }
      if (spec.jitter > 0.0) stamp += spec.jitter * normalRandom(state);
      if (spec.latency > 0.0) stamp += spec.latency * std::abs(normalRandom(state));
      if (k > 3 && burst_left > 0) {
        --burst_left;
        continue;
      }
      if (k > 3 && spec.drop_every > 0 && k % static_cast<std::size_t>(spec.drop_every) == 0)
        continue;
      if (k > 3 && spec.drop > 0.0 && uniformRandom(state) < spec.drop) {
        if (spec.burst > 1) burst_left = static_cast<int>(uniformRandom(state) * spec.burst);
        continue;
      }
    }
    samples.push_back({stamp - spec.rate_delay, w});
  }
  return samples;
}

// ---- Runs -------------------------------------------------------------------------------------

// Steps after the anchor whose states carry the unavoidable start-up error (the benchmark skips
// as many samples). Counted in steps, so that means stamped at their start or midpoint, whose
// states come one sample later, skip the same states as end-stamped ones.
constexpr std::uint64_t kStartUpSteps = 3;

struct Run {
  double worst = 0.0;
  std::set<Integrator> used;
};

/// The stamp the propagator anchors at: the first sample's, or for a start- or mid-stamped mean
/// read as such the end of its interval (the next stamp, or halfway to it).
inline double anchorStamp(const StreamSpec& spec, const std::vector<Sample>& samples) {
  if (spec.average_stamp == AverageStamp::Start) return samples[1].stamp;
  if (spec.average_stamp == AverageStamp::Mid) return 0.5 * (samples[0].stamp + samples[1].stamp);
  return samples.front().stamp;
}

/// The closed form at the stamp each sample's state is reported at. Stamp handling does not
/// depend on the method, so the stamp after sample k is the same for every method: it is
/// evaluated once per stream and looked up by k while the stamp matches (afresh otherwise).
class Truth {
 public:
  explicit Truth(const Motion& motion, std::size_t samples)
      : motion_(motion), t_(samples, NAN), q_(samples) {}
  const Eigen::Quaterniond& at(std::size_t k, double t) {
    if (!(t_[k] == t)) {
      t_[k] = t;
      q_[k] = motion_.attitude(t);
    }
    return q_[k];
  }

 private:
  const Motion& motion_;
  std::vector<double> t_;
  std::vector<Eigen::Quaterniond> q_;
};

inline Run run(const Motion& motion, const StreamSpec& spec, Integrator method,
               const std::vector<Sample>& samples, Truth& truth) {
  ap::KinematicConfig config;
  config.integrator = method;
  config.rate_samples = spec.setting;
  config.average_stamp = spec.average_stamp;
  config.stamp_filter = spec.stamp_filter;
  config.initial_q_WB = motion.attitude(anchorStamp(spec, samples));
  ap::KinematicPropagator propagator(config);
  Run r;
  for (std::size_t k = 0; k < samples.size(); ++k) {
    if (propagator.addSample(samples[k].stamp, samples[k].w_B) == ap::StampOutcome::Advanced) {
      r.used.insert(propagator.integrator());
    }
    if (!propagator.anchored() || propagator.steps() < kStartUpSteps) continue;
    r.worst = std::max(r.worst,
                       ap::rotationAngle(propagator.orientation(), truth.at(k, propagator.time())));
  }
  return r;
}

inline double median(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  return values[values.size() / 2];
}

constexpr int kSeeds = 5;       // a random stream's error: the median over these
constexpr double kBound = 1.5;  // auto's error over the best method's

/// Every stream of `specs` on the motion, a random one with seeds seed0 .. seed0 + kSeeds - 1:
/// auto against the best fixed kinematic method, one line per stream, headed by `tag`.
inline void judgeMotion(const Motion& motion, const std::vector<StreamSpec>& specs,
                        std::uint64_t seed0, const char* tag) {
  std::vector<Integrator> methods = ap::integratorsFor(ap::Model::Kinematic);
  methods.push_back(Integrator::Auto);
  for (const StreamSpec& spec : specs) {
    const int seeds = spec.random() ? kSeeds : 1;
    std::vector<std::vector<Sample>> streams;
    std::vector<Truth> truths;
    for (int s = 0; s < seeds; ++s) {
      streams.push_back(makeStream(motion, spec, seed0 + s));
      truths.emplace_back(motion, streams.back().size());
    }
    double best = INFINITY, automatic = NAN, cf4 = NAN;
    Integrator best_method = Integrator::Auto;
    std::set<Integrator> chosen;  // what auto integrated with, on any seed
    for (Integrator method : methods) {
      std::vector<double> errors;
      for (std::size_t s = 0; s < streams.size(); ++s) {
        const Run r = run(motion, spec, method, streams[s], truths[s]);
        errors.push_back(r.worst);
        if (method == Integrator::Auto) chosen.insert(r.used.begin(), r.used.end());
      }
      const double error = median(errors);
      if (method == Integrator::Cf4) cf4 = error;  // auto's method unless its rule switches
      if (method == Integrator::Auto) {
        automatic = error;
      } else if (error < best) {
        best = error;
        best_method = method;
      }
    }
    std::string used;
    for (Integrator m : chosen) used += (used.empty() ? "" : "+") + ap::integratorName(m);
    const double ratio = automatic / best;
    std::printf("%s %-6s %-27s %4.0f Hz  auto %-9.3g %-9s best %-5s %-9.3g cf4 %-9.3g x%.2f%s\n",
                tag, motion.name.c_str(), spec.name.c_str(), spec.rate_hz, automatic, used.c_str(),
                ap::integratorName(best_method).c_str(), best, cf4, ratio,
                ratio <= kBound   ? ""
                : spec.known_miss ? "  MISS (known)"
                                  : "  MISS");
    if (spec.known_miss) continue;
    EXPECT_LE(automatic, kBound * best)
        << motion.name << " " << spec.name << " at " << spec.rate_hz << " Hz: auto " << automatic
        << " rad, best " << ap::integratorName(best_method) << " " << best;
  }
}

}  // namespace held_out
