// Shared test assertions for rotations.
#pragma once

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include "attitude_propagator/numerics/quaternion.h"
#include "sampling.h"

/// Compares two rotations by the angle of a^c b, so that q and -q are equal.
#define EXPECT_ROTATION_NEAR(a, b, tol_rad)                            \
  EXPECT_LE(::attitude_propagator::rotationAngle((a), (b)), (tol_rad)) \
      << "rotations differ: a = " << (a).coeffs().transpose()          \
      << " (x y z w), b = " << (b).coeffs().transpose() << " (x y z w)"

/// Reproducible random unit quaternions, uniform on SO(3) (Shoemake's method).
inline Eigen::Quaterniond randomUnitQuaternion(std::uint64_t& state) {
  auto uniform = [&state]() { return uniformRandom(state); };
  const double u1 = uniform(), u2 = 2.0 * M_PI * uniform(), u3 = 2.0 * M_PI * uniform();
  const double a = std::sqrt(1.0 - u1), b = std::sqrt(u1);
  return Eigen::Quaterniond(b * std::cos(u3), a * std::sin(u2), a * std::cos(u2), b * std::sin(u3));
}
