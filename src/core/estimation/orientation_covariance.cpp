#include "attitude_propagator/estimation/orientation_covariance.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include "attitude_propagator/limits.h"
#include "attitude_propagator/numerics/quaternion.h"

namespace attitude_propagator {

namespace {

Eigen::Matrix3d skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0.0, -v.z(), v.y(),  //
      v.z(), 0.0, -v.x(),   //
      -v.y(), v.x(), 0.0;
  return m;
}

// Below this squared angle the closed-form coefficients (1 - cos t)/t^2 and (t - sin t)/t^3
// lose all their digits to cancellation; the series 1/2 - t^2/24 and 1/6 - t^2/120 are exact
// to round-off there (next terms ~ t^4/720 < 1e-22).
constexpr double kSmallAngleSquared = 1e-10;

}  // namespace

Eigen::Matrix3d rightJacobian(const Eigen::Vector3d& phi) {
  const double t2 = phi.squaredNorm();
  double a;  // (1 - cos t) / t^2
  double b;  // (t - sin t) / t^3
  if (t2 < kSmallAngleSquared) {
    a = 0.5 - t2 / 24.0;
    b = 1.0 / 6.0 - t2 / 120.0;
  } else {
    const double t = std::sqrt(t2);
    a = (1.0 - std::cos(t)) / t2;
    b = (t - std::sin(t)) / (t2 * t);
  }
  const Eigen::Matrix3d K = skew(phi);
  return Eigen::Matrix3d::Identity() - a * K + b * K * K;
}

Eigen::Matrix3d propagateOrientationCovariance(const Eigen::Matrix3d& P, double h,
                                               const Eigen::Vector3d& w_B,
                                               const Eigen::Matrix3d& R) {
  const Eigen::Vector3d phi = h * w_B;
  const Eigen::Matrix3d Phi = expMap(phi).toRotationMatrix().transpose();
  const Eigen::Matrix3d G = h * rightJacobian(phi);
  const Eigen::Matrix3d next = Phi * P * Phi.transpose() + G * R * G.transpose();
  return clampOrientationCovariance(next);
}

namespace {

/// Sylvester's criterion for semi-definiteness: every principal minor >= 0 (the 3 diagonal
/// entries, the 3 2x2 minors and the determinant).
bool principalMinorsNonNegative(const Eigen::Matrix3d& S) {
  if (!(S.diagonal().minCoeff() >= 0.0)) return false;
  for (int i = 0; i < 3; ++i) {
    const int j = (i + 1) % 3;
    if (!(S(i, i) * S(j, j) - S(i, j) * S(j, i) >= 0.0)) return false;
  }
  return S.determinant() >= 0.0;
}

/// The clamp of both public forms. With P_Bb given (the rows of the joint covariance that
/// belong to P), the clamped eigen-directions scale their correlations with it (below).
Eigen::Matrix3d clampWithCorrelations(const Eigen::Matrix3d& P, Eigen::Matrix3d* P_Bb) {
  const Eigen::Matrix3d ceiling = kMaxOrientationVariance * Eigen::Matrix3d::Identity();
  if (!P.allFinite()) {
    if (P_Bb) P_Bb->setZero();  // nothing is known of the attitude, nor of how it goes with b
    return ceiling;
  }
  Eigen::Matrix3d S = 0.5 * (P + P.transpose());
  // Semi-definite with trace <= ceiling: every eigenvalue is in [0, ceiling] already.
  if (principalMinorsNonNegative(S) && S.trace() <= kMaxOrientationVariance) return S;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(S);
  if (eigen.info() != Eigen::Success) {
    if (P_Bb) P_Bb->setZero();
    return ceiling;
  }
  const Eigen::Vector3d& lambda = eigen.eigenvalues();
  const Eigen::Vector3d clamped_lambda = lambda.cwiseMax(0.0).cwiseMin(kMaxOrientationVariance);
  const Eigen::Matrix3d& V = eigen.eigenvectors();
  if (P_Bb) {
    // S = V diag(lambda) V^T with lambda_i clamped to c_i: the joint covariance
    // [S P_Bb; P_Bb^T P_bb] goes through the congruence T = diag(A, I),
    //   A = V diag(s) V^T,  s_i = sqrt(c_i / lambda_i)  (0 where lambda_i < 0),
    // so A S A = V diag(c) V^T (the clamped S), P_Bb <- A P_Bb, P_bb unchanged. T P T^T is
    // semi-definite whenever P is, and the correlation of each eigen-direction v_i with each
    // bias component, v_i^T P_Bb e_j / sqrt(lambda_i P_bb,jj), is the same after (s_i cancels);
    // a direction lowered to zero variance has no correlation left. A = I + V diag(s - 1) V^T,
    // its unclamped directions' s_i - 1 = 0 exactly: only the clamped directions move P_Bb.
    Eigen::Vector3d s_minus_one = Eigen::Vector3d::Zero();
    for (int i = 0; i < 3; ++i) {
      if (clamped_lambda(i) == lambda(i)) continue;
      s_minus_one(i) = (lambda(i) > 0.0 ? std::sqrt(clamped_lambda(i) / lambda(i)) : 0.0) - 1.0;
    }
    *P_Bb += V * s_minus_one.asDiagonal() * (V.transpose() * *P_Bb);
  }
  const Eigen::Matrix3d clamped = V * clamped_lambda.asDiagonal() * V.transpose();
  S = 0.5 * (clamped + clamped.transpose());
  // The reconstruction rounds: keep the diagonal inside the range exactly.
  S.diagonal() = S.diagonal().cwiseMax(0.0).cwiseMin(kMaxOrientationVariance);
  return S;
}

}  // namespace

