// What the engine tests share: stamps like a real ROS time, a sink that records what the engine
// hands on and one that discards it, the standard configurations and inputs.
#pragma once

#include <cmath>
#include <vector>

#include <Eigen/Geometry>

#include "attitude_propagator/engine.h"

namespace engine_fixtures {

namespace ap = attitude_propagator;

constexpr ap::Stamp kSecond = 1000000000;
// An epoch stamp like a real ROS time (2026), so the origin handling is exercised.
constexpr ap::Stamp kEpoch = 1780000000LL * kSecond;

inline ap::Stamp at(double seconds) {
  return kEpoch + static_cast<ap::Stamp>(std::llround(seconds * 1e9));
}

inline Eigen::Quaterniond aboutAxis(const Eigen::Vector3d& axis, double angle) {
  return Eigen::Quaterniond(Eigen::AngleAxisd(angle, axis.normalized()));
}

/// Records what the engine hands on.
struct Recorder : ap::EngineSink {
  std::vector<ap::EngineState> states;
  std::vector<ap::Input> applied;
  std::vector<ap::EngineState> applied_states;  ///< the state handed on with each applied input
  std::vector<ap::EngineNote> notes;

  void publishState(const ap::EngineState& s) override { states.push_back(s); }
  void inputApplied(const ap::Input& input, const ap::EngineState& s) override {
    applied.push_back(input);
    applied_states.push_back(s);
  }
  void note(const ap::EngineNote& n) override { notes.push_back(n); }

  const ap::EngineState* stateAt(ap::Stamp stamp) const {
    for (const auto& s : states) {
      if (s.stamp == stamp) return &s;
    }
    return nullptr;
  }
  bool stampsIncrease() const {
    for (std::size_t i = 1; i < states.size(); ++i) {
      if (states[i].stamp <= states[i - 1].stamp) return false;
    }
    return true;
  }
};

/// Takes what the engine hands on and keeps nothing: for tests that look elsewhere.
struct DiscardingSink : ap::EngineSink {
  void publishState(const ap::EngineState&) override {}
  void inputApplied(const ap::Input&, const ap::EngineState&) override {}
  void note(const ap::EngineNote&) override {}
};

inline ap::EngineConfig kinematicConfig() {
  ap::EngineConfig c;
  c.model = ap::Model::Kinematic;
  return c;
}

/// A sphere (I = 2 about every axis) with torque input, 50 Hz grid, rk4.
inline ap::EngineConfig torqueConfig() {
  ap::EngineConfig c;
  c.model = ap::Model::Dynamic;
  ap::DynamicConfig d;
  d.body = ap::RigidBody::fromPrincipalMoments(Eigen::Vector3d::Constant(2.0));
  d.integrator = ap::Integrator::Rk4;
  d.torque_input = true;
  d.max_step = 0.02;
  c.dynamic = d;
  c.publish_rate = 50.0;
  return c;
}

/// A generic body for torque tests: principal moments kGenericMoments about the columns of
/// genericAxes(), a rotation of the body axes about a generic axis, so that no two axes respond
/// alike. A torque along principal axis i from rest spins the body about that axis alone
/// (Euler's equations: w x I w = 0), w_B(t) = tau t / I_i, which rk4 integrates exactly.
const Eigen::Vector3d kGenericMoments(1.5, 2.5, 3.0);
inline Eigen::Matrix3d genericAxes() {
  return Eigen::AngleAxisd(0.7, Eigen::Vector3d(1.0, -2.0, 3.0).normalized()).toRotationMatrix();
}
inline ap::EngineConfig genericTorqueConfig() {
  ap::EngineConfig c = torqueConfig();
  const Eigen::Matrix3d axes = genericAxes();
  Eigen::Matrix3d I_B = axes * kGenericMoments.asDiagonal() * axes.transpose();
  I_B = 0.5 * (I_B + I_B.transpose());
  c.dynamic->body = ap::RigidBody::fromTensor(I_B);
  return c;
}

/// A torque-free sphere turning at 0.2 rad/s about z (exact model).
inline ap::EngineConfig spinningSphereConfig() {
  ap::EngineConfig c;
  c.model = ap::Model::Dynamic;
  ap::DynamicConfig d;
  d.body = ap::RigidBody::fromPrincipalMoments(Eigen::Vector3d::Ones());
  d.initial.w_B = Eigen::Vector3d(0.0, 0.0, 0.2);
  d.max_step = 0.02;
  c.dynamic = d;
  c.publish_rate = 50.0;
  return c;
}

inline ap::Input rate(ap::Stamp stamp, const Eigen::Vector3d& w_B) {
  ap::Input in;
  in.source = ap::Source::Imu;
  in.stamp = stamp;
  in.value = w_B;
  return in;
}

inline ap::Input torque(ap::Stamp stamp, const Eigen::Vector3d& tau,
                        ap::TorqueFrame frame = ap::TorqueFrame::Body) {
  ap::Input in;
  in.source = ap::Source::Torque;
  in.stamp = stamp;
  in.value = tau;
  in.frame = frame;
  return in;
}

/// Ticks a complete clock record from `from` to `to` in steps of `step` seconds.
inline void runClock(ap::AttitudeEngine& engine, double from, double to, double step) {
  const int n = static_cast<int>(std::llround((to - from) / step));
  for (int k = 1; k <= n; ++k) engine.clockTick(at(from + k * step));
}

/// A fix covariance that breaks every symmetry (rad^2): variances unlike on each axis,
/// correlated, about (0.02 rad)^2 in all, so that C R C^T and C^T R C, or R and its transpose
/// of a wrongly turned frame, differ far beyond round-off.
inline Eigen::Matrix3d correlatedFixCovariance() {
  Eigen::Matrix3d L;
  L << 0.018, 0.0, 0.0, 0.006, 0.014, 0.0, -0.004, 0.008, 0.02;
  return L * L.transpose();
}

}  // namespace engine_fixtures
