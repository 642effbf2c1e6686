// bench_ahrs: the engine with gravity (and the field) as measurements side by side with a
// Madgwick gradient-descent filter (bench/madgwick.h, imu_filter_madgwick's algorithm) on the
// same simulated IMU streams (test/core/simulated_imu.h), 100 Hz, a MEMS gyro:
//   vehicle        300 s drive: turns, braking and accelerating, centripetal up to 2.6 m/s^2,
//                  roll and pitch from the suspension and the road within 10 deg
//   handheld       130 s tumble, tilt up to 52 deg, linear acceleration up to ~2 m/s^2
//   vehicle_mag    the vehicle with the magnetometer and, from 150 s, a 10 s disturbance that
//                  turns the horizontal field by 30 deg (an added field vector)
//   handheld_control, vehicle_mag_control  the same rotations (and field) without linear
//                  acceleration: controls, in no target
//   held out (added before the linear acceleration's treatment was designed, run only once it
//   was; they choose nothing):
//   vehicle2       240 s drive on another path: faster (16 +- 9 m/s), yaw rate with other
//                  periods (23 s, 31 s) and a bias to the right, another bias vector and seed
//   vehicle2_mag   vehicle2 with the magnetometer and the 30 deg disturbance from 150 s
//   boat           240 s at sea: roll and pitch swells of 5-12 s periods (tilt within ~14 deg),
//                  heave, surge and sway of up to ~1.5 m/s^2, a slow heading
// The engine runs with parameters that say what the simulated sensor is (rate_stddev,
// accel_stddev, mag_stddev) and a MEMS bias prior, and once more with an accel_stddev chosen on
// the handheld stream alone (the vehicle streams held out); Madgwick runs at beta in
// {0.01, 0.03, 0.1, 0.3} and the gain with the lowest attitude RMS is kept per stream.
// Prints a markdown table; writes the tilt (and heading) error of the engine and of the kept
// gain every 0.2 s to the CSV given (for bench/plot.py, docs/ahrs.png), with the engine's
// normalised estimation errors squared (NEES) there: the tilt's (2 degrees of freedom, the
// error's horizontal part against the 2 x 2 block of the published covariance) and the bias'
// per axis (1 each). Their means after kSettle are printed; a consistent filter has them near
// 2 and 1. Beside them, not a filter: the vertical the force's average since the first sample
// gives with a perfect gyro (runAverager), what a filter that knows of the linear acceleration
// only that it averages to zero has to go on: where it is off by more than half the kept
// gain's maximum, the max target is out of such a filter's reach.
// Usage: bench_ahrs [out.csv] [--design-only]  (--design-only: without the held-out streams)
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

#include "../test/core/simulated_imu.h"
#include "attitude_propagator/engine.h"
#include "attitude_propagator/numerics/quaternion.h"
#include "madgwick.h"

namespace {

namespace ap = attitude_propagator;
namespace sim = simulated_imu;
using sim::kDeg;

constexpr double kTwoPi = 2.0 * M_PI;
constexpr double kSettle = 10.0;  // s: the metrics start here
// s: where the start-up is over on every stream (the vehicles accelerate from their first sample
// for about 20 s, so both filters start about 10 deg off); the ratios from here on are printed
// beside the targets' to show how much of a miss the start-up owes, and are in no target.
constexpr double kAfterStartUp = 30.0;
// The 95 % point of the chi-square distribution with 2 degrees of freedom, -2 ln 0.05: an honest
// tilt covariance has its NEES below it 95 % of the time.
constexpr double kChi2Two95 = 5.991464547107979;
constexpr ap::Stamp kEpoch = 1780000000LL * 1000000000LL;
constexpr double kDisturbanceStart = 150.0;
constexpr double kDisturbanceRamp = 0.5;   // s, raised cosine on and off
constexpr double kDisturbanceHold = 10.0;  // s at the full 30 deg
constexpr double kDisturbanceEnd = kDisturbanceStart + 2 * kDisturbanceRamp + kDisturbanceHold;
// accel_stddev: the sensor's white noise says 0.05 m/s^2, but the EKF also takes the linear
// acceleration for noise on the gravity direction; a larger value says how much of it to expect.
// The one with the lowest tilt RMS on the handheld stream is kept; the vehicle streams are held
// out (they never choose anything).
constexpr double kSensorAccelStddev = 0.05;
const std::vector<double> kAccelStddevs = {0.05, 0.1, 0.2, 0.5, 1.0, 2.0, 5.0};

ap::Stamp at(double t) { return kEpoch + static_cast<ap::Stamp>(std::llround(t * 1e9)); }

Eigen::Quaterniond rpy(double roll, double pitch, double yaw) {
  return Eigen::Quaterniond(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
                            Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
                            Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()));
}

// ---- the vehicle: speed v(t) and yaw rate r(t) smooth, the heading their closed-form integral -

