// Orientation covariance propagation against closed forms.
#include <cmath>

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include "attitude_propagator/orientation_covariance.h"
#include "attitude_propagator/quaternion.h"

namespace ap = attitude_propagator;

namespace {
constexpr double kEps = 1e-12;

Eigen::Matrix3d rotZ(double angle) {
  return Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitZ()).toRotationMatrix();
}
}  // namespace

// With no rate noise the error ellipsoid, fixed in space, is seen from the turning body:
// after time t at rate w about z, P(t) = Rz(-w t) P0 Rz(-w t)^T exactly, for any step size.
TEST(OrientationCovariance, TurnsWithTheBodyWithoutNoise) {
  const double w = 0.7, h = 0.01;
  const Eigen::Matrix3d P0 = Eigen::Vector3d(4.0, 1.0, 0.25).asDiagonal();
  Eigen::Matrix3d P = P0;
  for (int k = 0; k < 1000; ++k) {
    P = ap::propagateOrientationCovariance(P, h, Eigen::Vector3d(0, 0, w), Eigen::Matrix3d::Zero());
  }
  const Eigen::Matrix3d C = rotZ(-w * 1000 * h);
  const Eigen::Matrix3d expected = C * P0 * C.transpose();
  EXPECT_LT((P - expected).norm(), 1e3 * kEps) << P << "\nexpected\n" << expected;
  // Closed form of one entry: P_xy = (a - b) cos(wt) (-sin(wt)), a = 4, b = 1.
  const double c = std::cos(w * 10.0), s = std::sin(w * 10.0);
  EXPECT_NEAR(P(0, 1), -(4.0 - 1.0) * c * s, 1e3 * kEps);
}

// At rest the angle error is a random walk: n samples of rate noise sigma over steps h give
// P = n h^2 sigma^2 I.
TEST(OrientationCovariance, RandomWalkAtRest) {
  const double sigma = 0.02, h = 0.005;
  const Eigen::Matrix3d R = sigma * sigma * Eigen::Matrix3d::Identity();
  Eigen::Matrix3d P = Eigen::Matrix3d::Zero();
  const int n = 400;
  for (int k = 0; k < n; ++k) {
    P = ap::propagateOrientationCovariance(P, h, Eigen::Vector3d::Zero(), R);
  }
  const Eigen::Matrix3d expected = n * h * h * R;
  EXPECT_LT((P - expected).norm(), 1e-6 * expected.norm());
}

// Noise along the rotation axis is untouched by the turning (J_r phi = phi, Phi e_z = e_z):
// P_zz = n h^2 sigma_z^2 even while turning fast.
TEST(OrientationCovariance, NoiseAlongTheAxisAccumulatesExactly) {
  const double sigma = 0.1, h = 0.01, w = 5.0;
  Eigen::Matrix3d R = Eigen::Matrix3d::Zero();
  R(2, 2) = sigma * sigma;
  Eigen::Matrix3d P = Eigen::Matrix3d::Zero();
  for (int k = 0; k < 100; ++k) {
    P = ap::propagateOrientationCovariance(P, h, Eigen::Vector3d(0, 0, w), R);
  }
  EXPECT_NEAR(P(2, 2), 100 * h * h * sigma * sigma, 1e-15);
  EXPECT_NEAR(P(0, 0), 0.0, 1e-18);
  EXPECT_NEAR(P(0, 2), 0.0, 1e-18);
}

// J_r against its defining property: Exp(phi + d) = Exp(phi) Exp(J_r(phi) d) + O(|d|^2),
// checked by finite differences, including across the small-angle branch.
TEST(RightJacobian, MatchesFiniteDifferences) {
  const double d = 1e-7;
  for (const Eigen::Vector3d& phi :
       {Eigen::Vector3d(0.3, -1.2, 0.8), Eigen::Vector3d(1e-6, 2e-6, -1e-6),
        Eigen::Vector3d(2.5, 0.1, 0.0), Eigen::Vector3d::Zero().eval()}) {
    const Eigen::Matrix3d J = ap::rightJacobian(phi);
    for (int i = 0; i < 3; ++i) {
      const Eigen::Vector3d e = d * Eigen::Vector3d::Unit(i);
      const Eigen::Quaterniond lhs = ap::expMap(phi + e);
      const Eigen::Quaterniond rhs = ap::expMap(phi) * ap::expMap(J * e);
      EXPECT_LT(ap::rotationAngle(lhs, rhs), 1e-13) << "phi = " << phi.transpose();
    }
    // Along the axis the Jacobian is the identity.
    EXPECT_LT((J * phi - phi).norm(), 1e-15 + 1e-15 * phi.norm());
  }
}

TEST(OrientationCovariance, RotateIntoAnotherFrame) {
  const Eigen::Matrix3d P = Eigen::Vector3d(1.0, 2.0, 3.0).asDiagonal();
  const Eigen::Matrix3d C = rotZ(M_PI / 2);
  const Eigen::Matrix3d Q = ap::rotateCovariance(P, C);
  EXPECT_NEAR(Q(0, 0), 2.0, kEps);
  EXPECT_NEAR(Q(1, 1), 1.0, kEps);
  EXPECT_NEAR(Q(2, 2), 3.0, kEps);
}
