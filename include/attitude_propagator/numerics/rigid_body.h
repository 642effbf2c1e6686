// A rigid body's inertia (docs/design.md §4, docs/numerics.md §6). The user's body frame B may
// differ from the principal frame P in which the Euler equations are diagonal; q_BP maps principal
// coordinates to the user's body coordinates, so everything the user sees stays in B.
#pragma once

#include <array>
#include <vector>

#include <Eigen/Geometry>

namespace attitude_propagator {

class RigidBody {
 public:
  /// Whether the moments must satisfy the triangle inequality I_i <= I_j + I_k, which every
  /// real body does. Ignore admits the mathematical test rotors of the literature, such as
  /// Hairer-Lubich-Wanner's free body I = (2, 1, 2/3) (docs/numerics.md §8): the Euler equations
  /// and their exact solution do not need the inequality.
  enum class TriangleInequality { Require, Ignore };

  /// Principal moments (kg m^2) along the body axes, so P = B.
  /// Throws std::invalid_argument naming the problem: non-finite, non-positive, outside
  /// [kMinInertia, kMaxInertia] (limits.h), or moments that break the triangle inequality (I_i <=
  /// I_j + I_k) unless told to ignore it.
  static RigidBody fromPrincipalMoments(const Eigen::Vector3d& moments,
                                        TriangleInequality triangle = TriangleInequality::Require);

  /// A full symmetric inertia tensor in B, diagonalised with Eigen's SelfAdjointEigenSolver:
  /// I_B = C_BP diag(I1, I2, I3) C_BP^T with the eigenvectors as the columns of C_BP, the
  /// third one flipped if needed so that det C_BP = +1 (q_BP is a proper rotation). A diagonal
  /// tensor keeps P = B. Symmetry is checked to 1e-12 of the largest entry.
  /// Throws std::invalid_argument for a non-symmetric, non-finite or not positive definite
  /// tensor or one whose principal moments leave [kMinInertia, kMaxInertia] or break the
  /// triangle inequality.
  static RigidBody fromTensor(const Eigen::Matrix3d& I_B);

  /// The `inertia` parameter: 3 values (principal, Ixx Iyy Izz) or 6 values
  /// (Ixx Iyy Izz Ixy Ixz Iyz), the latter being the off-diagonal elements of the tensor
  /// (the URDF convention, Ixy = -sum m x y). Throws std::invalid_argument for any other count and
  /// for the problems above.
  static RigidBody fromParameter(const std::vector<double>& values);

  /// Principal moments I1, I2, I3 in P.
  const Eigen::Vector3d& principalMoments() const { return moments_P_; }
  /// Rotation from principal coordinates to the user's body coordinates: x_B = q_BP x_P.
  const Eigen::Quaterniond& q_BP() const { return q_BP_; }
  /// Inertia tensor in the user's body frame.
  Eigen::Matrix3d tensor_B() const;

  /// True when all three principal moments are equal to rel_tol (relative to the largest).
  bool isSphere(double rel_tol = 1e-12) const;
  /// True when two principal moments are equal (to rel_tol); symmetryAxis() gives the
  /// symmetry axis.
  bool isSymmetric(double rel_tol = 1e-12) const;
  /// Index in P (0, 1, 2) of the moment that differs from the other two, i.e. the symmetry
  /// axis of a symmetric body (for a sphere: 2). Throws std::logic_error for a body that is
  /// not symmetric to rel_tol.
  int symmetryAxis(double rel_tol = 1e-12) const;
  /// Indices in P of the smallest, middle and largest principal moments (ties keep the order
  /// of the axes).
  std::array<int, 3> sortedAxes() const;

  /// Inverse principal moments 1/I1, 1/I2, 1/I3.
  const Eigen::Vector3d& inverseMoments() const { return inverse_moments_P_; }

  /// Angular momentum M_B = I_B w_B, body frame.
  Eigen::Vector3d angularMomentum_B(const Eigen::Vector3d& w_B) const;
  /// Kinetic energy 1/2 w_B . I_B w_B.
  double kineticEnergy(const Eigen::Vector3d& w_B) const;
  /// Angular momentum in the fixed frame, m_W = q_WB M_B (conserved without torque).
  Eigen::Vector3d angularMomentum_W(const Eigen::Quaterniond& q_WB,
                                    const Eigen::Vector3d& w_B) const;

 private:
  RigidBody(const Eigen::Vector3d& moments_P, const Eigen::Quaterniond& q_BP);
  Eigen::Vector3d moments_P_;
  Eigen::Vector3d inverse_moments_P_;
  Eigen::Quaterniond q_BP_;
};

}  // namespace attitude_propagator
