// A rigid body's inertia (DESIGN §4, REFERENCE §3). The user's body frame B may differ from the
// principal frame P in which the Euler equations are diagonal; q_BP maps principal coordinates
// to the user's body coordinates, so everything the user sees stays in B.
//
// CONTRACT for the dynamics issue: the public API below is used by the ROS wrapper and the
// benchmarks. Implement it in src/core/rigid_body.cpp; extend it, but do not change what is
// here without updating its users.
#pragma once

#include <vector>

#include <Eigen/Geometry>

namespace attitude_propagator {

class RigidBody {
 public:
  /// Principal moments (kg m^2) along the body axes, so P = B.
  /// Throws std::invalid_argument naming the problem: non-finite, non-positive, or moments
  /// that break the triangle inequality (I_i <= I_j + I_k).
  static RigidBody fromPrincipalMoments(const Eigen::Vector3d& moments);

  /// A full symmetric inertia tensor in B, diagonalised with Eigen's SelfAdjointEigenSolver.
  /// Throws std::invalid_argument for a non-symmetric, non-finite or not positive definite
  /// tensor or one whose principal moments break the triangle inequality.
  static RigidBody fromTensor(const Eigen::Matrix3d& I_B);

  /// The `inertia` parameter: 3 values (principal, Ixx Iyy Izz) or 6 values
  /// (Ixx Iyy Izz Ixy Ixz Iyz). Throws std::invalid_argument for any other count and for the
  /// problems above.
  static RigidBody fromParameter(const std::vector<double>& values);

  /// Principal moments I1, I2, I3 in P.
  const Eigen::Vector3d& principalMoments() const { return moments_P_; }
  /// Rotation from principal coordinates to the user's body coordinates: x_B = q_BP x_P.
  const Eigen::Quaterniond& q_BP() const { return q_BP_; }
  /// Inertia tensor in the user's body frame.
  Eigen::Matrix3d tensor_B() const;

  bool isSphere(double rel_tol = 1e-12) const;
  /// True when two principal moments are equal (to rel_tol); axis() gives the symmetry axis.
  bool isSymmetric(double rel_tol = 1e-12) const;

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
  Eigen::Quaterniond q_BP_;
};

}  // namespace attitude_propagator
