// A reference solution of the torqued rigid body for the dynamic tests, written apart from the
// core: the Euler equations and the kinematics in the user's body frame B with the full inertia
// tensor I_B (no principal frame),
//   I_B dw_B/dt = (I_B w_B) x w_B + T_B,   dq_WB/dt = 1/2 q_WB (x) (0, w_B),
// with T_B = tau for a body torque and T_B = R(q_WB)^T tau for a fixed-frame torque, integrated
// in long double by Boost.Odeint's Runge-Kutta-Fehlberg 7(8) at a fixed step (the 8th-order
// solution). At rates and torques of order one, a step of 1e-3 s leaves errors far below the
// doubles' round-off; ReferenceDynamics.* checks that by halving the step and against closed
// forms and published values.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <utility>
#include <vector>

#include <boost/numeric/odeint/stepper/runge_kutta_fehlberg78.hpp>

#include <Eigen/Geometry>

#include "attitude_propagator/numerics/dynamic_state.h"
#include "attitude_propagator/numerics/quaternion.h"

namespace reference_dynamics {

namespace ap = attitude_propagator;

using Real = long double;
using Vector3 = Eigen::Matrix<Real, 3, 1>;
using Matrix3 = Eigen::Matrix<Real, 3, 3>;
/// q_WB (w, x, y, z), w_B (x, y, z).
using State = std::array<Real, 7>;

/// A torque in force from `from` until the next segment starts (or the end).
struct TorqueSegment {
  double from = 0.0;
  ap::TorqueInput torque;
};

/// The right-hand side in long double.
struct RigidBodySystem {
  Matrix3 I_B;
  Matrix3 I_B_inverse;
  Vector3 tau;
  bool fixed = false;

  void operator()(const State& x, State& dxdt, Real /*t*/) const {
    const Real qw = x[0];
    const Vector3 v(x[1], x[2], x[3]);
    const Vector3 w(x[4], x[5], x[6]);
    // 1/2 q (x) (0, w) = 1/2 (-v.w, qw w + v x w).
    const Vector3 dv = Real(0.5) * (qw * w + v.cross(w));
    const Vector3 dw = I_B_inverse * (Vector3(I_B * w).cross(w) + torqueInBody(qw, v));
    dxdt = {Real(-0.5) * v.dot(w), dv.x(), dv.y(), dv.z(), dw.x(), dw.y(), dw.z()};
  }

  /// R(q)^T tau for q = (qw, v) taken as q/|q|: tau - (2/|q|^2) (qw (v x tau) - v x (v x tau)).
  Vector3 torqueInBody(Real qw, const Vector3& v) const {
    if (!fixed) return tau;
    const Vector3 vt = v.cross(tau);
    const Real s = Real(2) / (qw * qw + v.squaredNorm());
    return tau - s * (qw * vt - v.cross(vt));
  }
};

/// The long-double state rounded to a DynamicState (q normalised in long double).
inline ap::DynamicState toDouble(const State& x) {
  const Real norm = std::sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2] + x[3] * x[3]);
  ap::DynamicState y;
  y.q_WB = Eigen::Quaterniond(static_cast<double>(x[0] / norm), static_cast<double>(x[1] / norm),
                              static_cast<double>(x[2] / norm), static_cast<double>(x[3] / norm));
  y.w_B = Eigen::Vector3d(static_cast<double>(x[4]), static_cast<double>(x[5]),
                          static_cast<double>(x[6]));
  return y;
}

/// The reference trajectory from x0 at t0 under piecewise-constant torques (none: torque-free),
/// advanced in steps of at most h that land exactly on every switch of the torque and on every
/// time asked for.
class Trajectory {
 public:
  Trajectory(const Eigen::Matrix3d& I_B, const ap::DynamicState& x0, double t0,
             std::vector<TorqueSegment> torques = {}, double h = 1e-3)
      : torques_(std::move(torques)), h_(h), t_(t0) {
    system_.I_B = I_B.cast<Real>();
    system_.I_B_inverse = system_.I_B.inverse();
    const Eigen::Quaterniond q0 = x0.q_WB.normalized();
    x_ = {q0.w(), q0.x(), q0.y(), q0.z(), x0.w_B.x(), x0.w_B.y(), x0.w_B.z()};
  }

  /// Advances to t (t >= time()) and returns the state there.
  ap::DynamicState advanceTo(double t) {
    for (;;) {
      // The next switch of the torque after time(), or t.
      double end = t;
      for (const TorqueSegment& s : torques_) {
        if (s.from > t_ && s.from < end) end = s.from;
      }
      integrate(end);
      if (end == t) break;
    }
    return toDouble(x_);
  }

  double time() const { return t_; }
  const State& state() const { return x_; }

 private:
  /// Steps from time() to end (no switch inside) with the torque in force at time().
  void integrate(double end) {
    system_.tau = Vector3::Zero();
    system_.fixed = false;
    for (const TorqueSegment& s : torques_) {  // the last segment started at or before t_
      if (s.from <= t_) {
        system_.tau = s.torque.tau.cast<Real>();
        system_.fixed = s.torque.frame == ap::TorqueFrame::Fixed;
      }
    }
    const Real span = Real(end) - Real(t_);
    if (span > 0) {
      const long n = std::max(1L, static_cast<long>(std::ceil(span / Real(h_))));
      const Real dt = span / Real(n);
      for (long i = 0; i < n; ++i) stepper_.do_step(system_, x_, Real(t_) + Real(i) * dt, dt);
    }
    t_ = end;
  }

  RigidBodySystem system_;
  boost::numeric::odeint::runge_kutta_fehlberg78<State, Real, State, Real> stepper_;
  std::vector<TorqueSegment> torques_;
  double h_;
  double t_;
  State x_;
};

/// The state at t1 from x0 at t0 under one torque held from t0 on.
inline ap::DynamicState solve(const Eigen::Matrix3d& I_B, const ap::DynamicState& x0, double t0,
                              double t1, const ap::TorqueInput& torque, double h = 1e-3) {
  return Trajectory(I_B, x0, t0, {TorqueSegment{t0, torque}}, h).advanceTo(t1);
}

/// The largest difference of two long-double states, component-wise (q up to sign).
inline Real difference(const State& a, const State& b) {
  const Real sign = a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3] < 0 ? -1 : 1;
  Real worst = 0;
  for (int i = 0; i < 7; ++i) {
    worst = std::max(worst, std::abs(a[i] - (i < 4 ? sign : 1) * b[i]));
  }
  return worst;
}

/// How far (q_WB, w_B) is from a reference state: the larger of the attitude angle (rad) and
/// |w_B - w_ref| (rad/s).
inline double stateError(const Eigen::Quaterniond& q_WB, const Eigen::Vector3d& w_B,
                         const ap::DynamicState& truth) {
  return std::max(ap::rotationAngle(q_WB, truth.q_WB), (w_B - truth.w_B).norm());
}

}  // namespace reference_dynamics