// v = 11 + 5 sin(2 pi t / 60) + 1.5 sin(2 pi t / 9)  (m/s), its derivative the along-track
// acceleration; r = 0.015 + 0.09 sin(2 pi t / 40) + 0.06 sin(2 pi t / 13 + 1)  (rad/s), so
// psi = 0.015 t - 0.09 (40 / 2 pi) cos(2 pi t / 40) - 0.06 (13 / 2 pi) cos(2 pi t / 13 + 1).
double speed(double t) {
  return 11.0 + 5.0 * std::sin(kTwoPi * t / 60) + 1.5 * std::sin(kTwoPi * t / 9);
}
double alongAcceleration(double t) {
  return 5.0 * kTwoPi / 60 * std::cos(kTwoPi * t / 60) +
         1.5 * kTwoPi / 9 * std::cos(kTwoPi * t / 9);
}
double yawRate(double t) {
  return 0.015 + 0.09 * std::sin(kTwoPi * t / 40) + 0.06 * std::sin(kTwoPi * t / 13 + 1.0);
}
double heading(double t) {
  return 0.3 + 0.015 * t - 0.09 * 40 / kTwoPi * std::cos(kTwoPi * t / 40) -
         0.06 * 13 / kTwoPi * std::cos(kTwoPi * t / 13 + 1.0);
}

sim::Motion vehicle() {
  sim::Motion m;
  // Roll: 0.025 rad per m/s^2 of lateral (centripetal, v r, to the left) acceleration, outward
  // (right side down, positive about the forward axis), plus the road's bank; pitch: the nose
  // dips 0.02 rad per m/s^2 of braking, plus the road's grade.
  m.attitude = [](double t) {
    const double lateral = speed(t) * yawRate(t);
    const double roll = 0.025 * lateral + 0.07 * std::sin(kTwoPi * t / 70 + 0.3);
    const double pitch = -0.02 * alongAcceleration(t) + 0.1 * std::sin(kTwoPi * t / 90 + 0.5);
    return rpy(roll, pitch, heading(t));
  };
  // a_W = v_dot (cos psi, sin psi, 0) + v r (-sin psi, cos psi, 0).
  m.acceleration_W = [](double t) {
    const double psi = heading(t);
    const double along = alongAcceleration(t);
    const double across = speed(t) * yawRate(t);
    return Eigen::Vector3d(along * std::cos(psi) - across * std::sin(psi),
                           along * std::sin(psi) + across * std::cos(psi), 0.0);
  };
  return m;
}

// ---- the second vehicle (held out): another path, another speed profile --------------------

// v = 16 + 7 sin(2 pi t / 85) + 2 sin(2 pi t / 14 + 0.7); r = -0.01 + 0.07 sin(2 pi t / 31 +
// 0.4) + 0.05 sin(2 pi t / 23 + 2), psi its closed-form integral.
double speed2(double t) {
  return 16.0 + 7.0 * std::sin(kTwoPi * t / 85) + 2.0 * std::sin(kTwoPi * t / 14 + 0.7);
}
double alongAcceleration2(double t) {
  return 7.0 * kTwoPi / 85 * std::cos(kTwoPi * t / 85) +
         2.0 * kTwoPi / 14 * std::cos(kTwoPi * t / 14 + 0.7);
}
double yawRate2(double t) {
  return -0.01 + 0.07 * std::sin(kTwoPi * t / 31 + 0.4) + 0.05 * std::sin(kTwoPi * t / 23 + 2.0);
}
double heading2(double t) {
  return -1.1 - 0.01 * t - 0.07 * 31 / kTwoPi * std::cos(kTwoPi * t / 31 + 0.4) -
         0.05 * 23 / kTwoPi * std::cos(kTwoPi * t / 23 + 2.0);
}

sim::Motion vehicle2() {
  sim::Motion m;
  // A softer suspension (0.035 rad per m/s^2 lateral), a stiffer pitch (0.015 rad per m/s^2),
  // another road.
  m.attitude = [](double t) {
    const double lateral = speed2(t) * yawRate2(t);
    const double roll = 0.035 * lateral + 0.05 * std::sin(kTwoPi * t / 55 + 1.2);
    const double pitch = -0.015 * alongAcceleration2(t) + 0.08 * std::sin(kTwoPi * t / 120 + 2.0);
    return rpy(roll, pitch, heading2(t));
  };
  m.acceleration_W = [](double t) {
    const double psi = heading2(t);
    const double along = alongAcceleration2(t);
    const double across = speed2(t) * yawRate2(t);
    return Eigen::Vector3d(along * std::cos(psi) - across * std::sin(psi),
                           along * std::sin(psi) + across * std::cos(psi), 0.0);
  };
  return m;
}

// ---- the boat (held out): swells, heave, surge and sway ---------------------------------------

