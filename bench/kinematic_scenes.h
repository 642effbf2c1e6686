// Kinematic benchmark scenes (docs/design.md §8): a body-rate history w_B(t) with its closed-form
// attitude q_WB(t), so the error of a propagation from rate samples is measured against the
// truth, never against another run of ours.
#pragma once

#include <cmath>
#include <functional>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "attitude_propagator/numerics/coning_motion.h"

namespace bench {

/// Closed form of dq/dt = 1/2 q (x) (0, w_B(t)) for a precession at rate a about the fixed
/// axis m_W combined with a spin at rate c about body e3:
///   q(t) = Exp(t a m_W) (x) q0 (x) Exp(t c e3).
/// Differentiating, dq/dt = 1/2 (0, a m_W) q + 1/2 q (0, c e3) = 1/2 q (x) (0, w_B) with
///   w_B(t) = a R(q(t))^T m_W + c e3 = a Rz(-c t) R(q0)^T m_W + c e3,
/// since Exp(t a m_W) fixes m_W. With a = 0 it is the constant rate c e3.
struct TwoAxisMotion {
  double precession = 0.0;  ///< a, rad/s
  double spin = 0.0;        ///< c, rad/s
  Eigen::Vector3d m_W = Eigen::Vector3d::UnitZ();
  Eigen::Quaterniond q0 = Eigen::Quaterniond::Identity();

  Eigen::Quaterniond attitude(double t) const {
    return Eigen::Quaterniond(Eigen::AngleAxisd(precession * t, m_W)) * q0 *
           Eigen::Quaterniond(Eigen::AngleAxisd(spin * t, Eigen::Vector3d::UnitZ()));
  }

  Eigen::Vector3d bodyRate(double t) const {
    const Eigen::Vector3d m_B0 = q0.conjugate() * m_W;
    const Eigen::Vector3d m_B = Eigen::AngleAxisd(-spin * t, Eigen::Vector3d::UnitZ()) * m_B0;
    return precession * m_B + spin * Eigen::Vector3d::UnitZ();
  }
};

using attitude_propagator::ConingMotion;

struct KinematicScene {
  std::string name;
  std::function<Eigen::Quaterniond(double)> attitude;  ///< closed-form q_WB(t)
  std::function<Eigen::Vector3d(double)> rate;         ///< w_B(t), rad/s
  double max_rate = 1.0;             ///< largest |w_B|, rad/s: the |Omega| of |Omega| dt
  double duration = 1.0;             ///< s
  std::vector<double> sample_rates;  ///< Hz, the step-size sweep (dt = 1 / rate)
};

/// first * 2^k, k = 0..count-1.
inline std::vector<double> doublingRates(double first, int count) {
  std::vector<double> rates;
  for (int k = 0; k < count; ++k) rates.push_back(first * std::ldexp(1.0, k));
  return rates;
}

inline KinematicScene fromTwoAxis(const std::string& name, const TwoAxisMotion& m) {
  KinematicScene scene;
  scene.name = name;
  scene.attitude = [m](double t) { return m.attitude(t); };
  scene.rate = [m](double t) { return m.bodyRate(t); };
  scene.max_rate = std::abs(m.precession) + std::abs(m.spin);
  return scene;
}

/// constant_rate: 1 rad/s about body e3 from a skew initial attitude. exp, exp2 and cf4 are
/// exact at any step; euler and rk4 are not.
inline KinematicScene constantRateScene() {
  TwoAxisMotion m;
  m.spin = 1.0;
  m.q0 = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1.0, -2.0, 0.5).normalized());
  KinematicScene scene = fromTwoAxis("constant_rate", m);
  scene.duration = 20.0;
  scene.sample_rates = doublingRates(25.0, 11);  // 25 Hz .. 25.6 kHz
  return scene;
}

