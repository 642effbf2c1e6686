// A tight numerical reference for the dynamic scenes: Boost.Odeint's controlled
// Bulirsch-Stoer in long double at absolute and relative tolerance 1e-16 on (q, w) with the
// Euler equations
//   I dw/dt = (I w) x w + T,   dq/dt = 1/2 q (x) (0, w)   (Coutsias–Romero eqs. 10 and 9),
// written here independently of the core. It judges the torqued scene (no closed form) and
// cross-checks the exact solution; it is never a coarser run of a method under test.
#pragma once

#include <vector>

#include <Eigen/Geometry>

#include "attitude_propagator/numerics/dynamic_state.h"

namespace bench {

namespace ap = attitude_propagator;

/// States at the given increasing times (>= 0) from x0 at t = 0, body torque tau_B held.
std::vector<ap::DynamicState> referenceStates(const Eigen::Vector3d& moments,
                                              const ap::DynamicState& x0,
                                              const Eigen::Vector3d& tau_B,
                                              const std::vector<double>& times);

/// Largest rotation error of the reference against the constant-torque-from-rest closed form
/// (docs/numerics.md §8: w = T t / I, angle T t^2 / (2 I) about the principal axis), over 10 s.
double referenceSelfCheck();

}  // namespace bench
