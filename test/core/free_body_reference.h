// An independent numerical truth for the free rigid body: Boost.Odeint's Bulirsch-Stoer in
// long double on the Euler equations written with the full inertia tensor in the user's frame
// (no principal axes, no sorting, no closed form), and its time reversal for instants before
// the start.
#pragma once

#include <Eigen/Geometry>
#include <boost/numeric/odeint.hpp>

#include "attitude_propagator/numerics/dynamic_state.h"
#include "reference_dynamics.h"

namespace free_body_reference {

namespace ap = attitude_propagator;

/// Bulirsch-Stoer on the torque-free right-hand side of reference_dynamics.h (I dw/dt =
/// (I w) x w, dq/dt = 1/2 q (x) (0, w), I_B full) in long double at a tolerance of 1e-17: near
/// the separatrix a double reference at 1e-14 drifts in energy by 1e-14, which moves the flip
/// times by 1e-8 s (measured). Adaptive, unlike reference_dynamics::Trajectory's fixed step,
/// so that the long torque-free runs (100 s and more) stay cheap.
class TensorReference {
 public:
  TensorReference(const Eigen::Matrix3d& I_B, const ap::DynamicState& x0)
      : system_{I_B.cast<Real>(), I_B.cast<Real>().inverse(), Vector3::Zero(), false},
        x_{x0.q_WB.w(), x0.q_WB.x(), x0.q_WB.y(), x0.q_WB.z(), x0.w_B.x(), x0.w_B.y(), x0.w_B.z()} {
  }

  /// The state at time t (from 0), integrating forward from the last time asked for.
  ap::DynamicState advanceTo(double t) {
    namespace odeint = boost::numeric::odeint;
    if (t > t_) {
      odeint::bulirsch_stoer<State, Real> stepper(1e-17L, 1e-17L);
      odeint::integrate_adaptive(stepper, system_, x_, Real(t_), Real(t), Real(1e-3));
      t_ = t;
    }
    return reference_dynamics::toDouble(x_);
  }

 private:
  using Real = reference_dynamics::Real;
  using State = reference_dynamics::State;
  using Vector3 = reference_dynamics::Vector3;
  reference_dynamics::RigidBodySystem system_;
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
