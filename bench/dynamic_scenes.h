// Dynamic benchmark scenes (docs/design.md §8): a body, an initial state and a torque held in the
// body frame. Torque-free scenes are judged against the exact solution (docs/numerics.md §6), the
// torqued one against a tight Bulirsch-Stoer reference (reference.h).
#pragma once

#include <cmath>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "attitude_propagator/numerics/dynamic_state.h"

namespace bench {

namespace ap = attitude_propagator;

struct DynamicScene {
  std::string name;
  Eigen::Vector3d moments = Eigen::Vector3d::Ones();  ///< principal moments, B = P (kg m^2)
  ap::DynamicState initial;
  Eigen::Vector3d torque_B = Eigen::Vector3d::Zero();  ///< N m, constant in the body
  double duration = 10.0;                              ///< s
  /// Errors are taken at every multiple of this (s); every step of the sweep divides it.
  double check_interval = 0.4;
  std::vector<double> steps;  ///< s, the step-size sweep
  double max_rate = 1.0;      ///< rad/s, the |Omega| of |Omega| dt (set from the reference)

  bool torqueFree() const { return torque_B.isZero(0.0); }
};

/// check_interval / 2^k, k = first..last: every step divides the check interval.
inline std::vector<double> halvingSteps(double largest, int count) {
  std::vector<double> steps;
  for (int k = 0; k < count; ++k) steps.push_back(std::ldexp(largest, -k));
  return steps;
}

inline ap::DynamicState fromMomentum(const Eigen::Vector3d& moments, const Eigen::Vector3d& M) {
  ap::DynamicState x;
  x.w_B = M.cwiseQuotient(moments);
  return x;
}

/// free_body: Hairer-Lubich-Wanner, I = (2, 1, 2/3), M0 = (cos 1.1, 0, sin 1.1), to t = 100 s.
inline DynamicScene freeBodyScene() {
  DynamicScene s;
  s.name = "free_body";
  s.moments = Eigen::Vector3d(2.0, 1.0, 2.0 / 3.0);
  s.initial = fromMomentum(s.moments, Eigen::Vector3d(std::cos(1.1), 0.0, std::sin(1.1)));
  s.duration = 100.0;
  s.check_interval = 0.4;
  s.steps = halvingSteps(0.4, 12);  // 0.4 s .. 0.2 ms
  return s;
}

/// dzhanibekov: a T-handle, I = (1, 2, 2.5), spun at 5 rad/s about the middle axis with a small
/// disturbance; M circulates about the largest axis close to the separatrix and the handle
/// flips every half body period.
inline DynamicScene dzhanibekovScene() {
  DynamicScene s;
  s.name = "dzhanibekov";
  s.moments = Eigen::Vector3d(1.0, 2.0, 2.5);
  s.initial.w_B = Eigen::Vector3d(0.1, 5.0, 0.2);
  s.duration = 30.0;
  s.check_interval = 0.4;
  s.steps = halvingSteps(0.2, 11);  // 0.2 s .. 0.1 ms
  return s;
}

/// symmetric_top: a prolate top (a spinning rod or projectile), I = (2, 2, 1), spin 5 rad/s
/// about the symmetry axis with a transverse rate of 0.5 rad/s: it nutates and precesses.
inline DynamicScene symmetricTopScene() {
  DynamicScene s;
  s.name = "symmetric_top";
  s.moments = Eigen::Vector3d(2.0, 2.0, 1.0);
  s.initial.w_B = Eigen::Vector3d(0.5, 0.0, 5.0);
  s.initial.q_WB = Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitX());
  s.duration = 20.0;
  s.check_interval = 0.4;
  s.steps = halvingSteps(0.2, 11);
  return s;
}

/// torqued: a triaxial body, I = (3, 2, 1.5), tumbling from w0 = (0.3, -0.2, 1.0) rad/s under
/// a constant body torque (0.05, -0.1, 0.2) N m.
inline DynamicScene torquedScene() {
  DynamicScene s;
  s.name = "torqued";
  s.moments = Eigen::Vector3d(3.0, 2.0, 1.5);
  s.initial.w_B = Eigen::Vector3d(0.3, -0.2, 1.0);
  s.initial.q_WB = Eigen::AngleAxisd(-0.3, Eigen::Vector3d(1.0, 1.0, 0.0).normalized());
  s.torque_B = Eigen::Vector3d(0.05, -0.1, 0.2);
  s.duration = 20.0;
  s.check_interval = 0.4;
  s.steps = halvingSteps(0.2, 11);
  return s;
}

}  // namespace bench
