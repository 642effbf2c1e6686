// rk4 on a sphere, in closed form: w is constant, and rk4 on q' = q (x) (0, w)/2 is the Taylor
// polynomial of the exponential to 4th order, q1 = q0 (x) ((1 - a^2/2 + a^4/24),
// (1 - a^2/6) a w/|w|) with a = h |w| / 2. Its squared norm is 1 + d, d = -a^6/72 + a^8/576.
#pragma once

#include <cmath>

#include <Eigen/Core>

namespace rk4_sphere {

/// |q1| - 1 after one rk4 step of h at the constant rate w: d / (1 + sqrt(1 + d)).
inline double normError(double h, const Eigen::Vector3d& w) {
  const double a = 0.5 * h * w.norm();
  const double d = -std::pow(a, 6) / 72.0 + std::pow(a, 8) / 576.0;
  return d / (1.0 + std::sqrt(1.0 + d));
}

}  // namespace rk4_sphere
