// The coning motion, the classic strapdown benchmark with a closed-form attitude
// (docs/numerics.md §8), shared by the tests, the benchmarks and the demo as their truth.
#pragma once

#include <cmath>

#include <Eigen/Geometry>

namespace attitude_propagator {

/// The attitude q(t) below together with the body rate that generates it through
/// dq/dt = 1/2 q (x) (0, w_B) (notes eq. 9); test_kinematic_step checks the pair.
struct ConingMotion {
  double beta = 0.1;                // half-angle, rad
  double omega = 2.0 * M_PI * 1.1;  // cone rate, rad/s (not a whole number of cones per second)

  /// q_WB(t) = (cos(beta/2), 0, sin(beta/2) cos(omega t), sin(beta/2) sin(omega t)).
  Eigen::Quaterniond attitude(double t) const {
    const double s = std::sin(0.5 * beta);
    return Eigen::Quaterniond(std::cos(0.5 * beta), 0.0, s * std::cos(omega * t),
                              s * std::sin(omega * t));
  }

  /// w_B(t) = (-2 omega sin^2(beta/2), -omega sin(beta) sin(omega t),
  ///           omega sin(beta) cos(omega t)), rad/s.
  Eigen::Vector3d bodyRate(double t) const {
    const double s = std::sin(0.5 * beta);
    return Eigen::Vector3d(-2.0 * omega * s * s, -omega * std::sin(beta) * std::sin(omega * t),
                           omega * std::sin(beta) * std::cos(omega * t));
  }

  /// |w_B|, which is constant: 2 omega sin(beta/2).
  double rateMagnitude() const { return bodyRate(0.0).norm(); }
};

}  // namespace attitude_propagator