sim::Motion boat() {
  sim::Motion m;
  m.attitude = [](double t) {
    const double roll =
        8.0 * kDeg * std::sin(kTwoPi * t / 7.0) + 3.0 * kDeg * std::sin(kTwoPi * t / 11.5 + 1.0);
    const double pitch =
        4.0 * kDeg * std::sin(kTwoPi * t / 5.3 + 0.5) + 2.0 * kDeg * std::sin(kTwoPi * t / 9 + 2.0);
    const double yaw = 0.4 + 0.004 * t + 0.08 * std::sin(kTwoPi * t / 60 + 0.2);
    return rpy(roll, pitch, yaw);
  };
  m.acceleration_W = [](double t) {
    return Eigen::Vector3d(0.5 * std::sin(kTwoPi * t / 7.0 + 0.3) + 0.3 * std::sin(kTwoPi * t / 12),
                           0.8 * std::sin(kTwoPi * t / 8.5) + 0.4 * std::sin(kTwoPi * t / 5.3 + 1),
                           1.0 * std::sin(kTwoPi * t / 6.2 + 1.0));
  };
  return m;
}

// ---- the handheld tumble --------------------------------------------------------------------

sim::Motion handheld() {
  sim::Motion m;
  m.attitude = [](double t) {
    const double roll = 0.55 * std::sin(0.9 * t) + 0.25 * std::sin(2.3 * t + 0.4);
    const double pitch = 0.4 * std::sin(0.6 * t + 1.0) + 0.2 * std::sin(1.7 * t);
    const double yaw = 0.8 * std::sin(0.3 * t) + 0.5 * std::sin(0.13 * t + 2.0) + 0.2 * t;
    return rpy(roll, pitch, yaw);
  };
  m.acceleration_W = [](double t) {
    return Eigen::Vector3d(1.5 * std::sin(1.3 * t), 1.2 * std::sin(1.1 * t + 0.5),
                           1.0 * std::sin(1.7 * t + 1.0));
  };
  return m;
}

// ---- the sensor -----------------------------------------------------------------------------

sim::Sensor mems(bool disturbed,
                 const Eigen::Vector3d& bias = 0.3 * kDeg * Eigen::Vector3d(1.0, -0.9, 0.7),
                 unsigned seed = 7) {
  sim::Sensor s;
  s.rate = 100.0;
  s.gyro_noise = 0.005;
  s.gyro_bias = bias;  // by default a generic direction
  s.accel_noise = 0.05;
  s.mag_noise = 0.3e-6;
  s.field_W = sim::earthField(50e-6, 60.0 * kDeg, 0.0);
  if (disturbed) {
    // An added field h' - h that turns the horizontal field h by s(t) 30 deg about the vertical;
    // s rises and falls as a raised cosine over kDisturbanceRamp.
    const Eigen::Vector3d h(s.field_W.x(), s.field_W.y(), 0.0);
    s.disturbance_W = [h](double t) -> Eigen::Vector3d {
      const double a = t - kDisturbanceStart;
      const double r = kDisturbanceRamp;
      double level = 0.0;
      if (a >= 0 && a < r) level = 0.5 - 0.5 * std::cos(M_PI * a / r);
      if (a >= r && a < r + kDisturbanceHold) level = 1.0;
      if (a >= r + kDisturbanceHold && a < 2 * r + kDisturbanceHold) {
        level = 0.5 + 0.5 * std::cos(M_PI * (a - r - kDisturbanceHold) / r);
      }
      return Eigen::AngleAxisd(level * 30.0 * kDeg, Eigen::Vector3d::UnitZ()) * h - h;
    };
  }
  s.seed = seed;
  return s;
}

// ---- the filters on a stream ----------------------------------------------------------------

struct Stream {
  std::string name;
  std::vector<sim::Sample> samples;
  bool mag = false;
  Eigen::Vector3d bias = Eigen::Vector3d::Zero();
  bool held_out = false;
  sim::Motion motion;
  /// The bias' axes the stream makes observable: gravity alone, level within 10-15 deg, sees
  /// the two horizontal ones (the body's x and y); a tumble, or the field, sees all three.
  Eigen::Vector3d observable = Eigen::Vector3d::Ones();
};

struct Errors {
  std::vector<double> t, tilt, heading;  // every sample (rad)
  // The engine's NEES every sample (empty for Madgwick): the tilt's, the bias' per body axis.
  std::vector<double> tilt_nees;
  std::vector<Eigen::Vector3d> bias_nees;
};

// The tilt's NEES: the error dtheta_B = Log(q^-1 q_true) (the engine's body-frame error, truth =
// q (x) Exp(dtheta_B)) on the plane normal to the estimate's up u = C_BW e_z, B = [e1 e2], against
// that plane's block of the published covariance: e = B^T dtheta, e^T (B^T P_B B)^-1 e, chi-square
// with 2 degrees of freedom when the covariance is honest. The rotation about u (the heading) is
// left out: gravity does not see it.
double tiltNees(const Eigen::Quaterniond& q, const Eigen::Quaterniond& truth,
                const Eigen::Matrix3d& P_B) {
  const Eigen::Vector3d dtheta = ap::logMap(q.conjugate() * truth);
  const Eigen::Vector3d u = q.conjugate() * Eigen::Vector3d::UnitZ();
  Eigen::Index least = 0;
  u.cwiseAbs().minCoeff(&least);
  Eigen::Matrix<double, 3, 2> B;
  B.col(0) = u.cross(Eigen::Vector3d::Unit(least)).normalized();
  B.col(1) = u.cross(B.col(0));
  const Eigen::Vector2d e = B.transpose() * dtheta;
  const Eigen::Matrix2d S = B.transpose() * P_B * B;
  return e.dot(S.ldlt().solve(e));
}