Eigen::Matrix3d clampOrientationCovariance(const Eigen::Matrix3d& P) {
  return clampWithCorrelations(P, nullptr);
}

Eigen::Matrix3d clampOrientationCovariance(const Eigen::Matrix3d& P, Eigen::Matrix3d& P_Bb) {
  return clampWithCorrelations(P, &P_Bb);
}

RateCovarianceCheck checkRateCovariance(const Eigen::Matrix3d& R) {
  if (!R.allFinite()) return RateCovarianceCheck::NonFinite;
  const double largest = R.cwiseAbs().maxCoeff();
  if (!((R - R.transpose()).cwiseAbs().maxCoeff() <= kCovarianceSymmetryTolerance * largest)) {
    return RateCovarianceCheck::NotSymmetric;
  }
  if (!(R.diagonal().minCoeff() >= 0.0)) return RateCovarianceCheck::NegativeVariance;
  if (!(R.diagonal().maxCoeff() <= kMaxRateVariance)) {
    return RateCovarianceCheck::VarianceTooLarge;
  }
  for (int i = 0; i < 3; ++i) {
    const int j = (i + 1) % 3;
    // Both entries, at the symmetry tolerance: R_ij^2 <= R_ii R_jj (1 + tol).
    const double r = std::max(std::abs(R(i, j)), std::abs(R(j, i)));
    if (!(r * r <= R(i, i) * R(j, j) * (1.0 + kCovarianceSymmetryTolerance))) {
      return RateCovarianceCheck::NotACovariance;
    }
  }
  return RateCovarianceCheck::Ok;
}

const char* rateCovarianceCheckName(RateCovarianceCheck check) {
  switch (check) {
    case RateCovarianceCheck::Ok:
      return "ok";
    case RateCovarianceCheck::NonFinite:
      return "non_finite";
    case RateCovarianceCheck::NotSymmetric:
      return "not_symmetric";
    case RateCovarianceCheck::NegativeVariance:
      return "negative_variance";
    case RateCovarianceCheck::VarianceTooLarge:
      return "variance_too_large";
    case RateCovarianceCheck::NotACovariance:
      return "not_a_covariance";
  }
  return "unknown";
}

Eigen::Matrix3d rotateCovariance(const Eigen::Matrix3d& P, const Eigen::Matrix3d& C) {
  return C * P * C.transpose();
}

}  // namespace attitude_propagator
