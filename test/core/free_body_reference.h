// An independent numerical truth for the free rigid body: Boost.Odeint's Bulirsch-Stoer in
// long double on the Euler equations written with the full inertia tensor in the user's frame
// (no principal axes, no sorting, no closed form), and its time reversal for instants before
// the start.
#pragma once

#include <array>

#include <Eigen/Geometry>
#include <boost/numeric/odeint.hpp>

#include "attitude_propagator/dynamic_state.h"

namespace free_body_reference {

namespace ap = attitude_propagator;

/// Bulirsch-Stoer on (q, w) in long double with I_B full: I dw/dt = (I w) x w,
/// dq/dt = 1/2 q (x) (0, w). Long double, because near the separatrix a double reference at
/// 1e-14 drifts in energy by 1e-14, which moves the flip times by 1e-8 s (measured).
class TensorReference {
 public:
  TensorReference(const Eigen::Matrix3d& I_B, const ap::DynamicState& x0)
      : I_(I_B.cast<Real>()), I_inv_(I_B.cast<Real>().inverse()) {
    x_ = {x0.q_WB.w(), x0.q_WB.x(), x0.q_WB.y(), x0.q_WB.z(), x0.w_B.x(), x0.w_B.y(), x0.w_B.z()};
  }

  /// The state at time t (from 0), integrating forward from the last time asked for.
  ap::DynamicState advanceTo(double t) {
    namespace odeint = boost::numeric::odeint;
    auto system = [this](const State& x, State& dxdt, Real) {
      const Vector w(x[4], x[5], x[6]);
      const Vector v(x[1], x[2], x[3]);
      const Vector dv = Real(0.5) * (x[0] * w + v.cross(w));
      const Vector dw = I_inv_ * Vector(I_ * w).cross(w);
      dxdt = {Real(-0.5) * v.dot(w), dv.x(), dv.y(), dv.z(), dw.x(), dw.y(), dw.z()};
    };
    if (t > t_) {
      odeint::bulirsch_stoer<State, Real> stepper(1e-17L, 1e-17L);
      odeint::integrate_adaptive(stepper, system, x_, Real(t_), Real(t), Real(1e-3));
      t_ = t;
    }
    ap::DynamicState x;
    x.q_WB =
        Eigen::Quaterniond(double(x_[0]), double(x_[1]), double(x_[2]), double(x_[3])).normalized();
    x.w_B = Eigen::Vector3d(double(x_[4]), double(x_[5]), double(x_[6]));
    return x;
  }

 private:
  using Real = long double;
  using State = std::array<Real, 7>;
  using Vector = Eigen::Matrix<Real, 3, 1>;
  Eigen::Matrix<Real, 3, 3> I_;
  Eigen::Matrix<Real, 3, 3> I_inv_;
  State x_;
  double t_ = 0.0;
};

/// The time-reversed state (q, -w). The free body is reversible: if (q(t), w(t)) solves
/// dq/dt = 1/2 q (x) (0, w), I dw/dt = (I w) x w, so does (q(-t), -w(-t)) (both right-hand
/// sides change sign with w, the second as a product of two factors in w). So the state s
/// seconds before x0 is the reversal of the state s seconds after reversed(x0).
inline ap::DynamicState reversed(const ap::DynamicState& x) { return {x.q_WB, -x.w_B}; }

/// The reference run backward in time: the states at -s for increasing s.
class BackwardReference {
 public:
  BackwardReference(const Eigen::Matrix3d& I_B, const ap::DynamicState& x0)
      : forward_(I_B, reversed(x0)) {}

  /// The state s >= 0 seconds before the start (s not below the last one asked for).
  ap::DynamicState before(double s) { return reversed(forward_.advanceTo(s)); }

 private:
  TensorReference forward_;
};

}  // namespace free_body_reference