/// The share of the samples after kSettle whose value is at most `bound`.
double shareAtMostAfterSettle(const std::vector<double>& t, const std::vector<double>& v,
                              double bound) {
  std::size_t n = 0, within = 0;
  for (std::size_t i = 0; i < v.size(); ++i) {
    if (t[i] < kSettle) continue;
    ++n;
    if (v[i] <= bound) ++within;
  }
  return n ? static_cast<double>(within) / n : NAN;
}

double meanAfterSettle(const std::vector<double>& t, const std::vector<double>& v) {
  double s = 0;
  std::size_t n = 0;
  for (std::size_t i = 0; i < v.size(); ++i) {
    if (t[i] < kSettle) continue;
    s += v[i];
    ++n;
  }
  return n ? s / n : NAN;
}

struct Metrics {
  double tilt_rms = 0, tilt_max = 0, heading_rms = NAN, heading_disturbed = NAN, heading_max = NAN;
};

double rms(const std::vector<double>& v) {
  double s = 0;
  for (double x : v) s += x * x;
  return v.empty() ? NAN : std::sqrt(s / v.size());
}

Metrics metrics(const Errors& e, bool mag, double from = kSettle) {
  std::vector<double> tilt, head, disturbed;
  Metrics m;
  for (std::size_t i = 0; i < e.t.size(); ++i) {
    if (e.t[i] < from) continue;
    tilt.push_back(e.tilt[i]);
    m.tilt_max = std::max(m.tilt_max, e.tilt[i]);
    head.push_back(e.heading[i]);
    if (e.t[i] >= kDisturbanceStart && e.t[i] < kDisturbanceEnd) disturbed.push_back(e.heading[i]);
  }
  m.tilt_rms = rms(tilt);
  if (mag) {
    m.heading_rms = rms(head);
    m.heading_disturbed = rms(disturbed);
    m.heading_max = 0;
    for (double h : head) m.heading_max = std::max(m.heading_max, std::abs(h));
  }
  return m;
}

void record(Errors& e, double t, const Eigen::Quaterniond& q, const Eigen::Quaterniond& truth) {
  e.t.push_back(t);
  e.tilt.push_back(sim::tiltError(q, truth));
  e.heading.push_back(sim::headingError(q, truth));
}

struct EngineRun {
  Errors errors;
  double tilt_nees = NAN;         // mean after kSettle
  double tilt_nees_within = NAN;  // the share after kSettle at most kChi2Two95 (0.95 if honest)
  Eigen::Vector3d bias_nees = Eigen::Vector3d::Constant(NAN);  // mean after kSettle, per axis
  Eigen::Vector3d bias_error = Eigen::Vector3d::Zero();        // rad/s
  Eigen::Vector3d bias_stddev = Eigen::Vector3d::Zero();       // rad/s
  ap::AidingCounters accel, mag;
};

struct NullSink : ap::EngineSink {
  void publishState(const ap::EngineState&) override {}
  void inputApplied(const ap::Input&, const ap::EngineState&) override {}
  void note(const ap::EngineNote&) override {}
};

// The engine's parameters say what the simulated sensor is; the bias prior is a MEMS gyro's
// (0.01 rad/s = 0.57 deg/s per axis), its random walk the core tests' (1e-5 rad/s/sqrt(s));
// exp2 as test_aiding.cpp. accel_stddev: the sensor's 0.05 m/s^2, or the one chosen on the
// handheld stream (kAccelStddevs, main()).
ap::EngineConfig engineConfig(bool mag, double accel_stddev) {
  ap::EngineConfig c;
  c.model = ap::Model::Kinematic;
  c.kinematic.integrator = ap::Integrator::Exp2;
  c.rate_stddev = 0.005;
  c.aiding.use_accel = true;
  c.aiding.accel_stddev = accel_stddev;
  c.aiding.align = true;
  c.aiding.use_mag = mag;
  c.aiding.mag_stddev = 0.3e-6;
  c.fixes.estimate_gyro_bias = true;
  c.fixes.gyro_bias_stddev = 0.01;
  c.fixes.gyro_bias_random_walk = 1e-5;
  return c;
}

