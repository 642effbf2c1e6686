// Orientation covariance propagation against closed forms, against the linearised group map of
// the noise model, and against a Monte-Carlo estimate of that model.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/Geometry>

#include "attitude_propagator/estimation/orientation_covariance.h"
#include "attitude_propagator/numerics/quaternion.h"
#include "rotation_matchers.h"
#include "sampling.h"

namespace ap = attitude_propagator;

namespace {
Eigen::Matrix3d rotZ(double angle) {
  return Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitZ()).toRotationMatrix();
}

// Exp and Log of SO(3) through Eigen's angle-axis, not through the expMap/logMap the code uses.
Eigen::Quaterniond rotation(const Eigen::Vector3d& v) {
  const double angle = v.norm();
  if (angle == 0.0) return Eigen::Quaterniond::Identity();
  return Eigen::Quaterniond(Eigen::AngleAxisd(angle, v / angle));
}

Eigen::Vector3d rotationVector(const Eigen::Quaterniond& q) {
  const Eigen::AngleAxisd turn(q);
  return turn.angle() * turn.axis();
}

// The scene of the noise-model tests: a body turning fast (|w| h = 0.8 rad per sample) about
// an axis off all body axes, rate noise that is anisotropic and correlated and not aligned with
// the rate, and an initial error with correlations of its own. The bugs this scene is built to
// expose (J_r^T for J_r, Exp(h w) for its transpose) change P by many standard errors here.
struct NoisyTurn {
  Eigen::Vector3d w = Eigen::Vector3d(0.8, -0.5, 3.0);  // rad/s, body frame
  double h = 0.25;                                      // s per sample
  int samples = 6;
  Eigen::Matrix3d R;   // rate noise per sample, rad^2/s^2
  Eigen::Matrix3d P0;  // initial orientation error, rad^2

  NoisyTurn() {
    const Eigen::Vector3d sigma(0.02, 0.005, 0.012);
    Eigen::Matrix3d correlation;
    correlation << 1.0, 0.6, -0.4,  //
        0.6, 1.0, 0.3,              //
        -0.4, 0.3, 1.0;
    R = sigma.asDiagonal() * correlation * sigma.asDiagonal();
    P0 << 4.0, 1.5, -0.5,  //
        1.5, 2.0, 0.8,     //
        -0.5, 0.8, 1.0;
    P0 *= 1e-6;
  }

  Eigen::Matrix3d propagated() const {
    Eigen::Matrix3d P = P0;
    for (int k = 0; k < samples; ++k) P = ap::propagateOrientationCovariance(P, h, w, R);
    return P;
  }

  // The error model of orientation_covariance.h run forward: the true orientation starts at
  // Exp(dtheta_0) from the estimate and turns by Exp(h (w + n_k)) per sample, the estimate by
  // Exp(h w); the result is the body-frame error Log(q_est^c q_true).
  Eigen::Vector3d finalError(const Eigen::Vector3d& dtheta0,
                             const std::vector<Eigen::Vector3d>& noise) const {
    Eigen::Quaterniond q_est = Eigen::Quaterniond::Identity();
    Eigen::Quaterniond q_true = rotation(dtheta0);
    const Eigen::Quaterniond step = rotation(h * w);
    for (const Eigen::Vector3d& n : noise) {
      q_est = q_est * step;
      q_true = q_true * rotation(h * (w + n));
    }
    return rotationVector(q_est.conjugate() * q_true);
  }
};

// Three reproducible standard normal numbers (sampling.h).
Eigen::Vector3d standardNormal(std::uint64_t& state) {
  Eigen::Vector3d z;
  for (int i = 0; i < 3; ++i) z[i] = normalRandom(state);
  return z;
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
  // Measured 3.7e-13 after 1000 steps; bound 1.5e-12.
  EXPECT_LT((P - expected).norm(), 1.5e-12) << P << "\nexpected\n" << expected;
  // Closed form of one entry: P_xy = (a - b) cos(wt) (-sin(wt)), a = 4, b = 1. Measured
  // 1.4e-13; bound 5e-13.
  const double c = std::cos(w * 10.0), s = std::sin(w * 10.0);
  EXPECT_NEAR(P(0, 1), -(4.0 - 1.0) * c * s, 5e-13);
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
  // Measured 7.2e-15 of |P| after 400 steps; bound 3e-14.
  EXPECT_LT((P - expected).norm(), 3e-14 * expected.norm());
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

// The third of a turn about (1, 1, 1)/sqrt(3) maps x to y, y to z and z to x, so C P C^T is P
// with its indices shifted by one: (C P C^T)_ij = P_(i-1)(j-1), indices mod 3; the transposed
// rotation, C^T P C, would shift them the other way.
TEST(OrientationCovariance, RotateIntoAnotherFrame) {
  Eigen::Matrix3d P;
  P << 4.0, 1.5, -0.5,  //
      1.5, 2.0, 0.8,    //
      -0.5, 0.8, 1.0;
  const Eigen::Matrix3d C =
      Eigen::AngleAxisd(2.0 * M_PI / 3.0, Eigen::Vector3d(1, 1, 1).normalized()).toRotationMatrix();
  const Eigen::Matrix3d Q = ap::rotateCovariance(P, C);
  double largest_other_way = 0.0;  // how far the wrong rotation would land
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      // Measured 7.8e-16; bound 8 eps = 1.8e-15.
      EXPECT_NEAR(Q(i, j), P((i + 2) % 3, (j + 2) % 3), 8 * std::numeric_limits<double>::epsilon())
          << i << ", " << j;
      largest_other_way = std::max(
          largest_other_way, std::abs(P((i + 2) % 3, (j + 2) % 3) - P((i + 1) % 3, (j + 1) % 3)));
    }
  }
  ASSERT_GE(largest_other_way, 1.0);  // the case tells C P C^T from C^T P C
}