/// coning: beta = 0.1 rad, Omega = 2 pi 1.1 rad/s over 20 s, as docs/numerics.md §8 measured.
inline KinematicScene coningScene() {
  const ConingMotion cone;
  KinematicScene scene;
  scene.name = "coning";
  scene.attitude = [cone](double t) { return cone.attitude(t); };
  scene.rate = [cone](double t) { return cone.bodyRate(t); };
  scene.max_rate = cone.rateMagnitude();
  scene.duration = 20.0;
  scene.sample_rates = doublingRates(25.0, 11);  // includes 200 Hz, the target's rate
  return scene;
}

/// fast_spin: a spinner at 20 rev/s about body e3 whose spin axis, tilted by 0.3 rad,
/// precesses at 2 rad/s about world z (|w_B| up to 128 rad/s: |w| dt = 0.64 at 200 Hz).
inline KinematicScene fastSpinScene() {
  TwoAxisMotion m;
  m.spin = 2.0 * M_PI * 20.0;
  m.precession = 2.0;
  m.q0 = Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitX());
  KinematicScene scene = fromTwoAxis("fast_spin", m);
  scene.duration = 5.0;
  scene.sample_rates = doublingRates(100.0, 10);  // 100 Hz .. 51.2 kHz
  return scene;
}

/// tumbling: a fast tumbling body, spinning at 2 rev/s about body e3 while that axis, tilted
/// by 1 rad, precesses at 3 rad/s about world z (|w_B| up to 15.6 rad/s: |w| dt = 0.08 at 200 Hz).
inline KinematicScene tumblingScene() {
  TwoAxisMotion m;
  m.spin = 2.0 * M_PI * 2.0;
  m.precession = 3.0;
  m.q0 = Eigen::AngleAxisd(1.0, Eigen::Vector3d(1.0, 0.5, 0.0).normalized());
  KinematicScene scene = fromTwoAxis("tumbling", m);
  scene.duration = 20.0;
  scene.sample_rates = {200.0};
  return scene;
}

/// fast_tumbling: spinning at 3.5 rev/s about body e3 while that axis, tilted by 1 rad,
/// precesses at 2 rad/s about world z (|w_B| up to 24 rad/s: |w| h = 0.24 at 100 Hz).
inline KinematicScene fastTumblingScene() {
  TwoAxisMotion m;
  m.spin = 2.0 * M_PI * 3.5;
  m.precession = 2.0;
  m.q0 = Eigen::AngleAxisd(1.0, Eigen::Vector3d(1.0, 0.5, 0.0).normalized());
  KinematicScene scene = fromTwoAxis("fast_tumbling", m);
  scene.duration = 20.0;
  return scene;
}

/// vibration: a 50 Hz wobble (a coning of half-angle 0.02 rad, |w| = 6.3 rad/s, as a mount's
/// vibration makes) on top of a slow turn (0.5 rev/s about body e3, that axis tilted by 0.5 rad
/// precessing at 0.5 rad/s). With q = q_A(t) (x) q_B(t), the slow turn A and the wobble B,
///   dq/dt = 1/2 q (x) (0, R(q_B)^T w_A + w_B),
/// so w_B of the pair is the slow turn's rate seen in the wobbling body plus the wobble's.
inline KinematicScene vibrationScene() {
  TwoAxisMotion slow;
  slow.spin = 2.0 * M_PI * 0.5;
  slow.precession = 0.5;
  slow.q0 = Eigen::AngleAxisd(0.5, Eigen::Vector3d(0.3, 1.0, 0.0).normalized());
  ConingMotion wobble;
  wobble.beta = 0.02;
  wobble.omega = 2.0 * M_PI * 50.0;
  KinematicScene scene;
  scene.name = "vibration";
  scene.attitude = [slow, wobble](double t) { return slow.attitude(t) * wobble.attitude(t); };
  scene.rate = [slow, wobble](double t) {
    return Eigen::Vector3d(wobble.attitude(t).conjugate() * slow.bodyRate(t) + wobble.bodyRate(t));
  };
  scene.max_rate = std::abs(slow.spin) + std::abs(slow.precession) + wobble.rateMagnitude();
  scene.duration = 20.0;
  return scene;
}

}  // namespace bench