EngineRun runEngine(const Stream& s, double accel_stddev) {
  NullSink sink;
  ap::AttitudeEngine engine(engineConfig(s.mag, accel_stddev), sink);
  EngineRun run;
  ap::Input input;
  input.source = ap::Source::Imu;
  for (const sim::Sample& x : s.samples) {
    input.stamp = at(x.t);
    input.value = x.w_B;
    engine.submit(input);
    engine.submitAcceleration(input.stamp, x.f_B, Eigen::Matrix3d::Zero());
    if (s.mag) engine.submitMagneticField(input.stamp, x.m_B, Eigen::Matrix3d::Zero());
    const ap::EngineState state = engine.state();
    record(run.errors, x.t, state.q_WB, x.truth);
    run.errors.tilt_nees.push_back(tiltNees(state.q_WB, x.truth, state.P_B));
    const Eigen::Vector3d db = state.gyro_bias_estimate_B - s.bias;
    run.errors.bias_nees.push_back(
        db.cwiseProduct(db).cwiseQuotient(state.gyro_bias_stddev_B.cwiseAbs2()));
  }
  run.tilt_nees = meanAfterSettle(run.errors.t, run.errors.tilt_nees);
  run.tilt_nees_within = shareAtMostAfterSettle(run.errors.t, run.errors.tilt_nees, kChi2Two95);
  for (int a = 0; a < 3; ++a) {
    std::vector<double> axis;
    for (const Eigen::Vector3d& n : run.errors.bias_nees) axis.push_back(n(a));
    run.bias_nees(a) = meanAfterSettle(run.errors.t, axis);
  }
  run.bias_error = engine.gyroBiasEstimate() - s.bias;
  run.bias_stddev = engine.gyroBiasStddev();
  run.accel = engine.counters().accel;
  run.mag = engine.counters().mag;
  return run;
}

Errors runMadgwick(const Stream& s, double beta) {
  bench::Madgwick filter(beta);
  Errors e;
  const sim::Sample& first = s.samples.front();
  filter.initialise(first.f_B, s.mag ? &first.m_B : nullptr);
  record(e, first.t, filter.q_WB(), first.truth);
  for (std::size_t k = 1; k < s.samples.size(); ++k) {
    const sim::Sample& x = s.samples[k];
    filter.update(x.w_B, x.f_B, s.mag ? &x.m_B : nullptr, x.t - s.samples[k - 1].t);
    record(e, x.t, filter.q_WB(), x.truth);
  }
  return e;
}

// Not a filter: the best vertical a filter that takes the linear acceleration for zero-mean
// noise can know, given a perfect gyro. Gravity is fixed in the world, so the force turned into
// it by the true attitude and averaged since the first sample is g e_up + mean(a_W) (+ noise);
// its angle from e_up is the tilt error left by an acceleration that has not averaged out yet.
// A filter with a real gyro (its bias unknown) knows less; one with a model of the body's
// motion, or another input (a velocity), could know more.
Errors runAverager(const Stream& s) {
  Errors e;
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (const sim::Sample& x : s.samples) {
    sum += x.truth * x.f_B;
    const Eigen::Vector3d up = sum.normalized();
    e.t.push_back(x.t);
    e.tilt.push_back(std::atan2(up.head<2>().norm(), up.z()));
    e.heading.push_back(0.0);
  }
  return e;
}

// J^T f is the gradient of |f|^2 / 2: checked against central differences before any run.
void checkGradient() {
  const Eigen::Vector4d q = Eigen::Vector4d(0.8, -0.3, 0.4, 0.33).normalized();
  const Eigen::Vector3d d(0.2, 0.5, -0.84), s = Eigen::Vector3d(0.1, -0.7, 0.6).normalized();
  // |R(p)^T d - s|^2 / 2 for a unit p: eq. 20's f wherever |q| = 1.
  auto cost = [&](const Eigen::Vector4d& p) {
    const Eigen::Matrix3d R = Eigen::Quaterniond(p(0), p(1), p(2), p(3)).toRotationMatrix();
    return 0.5 * (R.transpose() * d - s).squaredNorm();
  };
  const Eigen::Vector4d g = bench::Madgwick::gradient(q, d, s);
  for (int i = 0; i < 4; ++i) {
    // Along the sphere's tangent only: eq. 20 holds on |q| = 1, so its radial slope is not R's.
    Eigen::Vector4d e = Eigen::Vector4d::Unit(i);
    e -= q.dot(e) * q;
    const double h = 1e-6;
    const double numeric =
        (cost((q + h * e).normalized()) - cost((q - h * e).normalized())) / (2 * h);
    Eigen::Vector4d tangent = g - q.dot(g) * q;
    if (std::abs(numeric - tangent.dot(e)) > 1e-6) {
      throw std::runtime_error("Madgwick gradient does not match its objective");
    }
  }
}

std::string fmt(double v, const char* f = "%.3f") {
  if (std::isnan(v)) return "";
  char buf[32];
  std::snprintf(buf, sizeof buf, f, v);
  return buf;
}

