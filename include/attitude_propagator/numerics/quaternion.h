// Quaternion operations of the Coutsias–Romero notes ("The Quaternions with an
// application to Rigid Body Dynamics") that Eigen does not already provide.
//
// Conventions (docs/conventions.md §2): Hamilton quaternions; q_WB maps body coordinates to world,
// x_W = q_WB X_B q_WB^c (notes eq. 7). Eigen's product, conjugate, norm, vector rotation and
// rotation matrix (notes §6) are used as they are.
#pragma once

#include <cmath>
#include <optional>

#include <Eigen/Geometry>

namespace attitude_propagator {

/// Exponential map of a rotation vector v (angle |v|, docs/numerics.md §1):
/// Exp(v) = (cos(|v|/2), sin(|v|/2) v/|v|). Below |v|^2 = 1e-12 a Taylor series is used, so
/// the result is exact to round-off near zero and never divides by zero. Inline: it is the
/// inner operation of every Lie-group step.
inline Eigen::Quaterniond expMap(const Eigen::Vector3d& v) {
  // Below this squared angle the series are exact to round-off (the next terms are of order
  // theta^6 / 46080 < 1e-22) and avoid the 0/0 of sin(theta/2)/theta.
  constexpr double kSmallAngleSquared = 1e-12;
  const double theta2 = v.squaredNorm();
  double w;
  double s;  // sin(theta/2) / theta
  if (theta2 < kSmallAngleSquared) {
    w = 1.0 - theta2 / 8.0 + theta2 * theta2 / 384.0;
    s = 0.5 - theta2 / 48.0 + theta2 * theta2 / 3840.0;
  } else {
    const double theta = std::sqrt(theta2);
    w = std::cos(0.5 * theta);
    s = std::sin(0.5 * theta) / theta;
  }
  return Eigen::Quaterniond(w, s * v.x(), s * v.y(), s * v.z());
}

/// q / |q| at any finite scale: the components are divided by the largest |component| first
/// (which leaves a norm in [1, 2]), then by that norm, so neither q = (1e300, 1e300, 0, 0)
/// (whose |q|^2 overflows) nor (1e-300, 0, 0, 0) (whose |q|^2 underflows to 0) is lost.
/// nullopt for a non-finite or all-zero q.
std::optional<Eigen::Quaterniond> safeNormalized(const Eigen::Quaterniond& q);

/// Logarithm map, the inverse of expMap: the rotation vector of q with angle in [0, pi].
/// q and -q give the same vector (the shorter of the two rotations is returned).
Eigen::Vector3d logMap(const Eigen::Quaterniond& q);

/// Rotation angle in [0, pi] of a^c b: the geodesic distance between two rotations, for which
/// q and -q are the same rotation. Accurate also for tiny angles (uses atan2, not acos).
double rotationAngle(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b);

/// The 4x4 matrices of the notes §7 in (w, x, y, z) ordering: for p = (w, x, y, z),
/// q (x) p = leftMatrix(q) p = rightMatrix(p) q.
Eigen::Matrix4d leftMatrix(const Eigen::Quaterniond& q);
Eigen::Matrix4d rightMatrix(const Eigen::Quaterniond& q);

/// Coefficient vector (w, x, y, z) of q, the ordering of the notes and of leftMatrix.
Eigen::Vector4d wxyz(const Eigen::Quaterniond& q);

/// The pure quaternion (0, v).
Eigen::Quaterniond pureQuaternion(const Eigen::Vector3d& v);

/// Reflection of the notes' Theorem 2: v' = n v n for a unit pure quaternion n, which is
/// v - 2 (n . v) n, the mirror image of v in the plane through the origin normal to n.
/// Throws std::invalid_argument if n is not of unit length (to 1e-9).
Eigen::Vector3d reflect(const Eigen::Vector3d& n, const Eigen::Vector3d& v);

}  // namespace attitude_propagator