// The recursion against the linearisation of the noise model itself: the final error as a
// function of the initial error dtheta_0 and of every sample's rate noise n_k, differentiated by
// central differences through the group operations (Eigen's angle-axis). For the linear map
// e = A_0 dtheta_0 + sum_k A_k n_k the covariance is A_0 P0 A_0^T + sum_k A_k R A_k^T.
TEST(OrientationCovariance, MatchesTheLinearisedNoiseModel) {
  const NoisyTurn scene;
  // Step in rad and rad/s: the truncation error goes as d^2 and the round-off as eps/d; at
  // d = 1e-4 both stay near 1e-11 of P (1e-6: 5e-10, round-off; 1e-3: 2e-10, truncation).
  const double d = 1e-4;
  const std::vector<Eigen::Vector3d> quiet(scene.samples, Eigen::Vector3d::Zero());
  // Column i of the Jacobian of the final error with respect to input `slot` (-1: dtheta_0).
  auto column = [&](int slot, int i) {
    Eigen::Vector3d dtheta0 = Eigen::Vector3d::Zero();
    std::vector<Eigen::Vector3d> plus = quiet, minus = quiet;
    const Eigen::Vector3d e = d * Eigen::Vector3d::Unit(i);
    if (slot < 0) {
      return ((scene.finalError(e, quiet) - scene.finalError(-e, quiet)) / (2 * d)).eval();
    }
    plus[slot] += e;
    minus[slot] -= e;
    return ((scene.finalError(dtheta0, plus) - scene.finalError(dtheta0, minus)) / (2 * d)).eval();
  };
  auto jacobian = [&](int slot) {
    Eigen::Matrix3d A;
    for (int i = 0; i < 3; ++i) A.col(i) = column(slot, i);
    return A;
  };
  const Eigen::Matrix3d A0 = jacobian(-1);
  Eigen::Matrix3d expected = A0 * scene.P0 * A0.transpose();
  for (int k = 0; k < scene.samples; ++k) {
    const Eigen::Matrix3d A = jacobian(k);
    expected += A * scene.R * A.transpose();
  }
  const Eigen::Matrix3d P = scene.propagated();
  // Measured 6.2e-12 of |P|; bound 3e-11.
  EXPECT_LE((P - expected).norm(), 3e-11 * expected.norm()) << P << "\nexpected\n" << expected;
}

// The noise model sampled: N trajectories with the initial error and every sample's rate noise
// drawn from N(0, P0) and N(0, R). The sample second moment S of the final body-frame error
// estimates P entry by entry with standard error sqrt((P_ii P_jj + P_ij^2) / N) (the fourth
// moments of a Gaussian). The errors stay near 0.01 rad, where the model's linearisation is
// exact for this purpose: ten times the noise (a hundred times the nonlinear terms) moves S by
// under one standard error of 400000 trials.
TEST(OrientationCovariance, AgreesWithAMonteCarloEstimate) {
  const NoisyTurn scene;
  const int trials = 50000;  // relative standard error about 0.5 %
  const Eigen::Matrix3d L0 = scene.P0.llt().matrixL();
  const Eigen::Matrix3d LR = scene.R.llt().matrixL();
  std::uint64_t seed = 20240917;
  Eigen::Matrix3d S = Eigen::Matrix3d::Zero();
  std::vector<Eigen::Vector3d> noise(scene.samples);
  for (int trial = 0; trial < trials; ++trial) {
    const Eigen::Vector3d dtheta0 = L0 * standardNormal(seed);
    for (Eigen::Vector3d& n : noise) n = LR * standardNormal(seed);
    const Eigen::Vector3d e = scene.finalError(dtheta0, noise);
    S += e * e.transpose();
  }
  S /= trials;
  const Eigen::Matrix3d P = scene.propagated();
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      const double standard_error = std::sqrt((P(i, i) * P(j, j) + P(i, j) * P(i, j)) / trials);
      // Measured at most 3.1 standard errors with this seed (1.0 to 3.0 with five others);
      // bound 6, which a correct P exceeds with a chance of 2e-9 per entry.
      EXPECT_NEAR(S(i, j), P(i, j), 6.0 * standard_error) << i << ", " << j;
    }
  }
}