std::string counters(const ap::AidingCounters& c) {
  char buf[160];
  std::snprintf(buf, sizeof buf, "accepted %llu, gate %llu, magnitude %llu, recovered %llu",
                static_cast<unsigned long long>(c.accepted),
                static_cast<unsigned long long>(c.rejected_gate),
                static_cast<unsigned long long>(c.rejected_magnitude),
                static_cast<unsigned long long>(c.recovered));
  return buf;
}

std::string verdict(double ratio) {
  return fmt(ratio, "%.2f") + (ratio <= 0.5 ? " met" : " **not met**");
}

}  // namespace

int main(int argc, char** argv) {
  try {
    checkGradient();
    const std::string csv_path = argc > 1 && argv[1][0] != '-' ? argv[1] : "ahrs.csv";
    std::FILE* csv = std::fopen(csv_path.c_str(), "w");
    if (csv == nullptr) throw std::runtime_error("cannot write " + csv_path);
    std::fprintf(csv,
                 "stream,filter,t,tilt_deg,heading_deg,tilt_nees,bias_nees_x,bias_nees_y,"
                 "bias_nees_z\n");

    // --design-only: the held-out streams are not run (while a rule is designed on the others).
    bool design_only = false;
    for (int a = 1; a < argc; ++a) design_only |= std::string(argv[a]) == "--design-only";
    const Eigen::Vector3d horizontal(1, 1, 0), all(1, 1, 1);
    std::vector<Stream> streams;
    streams.push_back({"handheld", sim::simulate(handheld(), mems(false), 130.0), false,
                       mems(false).gyro_bias, false, handheld(), all});
    streams.push_back({"vehicle", sim::simulate(vehicle(), mems(false), 300.0), false,
                       mems(false).gyro_bias, false, vehicle(), horizontal});
    streams.push_back({"vehicle_mag", sim::simulate(vehicle(), mems(true), 300.0), true,
                       mems(true).gyro_bias, false, vehicle(), all});
    // Controls, in no target: the rotations with no linear acceleration, so the force is gravity
    // and noise alone, as the EKF's model says.
    sim::Motion still = handheld();
    still.acceleration_W = [](double) { return Eigen::Vector3d::Zero().eval(); };
    streams.push_back({"handheld_control", sim::simulate(still, mems(false), 130.0), false,
                       mems(false).gyro_bias, false, still, all});
    sim::Motion level = vehicle();
    level.acceleration_W = [](double) { return Eigen::Vector3d::Zero().eval(); };
    streams.push_back({"vehicle_mag_control", sim::simulate(level, mems(true), 300.0), true,
                       mems(true).gyro_bias, false, level, all});
    if (!design_only) {
      // Held out: other paths, another bias vector and seed each.
      const Eigen::Vector3d bias2 = 0.25 * kDeg * Eigen::Vector3d(-0.8, 1.0, 0.5);
      const Eigen::Vector3d bias3 = 0.2 * kDeg * Eigen::Vector3d(0.6, 0.8, -1.0);
      streams.push_back({"vehicle2", sim::simulate(vehicle2(), mems(false, bias2, 19), 240.0),
                         false, bias2, true, vehicle2(), horizontal});
      streams.push_back({"vehicle2_mag", sim::simulate(vehicle2(), mems(true, bias2, 29), 240.0),
                         true, bias2, true, vehicle2(), all});
      streams.push_back({"boat", sim::simulate(boat(), mems(false, bias3, 41), 240.0), false, bias3,
                         true, boat(), horizontal});
    }
    const std::vector<double> gains = {0.01, 0.03, 0.1, 0.3};

    // accel_stddev chosen on the handheld stream alone.
    std::printf("accel_stddev chosen on the handheld stream (tilt after %.0f s):\n\n", kSettle);
    std::printf("| accel_stddev (m/s^2) | tilt RMS (deg) | tilt max (deg) |\n|---|---|---|\n");
    double chosen = kSensorAccelStddev, chosen_rms = INFINITY;
    for (double a : kAccelStddevs) {
      const Metrics m = metrics(runEngine(streams.front(), a).errors, false);
      std::printf("| %g | %s | %s |\n", a, fmt(m.tilt_rms / kDeg).c_str(),
                  fmt(m.tilt_max / kDeg).c_str());
      if (m.tilt_rms < chosen_rms) {
        chosen_rms = m.tilt_rms;
        chosen = a;
      }
    }
    std::printf("\nchosen: accel_stddev %g m/s^2\n\n", chosen);
    const std::vector<std::pair<std::string, double>> engines = {
        {"engine, accel_stddev " + fmt(kSensorAccelStddev, "%g") + " (the sensor's)",
         kSensorAccelStddev},
        {"engine, accel_stddev " + fmt(chosen, "%g") + " (chosen on handheld)", chosen}};

    std::printf(
        "| stream | filter | tilt RMS (deg) | tilt max (deg) | heading RMS (deg) | heading RMS "
        "during the disturbance (deg) | heading max (deg) |\n|---|---|---|---|---|---|---|\n");
    std::vector<std::string> targets, start_up, notes, consistency, bounds;
    for (const Stream& s : streams) {
      // The scene's own extremes, so the table says what the filters faced.
      double max_horizontal = 0, max_tilt = 0;
      const sim::Motion& motion = s.motion;
      for (const sim::Sample& x : s.samples) {
        const Eigen::Vector3d a = motion.acceleration_W(x.t);
        max_horizontal = std::max(max_horizontal, std::hypot(a.x(), a.y()));
        max_tilt = std::max(max_tilt, sim::tiltError(x.truth, Eigen::Quaterniond::Identity()));
      }
      std::vector<EngineRun> runs;
      std::vector<Metrics> em;
      for (const auto& e : engines) {
        runs.push_back(runEngine(s, e.second));
        em.push_back(metrics(runs.back().errors, s.mag));
      }
      // The kept gain: the lowest RMS of the attitude error (tilt, and heading with the field).
      std::size_t best = 0;
      double best_score = INFINITY;
      std::vector<Errors> peers;
      std::vector<Metrics> pm;
      for (std::size_t i = 0; i < gains.size(); ++i) {
        peers.push_back(runMadgwick(s, gains[i]));
        pm.push_back(metrics(peers.back(), s.mag));
        const double score = s.mag ? std::hypot(pm[i].tilt_rms, pm[i].heading_rms) : pm[i].tilt_rms;
        if (score < best_score) {
          best_score = score;
          best = i;
        }
      }
      const std::string label =
          s.name + (s.held_out                                     ? " (held out)"
                    : s.name.find("_control") != std::string::npos ? " (control)"
                                                                   : "");
      auto row = [&](const std::string& filter, const Metrics& m) {
        std::printf("| %s | %s | %s | %s | %s | %s | %s |\n", label.c_str(), filter.c_str(),
                    fmt(m.tilt_rms / kDeg).c_str(), fmt(m.tilt_max / kDeg).c_str(),
                    fmt(m.heading_rms / kDeg).c_str(), fmt(m.heading_disturbed / kDeg).c_str(),
                    fmt(m.heading_max / kDeg).c_str());
      };
      for (std::size_t j = 0; j < engines.size(); ++j) row(engines[j].first, em[j]);
      for (std::size_t i = 0; i < gains.size(); ++i) {
        row("Madgwick beta " + fmt(gains[i], "%g") + (i == best ? " (kept)" : ""), pm[i]);
      }
      const Metrics& p = pm[best];
      if (s.name.find("_control") == std::string::npos) {
        const Metrics avg = metrics(runAverager(s), false);
        bounds.push_back("| " + label + " | " + fmt(avg.tilt_max / kDeg, "%.2f") + " | " +
                         fmt(0.5 * p.tilt_max / kDeg, "%.2f") + " | " +
                         (avg.tilt_max <= 0.5 * p.tilt_max ? "no" : "**yes**") + " | " +
                         fmt(avg.tilt_rms / kDeg, "%.2f") + " | " +
                         fmt(0.5 * p.tilt_rms / kDeg, "%.2f") + " |");
      }
      for (std::size_t j = 0; j < engines.size(); ++j) {
        const EngineRun& r = runs[j];
        std::string bias;
        for (int a = 0; a < 3; ++a) {
          const double err = std::abs(r.bias_error(a)) / kDeg;
          bias += std::string(a ? ", " : "") + "xyz"[a] + " " + fmt(err, "%.3f") +
                  (s.observable(a) == 0 ? " (unobservable)"
                   : err <= 0.05        ? " met"
                                        : " **not met**");
        }
        targets.push_back("| " + label + " | " + engines[j].first + " | " +
                          verdict(em[j].tilt_rms / p.tilt_rms) + " | " +
                          verdict(em[j].tilt_max / p.tilt_max) + " | " +
                          (s.mag ? verdict(em[j].heading_rms / p.heading_rms) + " | " +
                                       verdict(em[j].heading_disturbed / p.heading_disturbed)
                                 : std::string(" | ")) +
                          " | " + bias + " |");
        const Metrics late = metrics(r.errors, s.mag, kAfterStartUp);
        const Metrics peer_late = metrics(peers[best], s.mag, kAfterStartUp);
        start_up.push_back("| " + label + " | " + engines[j].first + " | " +
                           verdict(late.tilt_rms / peer_late.tilt_rms) + " | " +
                           verdict(late.tilt_max / peer_late.tilt_max) + " |");
        std::string row = "| " + label + " | " + engines[j].first + " | " +
                          fmt(r.tilt_nees, "%.3g") + " | " +
                          fmt(100.0 * r.tilt_nees_within, "%.0f") + " % |";
        for (int a = 0; a < 3; ++a) {
          row += " " + fmt(r.bias_nees(a), "%.3g") +
                 (s.observable(a) == 0 ? " (unobservable)" : "") + " | " +
                 fmt(r.bias_error(a) / kDeg, "%+.3f") + " / " +
                 fmt(r.bias_stddev(a) / kDeg, "%.3f") + " |";
        }
        consistency.push_back(row);
        std::string nees;
        for (int a = 0; a < 3; ++a) {
          nees += std::string(a ? ", " : "") + "xyz"[a] + " " + fmt(r.bias_nees(a), "%.3g") +
                  (s.observable(a) == 0 ? " (unobservable)" : "");
        }
        char line[800];
        std::snprintf(line, sizeof line,
                      "%s, %s: bias error (deg/s) %+.3f %+.3f %+.3f, its stddev %.3f %.3f %.3f; "
                      "NEES after %.0f s (mean): tilt %.3g (2 if honest), bias %s (1 if honest); "
                      "gravity %s%s",
                      label.c_str(), engines[j].first.c_str(), r.bias_error.x() / kDeg,
                      r.bias_error.y() / kDeg, r.bias_error.z() / kDeg, r.bias_stddev.x() / kDeg,
                      r.bias_stddev.y() / kDeg, r.bias_stddev.z() / kDeg, kSettle, r.tilt_nees,
                      nees.c_str(), counters(r.accel).c_str(),
                      s.mag ? ("; field " + counters(r.mag)).c_str() : "");
        notes.push_back(line);
      }
      char line[300];
      std::snprintf(line, sizeof line,
                    "%s: largest horizontal acceleration %.2f m/s^2, largest tilt %.1f deg; "
                    "Madgwick's kept gain beta %g",
                    label.c_str(), max_horizontal, max_tilt / kDeg, gains[best]);
      notes.push_back(line);
      // Every 20th sample (0.2 s) of the engines and the kept gain.
      std::vector<std::pair<std::string, const Errors*>> series = {
          {"engine_accel_stddev_" + fmt(kSensorAccelStddev, "%g"), &runs[0].errors},
          {"engine_accel_stddev_" + fmt(chosen, "%g"), &runs[1].errors},
          {"madgwick_beta_" + fmt(gains[best], "%g"), &peers[best]}};
      for (const auto& [name, e] : series) {
        const bool engine = !e->tilt_nees.empty();
        for (std::size_t k = 0; k < e->t.size(); k += 20) {
          std::string nees = ",,,";
          if (engine) {
            nees = fmt(e->tilt_nees[k], "%.4g") + "," + fmt(e->bias_nees[k].x(), "%.4g") + "," +
                   fmt(e->bias_nees[k].y(), "%.4g") + "," + fmt(e->bias_nees[k].z(), "%.4g");
          }
          std::fprintf(csv, "%s,%s,%.1f,%.4g,%s,%s\n", s.name.c_str(), name.c_str(), e->t[k],
                       e->tilt[k] / kDeg, s.mag ? fmt(e->heading[k] / kDeg, "%.4g").c_str() : "",
                       nees.c_str());
        }
      }
    }
    std::fclose(csv);
    std::printf(
        "\nTargets (engine / kept Madgwick gain, <= 0.5 met; bias error per axis within "
        "0.05 deg/s):\n\n| stream | engine | tilt RMS | tilt max | heading RMS | heading RMS "
        "during the disturbance | bias error (deg/s) |\n|---|---|---|---|---|---|---|\n");
    for (const std::string& t : targets) std::printf("%s\n", t.c_str());
    std::printf(
        "\nThe vertical the force's average since the first sample gives, turned into the world "
        "by the true attitude (a perfect gyro): what a filter that knows of the linear "
        "acceleration only that it averages to zero has to go on (after %.0f s; not a filter, in "
        "no target). Where its maximum is beyond half the kept gain's, the max target is out of "
        "such a filter's reach:\n\n| stream | its tilt max (deg) | half the kept gain's max | "
        "beyond it | its tilt RMS (deg) | half the kept gain's RMS |\n|---|---|---|---|---|---|\n",
        kSettle);
    for (const std::string& b : bounds) std::printf("%s\n", b.c_str());
    std::printf(
        "\nThe same tilt ratios from %.0f s on, the start-up left out (in no target; the same "
        "kept gain):\n\n| stream | engine | tilt RMS | tilt max |\n|---|---|---|---|\n",
        kAfterStartUp);
    for (const std::string& t : start_up) std::printf("%s\n", t.c_str());
    std::printf(
        "\nConsistency (means after %.0f s; the tilt's NEES 2 and the bias' 1 per axis if the "
        "covariance is honest; the tilt's NEES within its 95 %% bound %.2f 95 %% of the time):\n\n"
        "| stream | engine | tilt NEES | tilt NEES within the bound | bias NEES x | bias x error "
        "/ stddev (deg/s) | bias NEES y | bias y error / stddev | bias NEES z | bias z error / "
        "stddev |\n|---|---|---|---|---|---|---|---|---|---|\n",
        kSettle, kChi2Two95);
    for (const std::string& c : consistency) std::printf("%s\n", c.c_str());
    std::printf("\n");
    for (const std::string& n : notes) std::printf("- %s\n", n.c_str());
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_ahrs: %s\n", e.what());
    return 1;
  }
}
