#include "attitude_propagator/numerics/rigid_body.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>

#include <Eigen/Eigenvalues>

#include "attitude_propagator/limits.h"

namespace attitude_propagator {

namespace {

// Relative slack on the triangle inequality and on the symmetry of a tensor: the moments of a
// flat lamina satisfy I3 = I1 + I2 exactly in theory, and a diagonalised tensor carries
// round-off of a few ulps of its largest entry.
constexpr double kRelativeSlack = 1e-12;

std::string describe(const Eigen::Vector3d& v) {
  std::ostringstream s;
  s.precision(17);
  s << "(" << v.x() << ", " << v.y() << ", " << v.z() << ")";
  return s.str();
}

void checkMoments(const Eigen::Vector3d& moments, bool triangle = true) {
  if (!moments.allFinite()) {
    throw std::invalid_argument("inertia: principal moments must be finite, got " +
                                describe(moments));
  }
  if (!(moments.minCoeff() > 0.0)) {
    throw std::invalid_argument(
        "inertia: principal moments must be positive (the tensor positive definite), got " +
        describe(moments));
  }
  if (!(moments.minCoeff() >= kMinInertia && moments.maxCoeff() <= kMaxInertia)) {
    // The door bound of limits.h: beyond it I |w|^2 and the closed forms' squares of I w may
    // leave the doubles.
    std::ostringstream range;
    range << "[" << kMinInertia << ", " << kMaxInertia << "]";
    throw std::invalid_argument("inertia: principal moments must lie in " + range.str() +
                                " kg m^2, got " + describe(moments));
  }
  if (!triangle) return;
  const double sum = moments.sum();
  for (int i = 0; i < 3; ++i) {
    // I_i <= I_j + I_k  <=>  2 I_i <= I1 + I2 + I3.
    if (2.0 * moments[i] > sum * (1.0 + kRelativeSlack)) {
      throw std::invalid_argument(
          "inertia: principal moments " + describe(moments) +
          " break the triangle inequality I_i <= I_j + I_k (no rigid body has them)");
    }
  }
}

}  // namespace

RigidBody::RigidBody(const Eigen::Vector3d& moments_P, const Eigen::Quaterniond& q_BP)
    : moments_P_(moments_P), inverse_moments_P_(moments_P.cwiseInverse()), q_BP_(q_BP) {}

RigidBody RigidBody::fromPrincipalMoments(const Eigen::Vector3d& moments,
                                          TriangleInequality triangle) {
  checkMoments(moments, triangle == TriangleInequality::Require);
  return RigidBody(moments, Eigen::Quaterniond::Identity());
}

RigidBody RigidBody::fromTensor(const Eigen::Matrix3d& I_B) {
  if (!I_B.allFinite()) {
    throw std::invalid_argument("inertia: the tensor must be finite");
  }
  const double scale = I_B.cwiseAbs().maxCoeff();
  if (!((I_B - I_B.transpose()).cwiseAbs().maxCoeff() <= kRelativeSlack * scale)) {
    throw std::invalid_argument("inertia: the tensor must be symmetric (Ixy = Iyx etc.)");
  }
  const Eigen::Matrix3d off_diagonal = I_B - Eigen::Matrix3d(I_B.diagonal().asDiagonal());
  if (off_diagonal.isZero(0.0)) return fromPrincipalMoments(I_B.diagonal());

  const Eigen::Matrix3d symmetric = 0.5 * (I_B + I_B.transpose());
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(symmetric);
  if (solver.info() != Eigen::Success) {
    throw std::invalid_argument("inertia: the tensor could not be diagonalised");
  }
  const Eigen::Vector3d& moments = solver.eigenvalues();
  checkMoments(moments);
  Eigen::Matrix3d C_BP = solver.eigenvectors();
  // Eigenvectors are defined up to sign: make the frame right-handed so that C_BP is a
  // rotation and q_BP a unit quaternion of it.
  if (C_BP.determinant() < 0.0) C_BP.col(2) = -C_BP.col(2);
  return RigidBody(moments, Eigen::Quaterniond(C_BP).normalized());
}

RigidBody RigidBody::fromParameter(const std::vector<double>& values) {
  if (values.size() == 3) {
    return fromPrincipalMoments(Eigen::Vector3d(values[0], values[1], values[2]));
  }
  if (values.size() == 6) {
    Eigen::Matrix3d I_B;
    I_B << values[0], values[3], values[4],  //
        values[3], values[1], values[5],     //
        values[4], values[5], values[2];
    return fromTensor(I_B);
  }
  throw std::invalid_argument(
      "inertia: expected 3 values (Ixx Iyy Izz) or 6 values (Ixx Iyy Izz Ixy Ixz Iyz), got " +
      std::to_string(values.size()));
}

Eigen::Matrix3d RigidBody::tensor_B() const {
  const Eigen::Matrix3d C_BP = q_BP_.toRotationMatrix();
  return C_BP * moments_P_.asDiagonal() * C_BP.transpose();
}

bool RigidBody::isSphere(double rel_tol) const {
  return moments_P_.maxCoeff() - moments_P_.minCoeff() <= rel_tol * moments_P_.maxCoeff();
}

bool RigidBody::isSymmetric(double rel_tol) const {
  const double tol = rel_tol * moments_P_.maxCoeff();
  const Eigen::Vector3d& I = moments_P_;
  return std::abs(I[0] - I[1]) <= tol || std::abs(I[1] - I[2]) <= tol ||
         std::abs(I[0] - I[2]) <= tol;
}

int RigidBody::symmetryAxis(double rel_tol) const {
  const double tol = rel_tol * moments_P_.maxCoeff();
  const Eigen::Vector3d& I = moments_P_;
  if (std::abs(I[0] - I[1]) <= tol) return 2;
  if (std::abs(I[1] - I[2]) <= tol) return 0;
  if (std::abs(I[0] - I[2]) <= tol) return 1;
  throw std::logic_error("RigidBody::symmetryAxis: the body is not symmetric");
}

std::array<int, 3> RigidBody::sortedAxes() const {
  std::array<int, 3> axes{0, 1, 2};
  std::stable_sort(axes.begin(), axes.end(),
                   [this](int a, int b) { return moments_P_[a] < moments_P_[b]; });
  return axes;
}

Eigen::Vector3d RigidBody::angularMomentum_B(const Eigen::Vector3d& w_B) const {
  const Eigen::Vector3d w_P = q_BP_.conjugate() * w_B;
  return q_BP_ * Eigen::Vector3d(moments_P_.cwiseProduct(w_P));
}

double RigidBody::kineticEnergy(const Eigen::Vector3d& w_B) const {
  const Eigen::Vector3d w_P = q_BP_.conjugate() * w_B;
  return 0.5 * w_P.dot(moments_P_.cwiseProduct(w_P));
}

Eigen::Vector3d RigidBody::angularMomentum_W(const Eigen::Quaterniond& q_WB,
                                             const Eigen::Vector3d& w_B) const {
  return q_WB * angularMomentum_B(w_B);
}

}  // namespace attitude_propagator
