// The coning motion, the classic strapdown benchmark with a closed-form attitude
// (REFERENCE §2): half-angle beta, cone rate omega.
#pragma once

#include <cmath>

#include <Eigen/Geometry>

struct ConingMotion {
  double beta = 0.1;
  double omega = 2.0 * M_PI * 1.1;  // not a whole number of cones in the test spans

  /// q(t) = (cos(beta/2), 0, sin(beta/2) cos(omega t), sin(beta/2) sin(omega t)).
  Eigen::Quaterniond attitude(double t) const {
    const double s = std::sin(0.5 * beta);
    return Eigen::Quaterniond(std::cos(0.5 * beta), 0.0, s * std::cos(omega * t),
                              s * std::sin(omega * t));
  }

  /// w_B(t) = (-2 omega sin^2(beta/2), -omega sin(beta) sin(omega t), omega sin(beta) cos(omega
  /// t)).
  Eigen::Vector3d bodyRate(double t) const {
    const double s = std::sin(0.5 * beta);
    return Eigen::Vector3d(-2.0 * omega * s * s, -omega * std::sin(beta) * std::sin(omega * t),
                           omega * std::sin(beta) * std::cos(omega * t));
  }
};
