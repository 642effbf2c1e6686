// Gravity and the magnetic field as measurements (docs/design.md §6.10, numerics.md §7.3):
// the measurement models against closed forms and finite differences, the gates on both sides
// of their thresholds, the alignment against the published tilt formulas, the observability of
// the bias, the attitude block clamped with its correlations, late samples against on-time ones,
// and the filter against a truth.
#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <optional>
#include <vector>

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>

#include "attitude_propagator/engine.h"
#include "attitude_propagator/estimation/attitude_fix.h"
#include "attitude_propagator/estimation/gravity_direction.h"
#include "attitude_propagator/estimation/magnetic_heading.h"
#include "attitude_propagator/estimation/orientation_covariance.h"
#include "attitude_propagator/numerics/quaternion.h"
#include "engine_fixtures.h"
#include "sampling.h"
#include "simulated_imu.h"

namespace {

namespace ap = attitude_propagator;
using engine_fixtures::at;
using engine_fixtures::Recorder;
using simulated_imu::kDeg;

constexpr double g = ap::kStandardGravity;

ap::Input imu(ap::Stamp stamp, const Eigen::Vector3d& w_B) {
  ap::Input input;
  input.source = ap::Source::Imu;
  input.stamp = stamp;
  input.value = w_B;
  return input;
}

Eigen::Quaterniond rpy(double roll, double pitch, double yaw) {
  return Eigen::Quaterniond(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
                            Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
                            Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()));
}

simulated_imu::Motion tumble();  // below, with the late samples
ap::EngineConfig aidedConfig();  // below, with the engine's tests

// A generic attitude: no axis lines up with the world's.
const Eigen::Quaterniond kGeneric = rpy(0.4, -0.7, 2.1);

// r(q_hat) ~= H dtheta for q_true = q_hat (x) Exp(dtheta): the Jacobian against the residual's
// own change, per axis, at a step where the second-order term is below the tolerance.
template <class M>
void expectJacobianMatchesResidual(const M& m, const Eigen::Quaterniond& truth) {
  const double d = 1e-6;
  for (int i = 0; i < 3; ++i) {
    const Eigen::Vector3d dtheta = d * (Eigen::Vector3d::Unit(i) + 0.3 * Eigen::Vector3d::Ones());
    const Eigen::Quaterniond estimate = truth * ap::expMap(-dtheta);
    const ap::Linearized l = m.linearize(estimate);
    EXPECT_LE((l.r - l.H * dtheta).norm(), 1e-10) << i;
    EXPECT_GE((l.H * dtheta).norm(), 1e-7) << i;  // the axis is seen (not only round-off)
  }
}

// ---- the measurement models ------------------------------------------------------------------

TEST(GravityDirection, TheResidualIsZeroAtTheTruthAndItsJacobianIsTheResidualsSlope) {
  const Eigen::Vector3d f_B = kGeneric.conjugate() * Eigen::Vector3d(0, 0, g);
  const ap::GravityDirection m(f_B, 0.01 * Eigen::Matrix3d::Identity(), ap::kAccelGate);
  EXPECT_LE(m.linearize(kGeneric).r.norm(), 1e-15);
  EXPECT_EQ(m.linearize(kGeneric).r.size(), 2);
  expectJacobianMatchesResidual(m, kGeneric);
  // A rotation about the body's up is not observed: H u = 0.
  const ap::Linearized l = m.linearize(kGeneric);
  EXPECT_LE((l.H * ap::bodyUp(kGeneric)).norm(), 1e-15);
}

TEST(GravityDirection, ItsNoiseIsTheForcesOverGSquaredInflatedByTheMagnitudesOffset) {
  const Eigen::Vector3d up(0, 0, 1);
  const double s = 0.05;
  const ap::GravityDirection at_g(g * up, s * s * Eigen::Matrix3d::Identity(), ap::kAccelGate);
  const ap::Linearized l = at_g.linearize(Eigen::Quaterniond::Identity());
  EXPECT_NEAR(l.R(0, 0), s * s / (g * g), 1e-18);
  EXPECT_NEAR(l.R(1, 1), s * s / (g * g), 1e-18);
  const double f = 1.05 * g;  // 5 % off g
  const ap::GravityDirection off(f * up, s * s * Eigen::Matrix3d::Identity(), ap::kAccelGate);
  EXPECT_NEAR(off.linearize(Eigen::Quaterniond::Identity()).R(0, 0), s * s / (f * f) + 0.05 * 0.05,
              1e-15);
}

// The heading's Jacobian is the residual's slope about every axis: 1 about the body's up (the
// heading itself), tan(dip) times a tilt about the field's horizontal direction, nothing about
// the axis across it.
TEST(MagneticHeading, TheResidualIsZeroAtTheTruthAndItsJacobianIsTheResidualsSlope) {
  const double declination = 0.2;
  const Eigen::Vector3d m_W = simulated_imu::earthField(48e-6, 1.1, declination);
  const Eigen::Vector3d m_B = kGeneric.conjugate() * m_W;
  const ap::MagneticHeading m(m_B, 1e-14 * Eigen::Matrix3d::Identity(), declination, ap::kMagGate);
  EXPECT_LE(std::abs(m.linearize(kGeneric).r(0)), 1e-12);
  expectJacobianMatchesResidual(m, kGeneric);
  const ap::Linearized l = m.linearize(kGeneric);
  const Eigen::Vector3d along_W = Eigen::Vector3d(m_W.x(), m_W.y(), 0).normalized();
  const Eigen::Vector3d along = kGeneric.conjugate() * along_W;
  const Eigen::Vector3d across = kGeneric.conjugate() * Eigen::Vector3d::UnitZ().cross(along_W);
  EXPECT_NEAR((l.H * ap::bodyUp(kGeneric))(0), 1.0, 1e-12);
  EXPECT_NEAR(std::abs((l.H * along)(0)), std::tan(1.1), 1e-12);
  EXPECT_LE(std::abs((l.H * across)(0)), 1e-12);
}

// rotationBetween, as its comment says: the rotation vector turns `from` onto `to` the shortest
// way (its axis normal to both, its angle acos(from . to)) for a generic pair, a right angle, a
// pair 1e-9 rad apart (the axis from a tiny cross product), parallel vectors (zero), and
// opposite ones, exactly and 1e-13 short of it (half a turn about an axis normal to `from`).
TEST(GravityDirection, RotationBetweenTurnsFromOntoToTheShortestWay) {
  const Eigen::Vector3d from = Eigen::Vector3d(0.3, -0.5, 0.8).normalized();
  const Eigen::Vector3d normal = ap::normalPlane(from).col(0);
  const std::vector<Eigen::Vector3d> tos = {
      Eigen::Vector3d(-0.6, 0.2, 0.4).normalized(),
      normal,
      ap::expMap(1e-9 * normal) * from,
      from,
      -from,
      (ap::expMap(1e-13 * normal) * -from).normalized(),
  };
  for (std::size_t i = 0; i < tos.size(); ++i) {
    const Eigen::Vector3d& to = tos[i];
    const Eigen::Vector3d phi = ap::rotationBetween(from, to);
    EXPECT_LE((ap::expMap(phi) * from - to).norm(), 1e-12) << i;
    EXPECT_NEAR(phi.norm(), std::acos(std::clamp(from.dot(to), -1.0, 1.0)), 1e-7) << i;
    EXPECT_LE(std::abs(phi.dot(from)), 1e-12) << i;
    EXPECT_LE(std::abs(phi.dot(to)), 1e-12) << i;
  }
  EXPECT_EQ(ap::rotationBetween(from, from), Eigen::Vector3d::Zero());
  EXPECT_NEAR(ap::rotationBetween(from, -from).norm(), M_PI, 1e-15);
}

// normalPlane: two orthonormal columns normal to u with u x e1 = e2, for u along each axis (where
// the least aligned axis is a tie) and generic.
TEST(GravityDirection, NormalPlaneIsARightHandedBasisNormalToU) {
  const std::vector<Eigen::Vector3d> us = {
      Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY(), -Eigen::Vector3d::UnitZ(),
      Eigen::Vector3d(0.3, -0.5, 0.8).normalized(), Eigen::Vector3d(1.0, 1.0, 1.0).normalized()};
  for (const Eigen::Vector3d& u : us) {
    const Eigen::Matrix<double, 3, 2> B = ap::normalPlane(u);
    EXPECT_LE((B.transpose() * B - Eigen::Matrix2d::Identity()).norm(), 1e-15) << u.transpose();
    EXPECT_LE((B.transpose() * u).norm(), 1e-15) << u.transpose();
    EXPECT_LE((u.cross(B.col(0)) - B.col(1)).norm(), 1e-15) << u.transpose();
  }
}

// An anisotropic force noise at a tilted estimate: the direction's noise is the force's across
// the predicted up, over |f|^2. With u = C_BW e_up and the force quiet across one horizontal axis,
// noisy across the other and very noisy along u, R's eigenvalues are the two across u only.
TEST(GravityDirection, AnAnisotropicNoiseCountsOnlyAcrossThePredictedUp) {
  const Eigen::Vector3d u = ap::bodyUp(kGeneric);
  const Eigen::Matrix<double, 3, 2> B = ap::normalPlane(u);
  const double a = 0.01, b = 0.09, along = 25.0;  // (m/s^2)^2
  const Eigen::Matrix3d cov = a * B.col(0) * B.col(0).transpose() +
                              b * B.col(1) * B.col(1).transpose() + along * u * u.transpose();
  // The sample 0.05 rad off the prediction: the noise is taken across u, not across f.
  const ap::GravityDirection m(g * (ap::expMap(0.05 * B.col(0)) * u), cov, ap::kAccelGate);
  const Eigen::Matrix2d R = m.linearize(kGeneric).R;
  const Eigen::Vector2d eig = Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(R).eigenvalues();
  EXPECT_NEAR(eig(0), a / (g * g), 1e-15);
  EXPECT_NEAR(eig(1), b / (g * g), 1e-15);
}

TEST(GravityDirection, ItsNoiseHoldsTheLinearAccelerationGivenPerAxisOverGSquared) {
  const double s = 0.05, lv = 1.5;  // m/s^2, (m/s^2)^2
  const ap::GravityDirection m(g * Eigen::Vector3d::UnitZ(), s * s * Eigen::Matrix3d::Identity(),
                               ap::kAccelGate, lv);
  const ap::Linearized l = m.linearize(Eigen::Quaterniond::Identity());
  EXPECT_NEAR(l.R(0, 0), s * s / (g * g) + lv / (g * g), 1e-15);
  EXPECT_NEAR(l.R(1, 1), s * s / (g * g) + lv / (g * g), 1e-15);
}

// A level body in a long turn: the centripetal acceleration grows to 3 m/s^2 over 2 s and lasts
// 12 s, so the accelerometer's direction leans 17 degrees for longer than kAccelRecovery.
// Without the linear acceleration's average the gate refuses the leaning samples until the
// recovery takes one as the truth: the tilt then is the lean. With it they count for little
// while the turn lasts, none is refused for long, and the gyro holds the tilt.
TEST(LinearAcceleration, WhileALongTurnLastsTheTiltStaysWithTheGyro) {
  auto run = [](double window) {
    ap::EngineConfig c = aidedConfig();
    c.aiding.linear_window = window;
    c.rate_stddev = 0.002;
    Recorder sink;
    ap::AttitudeEngine engine(c, sink);
    for (int k = 0; k <= 1600; ++k) {  // 2 s still, 2 s turning harder, 12 s held
      const double t = 0.01 * k;
      const Eigen::Vector3d f(3.0 * std::clamp((t - 2.0) / 2.0, 0.0, 1.0), 0.0, g);
      engine.submit(imu(at(t), Eigen::Vector3d::Zero()));
      engine.submitAcceleration(at(t), f, Eigen::Matrix3d::Zero());
    }
    return simulated_imu::tiltError(engine.state().q_WB, Eigen::Quaterniond::Identity());
  };
  const double with = run(ap::kLinearAccelerationWindow);
  const double without = run(0.0);
  EXPECT_GT(without, 5.0 * kDeg);
  EXPECT_LT(with, 0.25 * without);
}

TEST(MagneticHeading, TheResidualIsTheHeadingErrorAboutTheWorldsUp) {
  // The estimate turned 0.3 rad about the world's up from the truth: the residual turns it back.
  const Eigen::Vector3d m_W = simulated_imu::earthField(50e-6, 1.0, 0.0);
  const ap::MagneticHeading m(kGeneric.conjugate() * m_W, 1e-14 * Eigen::Matrix3d::Identity(), 0.0,
                              ap::kMagGate);
  const Eigen::Quaterniond estimate = engine_fixtures::aboutAxis({0, 0, 1}, 0.3) * kGeneric;
  EXPECT_NEAR(m.linearize(estimate).r(0), -0.3, 1e-12);
  // East of north: the field of a declination D read with D as the reference is no error.
  const ap::MagneticHeading east(kGeneric.conjugate() * simulated_imu::earthField(50e-6, 1.0, 0.3),
                                 1e-14 * Eigen::Matrix3d::Identity(), 0.3, ap::kMagGate);
  EXPECT_LE(std::abs(east.linearize(kGeneric).r(0)), 1e-12);
}

TEST(MagneticHeading, AnUpdateNeverMovesRollAndPitchWhateverTheCorrelations) {
  const Eigen::Vector3d m_W = simulated_imu::earthField(50e-6, 1.2, 0.0);
  // The truth 0.2 rad of heading and 0.1 rad of tilt away from the estimate.
  const Eigen::Quaterniond truth = rpy(0.1, 0.0, 0.2) * kGeneric;
  const ap::MagneticHeading m(truth.conjugate() * m_W, 1e-14 * Eigen::Matrix3d::Identity(), 0.0,
                              1e9);
  Eigen::Quaterniond q = kGeneric;
  ap::ErrorState e;
  Eigen::Matrix3d A;
  A << 0.3, 0.1, -0.2, 0.05, 0.2, 0.1, -0.1, 0.15, 0.4;
  e.P_B = A * A.transpose();  // strongly correlated axes
  const Eigen::Vector3d up_before = ap::bodyUp(q);
  ASSERT_TRUE(ap::fuseMeasurement(m, q, e).accepted);
  const Eigen::Vector3d up_after = ap::bodyUp(q);
  EXPECT_LE((up_after - up_before).norm(), 1e-12);
  EXPECT_GT(ap::rotationAngle(q, kGeneric), 1e-3);  // and the heading did move
}

TEST(AttitudeFix, AsAMeasurementItsResidualIsTheRotationVectorToTheFix) {
  const Eigen::Vector3d dtheta(0.01, -0.02, 0.03);
  const ap::AttitudeFix m(kGeneric * ap::expMap(dtheta), Eigen::Matrix3d::Identity(), 16.0);
  EXPECT_LE((m.linearize(kGeneric).r - dtheta).norm(), 1e-15);
  expectJacobianMatchesResidual(m, kGeneric * ap::expMap(dtheta));
}

// The heading's noise is the field's across its horizontal part: a field noisy along the
// horizontal field (and up) but quiet across it gives a quiet heading.
TEST(MagneticHeading, ItsNoiseIsTheFieldsAcrossTheHorizontalFieldOverItsSquare) {
  const double B = 50e-6, dip = 1.0;
  const Eigen::Vector3d m_W = simulated_imu::earthField(B, dip, 0.0);  // north: +y
  const double along = 4e-6, across = 0.5e-6, up = 3e-6;
  const Eigen::Matrix3d R_W = Eigen::Vector3d(across * across, along * along, up * up).asDiagonal();
  const Eigen::Matrix3d C = kGeneric.toRotationMatrix();
  const ap::MagneticHeading m(kGeneric.conjugate() * m_W, C.transpose() * R_W * C, 0.0,
                              ap::kMagGate);
  const double h = B * std::cos(dip);
  EXPECT_NEAR(m.linearize(kGeneric).R(0, 0), across * across / (h * h),
              1e-12 * across * across / (h * h));
}

// The error state seen from a quarter turn further along: dtheta_f = C(D)^T dtheta_k, so a
// covariance diag(1, 2, 3) about x, y, z is diag(2, 1, 3) after a quarter turn about z, the
// cross-covariance turns alike, the bias's stays; and back with D^-1.
TEST(ErrorState, MovingItAlongTheMotionTurnsItsAttitudeBlocksByTheMotion) {
  ap::ErrorState e;
  e.P_B = Eigen::Vector3d(1, 2, 3).asDiagonal();
  e.P_Bb << 0.1, 0, 0, 0, 0.2, 0, 0, 0, 0.3;
  e.P_bb = 0.5 * Eigen::Matrix3d::Identity();
  const Eigen::Quaterniond D = engine_fixtures::aboutAxis({0, 0, 1}, M_PI / 2);
  const ap::ErrorState f = ap::moveErrorState(e, D);
  EXPECT_LE((f.P_B - Eigen::Matrix3d(Eigen::Vector3d(2, 1, 3).asDiagonal())).norm(), 1e-15);
  Eigen::Matrix3d P_Bb;
  P_Bb << 0, 0.2, 0, -0.1, 0, 0, 0, 0, 0.3;  // C^T P_Bb with C the quarter turn
  EXPECT_LE((f.P_Bb - P_Bb).norm(), 1e-15);
  EXPECT_EQ(f.P_bb, e.P_bb);
  // From first principles, at a generic motion: an error v at t_k (the truth q_k (x) Exp(v))
  // moved along D is the error Log((q_k D)^-1 (q_k Exp(v) D)) at t_f; a covariance v v^T moves
  // to that error's outer product.
  const Eigen::Quaterniond Dg = engine_fixtures::aboutAxis({0.3, -0.5, 0.8}, 1.1);
  const Eigen::Vector3d v(1e-4, -2e-4, 0.5e-4);
  const Eigen::Vector3d v_f =
      ap::logMap((kGeneric * Dg).conjugate() * (kGeneric * ap::expMap(v) * Dg));
  ap::ErrorState single;
  single.P_B = v * v.transpose();
  EXPECT_LE((ap::moveErrorState(single, Dg).P_B - v_f * v_f.transpose()).norm(), 1e-15);
  const ap::ErrorState back = ap::moveErrorState(f, D.conjugate());
  EXPECT_LE((back.P_B - e.P_B).norm(), 1e-15);
  EXPECT_LE((back.P_Bb - e.P_Bb).norm(), 1e-15);
}

// ---- the attitude block clamped with its correlations ---------------------------------------

using Matrix6 = Eigen::Matrix<double, 6, 6>;

Matrix6 joint(const Eigen::Matrix3d& P_B, const Eigen::Matrix3d& P_Bb,
              const Eigen::Matrix3d& P_bb) {
  Matrix6 P;
  P << P_B, P_Bb, P_Bb.transpose(), P_bb;
  return P;
}

// A joint covariance built from its truth: in the attitude's eigen-directions V (variances
// lambda) and the bias axes (stddevs sigma_b), Sigma = D C D with D = diag(sqrt(lambda),
// sigma_b) and C a correlation matrix, so P = diag(V, I) Sigma diag(V, I)^T.
struct JointTruth {
  Eigen::Matrix3d V;
  Eigen::Vector3d lambda;
  Eigen::Vector3d sigma_b;
  Matrix6 C;

  Matrix6 covariance() const {
    Eigen::Matrix<double, 6, 1> d;
    d << lambda.cwiseSqrt(), sigma_b;
    Matrix6 T = Matrix6::Identity();
    T.topLeftCorner<3, 3>() = V;
    return T * d.asDiagonal() * C * d.asDiagonal() * T.transpose();
  }
};

JointTruth genericJoint(const Eigen::Vector3d& lambda) {
  JointTruth t;
  t.V = engine_fixtures::aboutAxis({0.3, -0.5, 0.8}, 1.1).toRotationMatrix();
  t.lambda = lambda;
  t.sigma_b = Eigen::Vector3d(0.01, 0.02, 0.015);
  // C = [I R; R^T R^T R + D], D = I - diag(R^T R) >= 0 (R's columns shorter than 1): unit
  // diagonal, the attitude's directions uncorrelated among themselves (V and lambda are the
  // attitude block's eigen-decomposition), and the Schur complement D semi-definite.
  Eigen::Matrix3d R;
  R << 0.5, -0.2, 0.3,  //
      0.1, 0.6, -0.4,   //
      -0.3, 0.2, 0.7;
  const Eigen::Matrix3d RtR = R.transpose() * R;
  t.C.setIdentity();
  t.C.topRightCorner<3, 3>() = R;
  t.C.bottomLeftCorner<3, 3>() = R.transpose();
  t.C.bottomRightCorner<3, 3>() = RtR;
  t.C.bottomRightCorner<3, 3>().diagonal().setOnes();
  return t;
}

// The error state whose joint covariance is P (the bias estimate zero).
ap::ErrorState errorStateOf(const Matrix6& P) {
  ap::ErrorState e;
  e.P_B = P.topLeftCorner<3, 3>();
  e.P_Bb = P.topRightCorner<3, 3>();
  e.P_bb = P.bottomRightCorner<3, 3>();
  return e;
}

// A rate noise per sample (rad^2/s^2) with unequal variances and correlated axes.
Eigen::Matrix3d anisotropicRateNoise() {
  Eigen::Matrix3d R;
  R << 4e-6, 1e-6, 0.0, 1e-6, 9e-6, -2e-6, 0.0, -2e-6, 1e-6;
  return R;
}

double smallestEigenvalue(const Matrix6& P) {
  return Eigen::SelfAdjointEigenSolver<Matrix6>(P).eigenvalues().minCoeff();
}

// An eigenvalue of the attitude block above the cap is lowered to it and its correlations with
// the bias stay what they were: the result is the joint covariance built from the same truth
// with that variance at the cap. The joint matrix stays symmetric and semi-definite.
TEST(ClampedCovariance, AClampedDirectionKeepsItsCorrelationsWithTheBias) {
  const double cap = ap::kMaxOrientationVariance;
  const JointTruth before = genericJoint({0.02, 0.3, 1.5 * cap});
  const Matrix6 P = before.covariance();
  Eigen::Matrix3d P_Bb = P.topRightCorner<3, 3>();
  const Eigen::Matrix3d P_B = ap::clampOrientationCovariance(P.topLeftCorner<3, 3>(), P_Bb);
  JointTruth after = before;
  after.lambda.z() = cap;
  const Matrix6 expected = after.covariance();
  const double scale = cap;
  EXPECT_LE((P_B - expected.topLeftCorner<3, 3>()).norm(), 1e-13 * scale);
  EXPECT_LE((P_Bb - expected.topRightCorner<3, 3>()).norm(), 1e-13 * scale);
  const Matrix6 clamped = joint(P_B, P_Bb, P.bottomRightCorner<3, 3>());
  EXPECT_EQ(P_B, P_B.transpose());  // the joint matrix symmetric: P_Bb appears on both sides
  EXPECT_GE(smallestEigenvalue(clamped), -1e-15 * scale);
  // The correlation coefficients, direction by direction, from the clamped matrix.
  for (int i = 0; i < 3; ++i) {
    const Eigen::Vector3d v = before.V.col(i);
    for (int j = 0; j < 3; ++j) {
      const double rho = v.dot(P_Bb.col(j)) / std::sqrt(v.dot(P_B * v) * P(3 + j, 3 + j));
      EXPECT_NEAR(rho, before.C(i, 3 + j), 1e-12) << i << " " << j;
    }
  }
  // And the same scene with a negative eigenvalue (round-off's kind): raised to zero, that
  // direction has no correlation left, the others are kept.
  JointTruth negative = genericJoint({0.02, 0.3, 0.5});
  Matrix6 Pn = negative.covariance();
  const Eigen::Vector3d v0 = negative.V.col(0);
  Pn.topLeftCorner<3, 3>() -= 0.03 * v0 * v0.transpose();  // lambda_0 = -0.01
  Eigen::Matrix3d P_Bb_n = Pn.topRightCorner<3, 3>();
  const Eigen::Matrix3d P_B_n = ap::clampOrientationCovariance(Pn.topLeftCorner<3, 3>(), P_Bb_n);
  EXPECT_LE(std::abs(v0.dot(P_B_n * v0)), 1e-15);
  EXPECT_LE((P_Bb_n.transpose() * v0).norm(), 1e-15);
  for (int i = 1; i < 3; ++i) {
    const Eigen::Vector3d v = negative.V.col(i);
    EXPECT_LE((P_Bb_n.transpose() * v - Pn.topRightCorner<3, 3>().transpose() * v).norm(), 1e-15);
  }
  EXPECT_GE(smallestEigenvalue(joint(P_B_n, P_Bb_n, Pn.bottomRightCorner<3, 3>())), -1e-15);
}

// Nothing to clamp: the cross-covariance is left bit for bit, whether the quick test lets the
// matrix through (trace within the cap) or the eigen-decomposition runs and finds every
// eigenvalue within the bounds (trace beyond the cap, no eigenvalue beyond it).
TEST(ClampedCovariance, AnUnclampedBlockLeavesTheCrossCovarianceBitForBit) {
  for (const Eigen::Vector3d& lambda :
       {Eigen::Vector3d(0.02, 0.3, 0.5),
        Eigen::Vector3d(0.02, 3.0, 0.9 * ap::kMaxOrientationVariance)}) {
    const Matrix6 P = genericJoint(lambda).covariance();
    const Eigen::Matrix3d P_B =
        0.5 * (P.topLeftCorner<3, 3>() + P.topLeftCorner<3, 3>().transpose());
    const Eigen::Matrix3d P_Bb_before = P.topRightCorner<3, 3>();
    Eigen::Matrix3d P_Bb = P_Bb_before;
    const Eigen::Matrix3d clamped = ap::clampOrientationCovariance(P_B, P_Bb);
    EXPECT_EQ(P_Bb, P_Bb_before) << lambda.transpose();
    EXPECT_EQ(clamped, ap::clampOrientationCovariance(P_B)) << lambda.transpose();
    if (lambda.sum() <= ap::kMaxOrientationVariance) {
      EXPECT_EQ(clamped, P_B);
    }
  }
  // Not finite: the attitude unknown, no correlation left.
  Eigen::Matrix3d P_Bb = Eigen::Matrix3d::Constant(0.1);
  Eigen::Matrix3d P_B = Eigen::Matrix3d::Identity();
  P_B(1, 1) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(ap::clampOrientationCovariance(P_B, P_Bb),
            ap::kMaxOrientationVariance * Eigen::Matrix3d::Identity());
  EXPECT_EQ(P_Bb, Eigen::Matrix3d::Zero());
}

// The heading's variance one ulp below the cap, at it, and above it (the tilt's small, so the
// trace is beyond the cap and the eigen-decomposition runs in all three): below and at, the
// cross-covariance is left bit for bit; above, the heading's row is scaled by sqrt(cap / v) and
// the others stay.
TEST(ClampedCovariance, TheHeadingJustBelowAtAndAboveTheCap) {
  const double cap = ap::kMaxOrientationVariance;
  Eigen::Matrix3d P_Bb_before;
  P_Bb_before << 1e-4, -2e-4, 0.5e-4,  //
      3e-4, 1e-4, -1e-4,               //
      -2e-3, 1e-3, 4e-3;
  const Eigen::Matrix3d P_bb = 1e-4 * Eigen::Matrix3d::Identity();
  for (const double v : {std::nextafter(cap, 0.0), cap, cap * (1.0 + 1e-6), 4.0 * cap}) {
    Eigen::Matrix3d P = Eigen::Vector3d(1e-3, 2e-3, v).asDiagonal();
    Eigen::Matrix3d P_Bb = P_Bb_before;
    const Eigen::Matrix3d P_B = ap::clampOrientationCovariance(P, P_Bb);
    EXPECT_EQ(P_B(2, 2), std::min(v, cap)) << v;
    if (v <= cap) {
      EXPECT_EQ(P_Bb, P_Bb_before) << v;
    } else {
      const double s = std::sqrt(cap / v);
      EXPECT_LE((P_Bb.row(2) - s * P_Bb_before.row(2)).norm(), 1e-15 * P_Bb_before.row(2).norm())
          << v;
      EXPECT_LE((P_Bb.topRows<2>() - P_Bb_before.topRows<2>()).norm(), 1e-18) << v;
      EXPECT_LT(P_Bb.row(2).norm(), P_Bb_before.row(2).norm()) << v;
    }
    EXPECT_GE(smallestEigenvalue(joint(P_B, P_Bb, P_bb)), -1e-15 * cap) << v;
  }
}

// ---- the gates, on both sides ----------------------------------------------------------------

// P = p^2 I and an isotropic force noise: S = (p^2 + (s/g)^2) I, and d2 = angle^2 / that.
TEST(Gates, AGravityDirectionJustInsideTheGateIsFusedJustOutsideItIsNot) {
  const double s = 0.1;
  const double p = 0.01;
  const double sigma = std::sqrt(p * p + s * s / (g * g));
  for (double ratio : {0.999, 1.001}) {
    const double angle = std::sqrt(ratio * ap::kAccelGate) * sigma;
    const Eigen::Vector3d f_B = g * Eigen::Vector3d(std::sin(angle), 0.0, std::cos(angle));
    const ap::GravityDirection m(f_B, s * s * Eigen::Matrix3d::Identity(), ap::kAccelGate);
    Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
    ap::ErrorState e;
    e.P_B = p * p * Eigen::Matrix3d::Identity();
    const ap::UpdateResult r = ap::fuseMeasurement(m, q, e);
    EXPECT_NEAR(r.d2, ratio * ap::kAccelGate, 1e-9 * ap::kAccelGate);
    EXPECT_EQ(r.accepted, ratio < 1.0) << ratio;
    EXPECT_EQ(q.coeffs() == Eigen::Quaterniond::Identity().coeffs(), ratio > 1.0) << ratio;
    EXPECT_EQ(e.P_B == p * p * Eigen::Matrix3d::Identity(), ratio > 1.0) << ratio;
  }
}

TEST(Gates, AHeadingJustInsideTheGateIsFusedJustOutsideItIsNot) {
  const double B = 50e-6;
  const double s = 1e-6;
  const double dip = 1.0;
  const double p = 0.01;
  // S = H P H^T + R: |H|^2 = 1 + tan^2(dip) (the heading and a tilt about the field's
  // horizontal direction), R across the horizontal field.
  const double sigma = std::hypot(p / std::cos(dip), s / (B * std::cos(dip)));
  for (double ratio : {0.999, 1.001}) {
    const double angle = std::sqrt(ratio * ap::kMagGate) * sigma;
    const Eigen::Quaterniond truth = engine_fixtures::aboutAxis({0, 0, 1}, angle);
    const ap::MagneticHeading m(truth.conjugate() * simulated_imu::earthField(B, dip, 0.0),
                                s * s * Eigen::Matrix3d::Identity(), 0.0, ap::kMagGate);
    Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
    ap::ErrorState e;
    e.P_B = p * p * Eigen::Matrix3d::Identity();
    const ap::UpdateResult r = ap::fuseMeasurement(m, q, e);
    EXPECT_NEAR(r.d2, ratio * ap::kMagGate, 1e-6 * ap::kMagGate) << ratio;
    EXPECT_EQ(r.accepted, ratio < 1.0) << ratio;
  }
}

// ---- the engine: alignment, magnitude rule, recovery -----------------------------------------

ap::EngineConfig aidedConfig() {
  ap::EngineConfig c = engine_fixtures::kinematicConfig();
  c.kinematic.integrator = ap::Integrator::Exp2;
  c.rate_stddev = 1e-3;
  c.aiding.use_accel = true;
  c.aiding.align = true;
  c.aiding.accel_stddev = 0.05;
  return c;
}

// The field on (0.3 uT of noise) and the attitude given rather than aligned.
ap::EngineConfig fieldConfig() {
  ap::EngineConfig c = aidedConfig();
  c.aiding.align = false;
  c.aiding.use_mag = true;
  c.aiding.mag_stddev = 0.3e-6;
  return c;
}

// The published tilt from one static sample (docs/numerics.md §7.3): roll atan2(f_y, f_z),
// pitch atan2(-f_x, sqrt(f_y^2 + f_z^2)).
TEST(Alignment, TheFirstGravitySampleSetsRollAndPitchAsThePublishedFormulas) {
  struct Case {
    Eigen::Vector3d f;
    double roll, pitch;
  };
  const double r = 0.3, p = 0.2;
  for (const Case& c :
       {Case{{0, 0, g}, 0, 0}, Case{{0, g * std::sin(r), g * std::cos(r)}, r, 0},
        Case{{-g * std::sin(p), 0, g * std::cos(p)}, 0, p},
        Case{rpy(-0.5, 0.35, 0).conjugate() * Eigen::Vector3d(0, 0, g), -0.5, 0.35}}) {
    Recorder sink;
    ap::AttitudeEngine engine(aidedConfig(), sink);
    engine.submit(imu(at(0.0), Eigen::Vector3d::Zero()));
    EXPECT_EQ(engine.submitAcceleration(at(0.0), c.f, Eigen::Matrix3d::Zero()),
              ap::AidingOutcome::Aligned);
    // Roll and pitch (z-y-x angles) depend on the world's up in the body alone, R's last row.
    const Eigen::Matrix3d R = engine.state().q_WB.toRotationMatrix();
    EXPECT_NEAR(std::atan2(R(2, 1), R(2, 2)), c.roll, 1e-12) << c.f.transpose();
    EXPECT_NEAR(std::asin(-R(2, 0)), c.pitch, 1e-12) << c.f.transpose();
    EXPECT_EQ(engine.counters().accel.aligned, 1u);
  }
}

// What the covariance says after the alignment: the tilt as well known as one sample says, the
// heading unknown (pi^2 about the body's up).
TEST(Alignment, TheCovarianceSaysTheTiltIsKnownAndTheHeadingIsNot) {
  Recorder sink;
  ap::AttitudeEngine engine(aidedConfig(), sink);
  const Eigen::Quaterniond truth = rpy(0.3, -0.2, 0.0);
  engine.submit(imu(at(0.0), Eigen::Vector3d::Zero()));
  engine.submitAcceleration(at(0.0), truth.conjugate() * Eigen::Vector3d(0, 0, g),
                            Eigen::Matrix3d::Zero());
  const Eigen::Matrix3d P = engine.state().P_B;
  const Eigen::Vector3d u = ap::bodyUp(engine.state().q_WB);
  const Eigen::Matrix<double, 3, 2> B = ap::normalPlane(u);
  const double tilt = 0.05 * 0.05 / (g * g);
  EXPECT_NEAR(u.dot(P * u), ap::kMaxOrientationVariance, 1e-9);
  EXPECT_LE(((B.transpose() * P * B) - tilt * Eigen::Matrix2d::Identity()).norm(), 1e-9 * tilt);
}

TEST(Alignment, AFieldSampleBeforeTheTiltIsKnownIsNotUsedAfterItTheHeadingIs) {
  ap::EngineConfig c = aidedConfig();
  c.aiding.use_mag = true;
  c.aiding.mag_stddev = 0.2e-6;
  Recorder sink;
  ap::AttitudeEngine engine(c, sink);
  const Eigen::Quaterniond truth = rpy(0.2, 0.1, 1.3);
  const Eigen::Vector3d m_W = simulated_imu::earthField(50e-6, 1.0, 0.0);
  engine.submit(imu(at(0.0), Eigen::Vector3d::Zero()));
  EXPECT_EQ(engine.submitMagneticField(at(0.0), truth.conjugate() * m_W, Eigen::Matrix3d::Zero()),
            ap::AidingOutcome::NotAligned);
  engine.submitAcceleration(at(0.0), truth.conjugate() * Eigen::Vector3d(0, 0, g),
                            Eigen::Matrix3d::Zero());
  EXPECT_EQ(engine.submitMagneticField(at(0.0), truth.conjugate() * m_W, Eigen::Matrix3d::Zero()),
            ap::AidingOutcome::Accepted);
  // The heading was unknown (pi^2): the gain is pi^2 / (pi^2 + R), the residual of 1.3 rad
  // taken but for a part R / pi^2 ~ 6e-6 of it.
  EXPECT_LE(ap::rotationAngle(engine.state().q_WB, truth), 2e-5);
  EXPECT_EQ(engine.counters().mag.not_aligned, 1u);
  // The heading is now as well known as the field says.
  const Eigen::Vector3d u = ap::bodyUp(engine.state().q_WB);
  EXPECT_LT(u.dot(engine.state().P_B * u), 1e-3);
}

TEST(MagnitudeRule, ASampleOffGByMoreThanTheToleranceIsLinearAccelerationAndNotUsed) {
  for (double scale :
       {1.0 + 0.999 * ap::kAccelMagnitudeTolerance, 1.0 + 1.001 * ap::kAccelMagnitudeTolerance,
        1.0 - 1.001 * ap::kAccelMagnitudeTolerance}) {
    Recorder sink;
    ap::AttitudeEngine engine(aidedConfig(), sink);
    engine.submit(imu(at(0.0), Eigen::Vector3d::Zero()));
    const ap::AidingOutcome o = engine.submitAcceleration(
        at(0.0), scale * g * Eigen::Vector3d(0, 0.1, 1).normalized(), Eigen::Matrix3d::Zero());
    const bool inside = std::abs(scale - 1.0) < ap::kAccelMagnitudeTolerance;
    EXPECT_EQ(o, inside ? ap::AidingOutcome::Aligned : ap::AidingOutcome::RejectedMagnitude)
        << scale;
    EXPECT_EQ(engine.counters().accel.rejected_magnitude, inside ? 0u : 1u);
  }
}

TEST(Invalid, NonFiniteZeroOrBadCovarianceSamplesAreCountedAndChangeNothing) {
  ap::EngineConfig c = aidedConfig();
  c.aiding.use_mag = true;
  Recorder sink;
  ap::AttitudeEngine engine(c, sink);
  engine.submit(imu(at(0.0), Eigen::Vector3d::Zero()));
  const Eigen::Vector3d nan(std::nan(""), 0, 0);
  Eigen::Matrix3d asymmetric = Eigen::Matrix3d::Identity();
  asymmetric(0, 1) = 0.5;
  EXPECT_EQ(engine.submitAcceleration(at(0.0), nan, Eigen::Matrix3d::Zero()),
            ap::AidingOutcome::Invalid);
  EXPECT_EQ(engine.submitAcceleration(at(0.0), Eigen::Vector3d::Zero(), Eigen::Matrix3d::Zero()),
            ap::AidingOutcome::Invalid);
  EXPECT_EQ(engine.submitAcceleration(at(0.0), {0, 0, g}, asymmetric), ap::AidingOutcome::Invalid);
  EXPECT_EQ(engine.submitMagneticField(at(0.0), nan, Eigen::Matrix3d::Zero()),
            ap::AidingOutcome::Invalid);
  EXPECT_EQ(engine.counters().accel.invalid, 3u);
  EXPECT_EQ(engine.counters().mag.invalid, 1u);
  EXPECT_FALSE(engine.tiltKnown());
}

TEST(Off, WithoutUseAccelOrUseMagSamplesAreIgnoredAndNotCounted) {
  Recorder sink;
  ap::AttitudeEngine engine(engine_fixtures::kinematicConfig(), sink);
  engine.submit(imu(at(0.0), Eigen::Vector3d::Zero()));
  EXPECT_EQ(engine.submitAcceleration(at(0.0), {0, 1, g}, Eigen::Matrix3d::Zero()),
            ap::AidingOutcome::Off);
  EXPECT_EQ(engine.submitMagneticField(at(0.0), {1e-5, 0, 0}, Eigen::Matrix3d::Zero()),
            ap::AidingOutcome::Off);
  EXPECT_EQ(engine.state().q_WB.coeffs(), Eigen::Quaterniond::Identity().coeffs());
  EXPECT_EQ(engine.counters().accel.rejected_gate + engine.counters().accel.accepted, 0u);
}

TEST(Configuration, TheDynamicModelAndAbsurdValuesAreRefusedNamingTheSetting) {
  ap::EngineConfig c = engine_fixtures::torqueConfig();
  c.aiding.use_accel = true;
  Recorder sink;
  try {
    ap::AttitudeEngine engine(c, sink);
    FAIL() << "accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("use_accel"), std::string::npos) << e.what();
  }
  for (double bad : {0.0, -1.0, std::nan(""), 1e9}) {
    ap::EngineConfig k = aidedConfig();
    k.aiding.accel_stddev = bad;
    EXPECT_THROW(ap::AttitudeEngine(k, sink), std::invalid_argument) << bad;
    k = aidedConfig();
    k.aiding.mag_stddev = bad;
    EXPECT_THROW(ap::AttitudeEngine(k, sink), std::invalid_argument) << bad;
  }
  ap::EngineConfig d = aidedConfig();
  d.aiding.declination = 4.0;
  EXPECT_THROW(ap::AttitudeEngine(d, sink), std::invalid_argument);
}

// A gate that rejects for kMagRecovery seconds ends in one sample applied as a reset: a heading
// that was wrong (here: the estimate pinned 40 degrees off, with a tiny covariance) is set
// right; before that time, nothing is.
TEST(Recovery, AfterTheRecoveryTimeOfRejectionsTheNextSampleResetsTheHeading) {
  ap::EngineConfig c = fieldConfig();
  c.aiding.use_accel = false;
  c.rate_stddev = 1e-9;
  Recorder sink;
  ap::AttitudeEngine engine(c, sink);
  const Eigen::Quaterniond wrong = rpy(0, 0, 40 * kDeg);
  ASSERT_EQ(engine.setState(at(0.0), wrong, Eigen::Vector3d::Zero()), "");
  const Eigen::Vector3d m = simulated_imu::earthField(50e-6, 1.0, 0.0);
  const double h = 0.1;
  const int n = static_cast<int>(std::lround(ap::kMagRecovery / h));
  for (int k = 1; k <= n + 1; ++k) {
    engine.submit(imu(at(k * h), Eigen::Vector3d::Zero()));
    const ap::AidingOutcome o = engine.submitMagneticField(at(k * h), m, Eigen::Matrix3d::Zero());
    // The first rejection at k = 1; kMagRecovery s later, at k = n + 1, the reset.
    EXPECT_EQ(o, k <= n ? ap::AidingOutcome::RejectedGate : ap::AidingOutcome::Recovered) << k;
  }
  EXPECT_LE(ap::rotationAngle(engine.state().q_WB, Eigen::Quaterniond::Identity()), 1e-9);
  EXPECT_EQ(engine.counters().mag.rejected_gate, static_cast<std::uint64_t>(n));
  EXPECT_EQ(engine.counters().mag.recovered, 1u);
}

TEST(Recovery, ARunEndsAfterItsTimeExactlyAndAnAcceptanceStartsItAgain) {
  ap::RejectionRun run;
  EXPECT_FALSE(run.rejected(at(1.0), 10.0));
  EXPECT_FALSE(run.rejected(at(11.0) - 1, 10.0));
  EXPECT_TRUE(run.rejected(at(11.0), 10.0));
  EXPECT_FALSE(run.rejected(at(12.0), 10.0));  // a new run
  run.accepted();
  EXPECT_FALSE(run.rejected(at(21.0), 10.0));
  EXPECT_FALSE(run.rejected(at(30.0), 10.0));
}

// Linear acceleration that lasts (a turn, a braking) is noise on the gravity direction while it
// lasts: the average of the unexplained part over the window, less the sensor's noise, spread
// over the three axes; a single sample far off moves the average by its share of the window only.
TEST(LinearAcceleration, ALastingAccelerationIsAveragedOverTheWindowASingleOneIsNot) {
  ap::LinearAcceleration seen;
  const Eigen::Vector3d a(3.0, 0.0, 0.0);  // 3 m/s^2 unexplained
  ap::LinearVariance v;
  for (int k = 0; k <= 500; ++k) v = seen.observe(at(0.01 * k), a, 0.0);
  const double lasting = 9.0 / 3.0 * (1.0 - std::exp(-5.0 / ap::kLinearAccelerationWindow));
  EXPECT_NEAR(v.direction, lasting, 1e-6);
  EXPECT_NEAR(v.spread, lasting, 1e-6);
  ap::LinearAcceleration once;
  for (int k = 0; k < 100; ++k) once.observe(at(0.01 * k), Eigen::Vector3d::Zero(), 0.0);
  const ap::LinearVariance bump = once.observe(at(1.0), Eigen::Vector3d(30.0, 0, 0), 0.0);
  const double share = 900.0 / 3.0 * (1.0 - std::exp(-0.01 / ap::kLinearAccelerationWindow));
  EXPECT_NEAR(bump.direction, share, 1e-9);
  EXPECT_NEAR(bump.spread, share, 1e-9);
  // The sensor's own noise is no acceleration.
  ap::LinearAcceleration noise;
  for (int k = 0; k <= 500; ++k) v = noise.observe(at(0.01 * k), Eigen::Vector3d(0.1, 0, 0), 0.03);
  EXPECT_EQ(v.direction, 0.0);
  EXPECT_EQ(v.spread, 0.0);
}

// The lasting disagreement (TiltDisagreement): the horizontal part of the measured up in the
// world, the first sample whole, the plain mean of the samples until the window weighs less
// (+h then -h: none), then an exponential window over the stamps (a disagreement that stops
// fades by e^-1 a window later); reset forgets it.
TEST(TiltDisagreement, TheFirstSampleCountsWholeThenTheMeanThenTheWindow) {
  const Eigen::Vector3d h(0.06, -0.08, 0.0);  // |h| = 0.1
  const Eigen::Vector3d up = Eigen::Vector3d::UnitZ();
  auto measured = [&](const Eigen::Vector3d& horizontal) {
    return (up + horizontal).normalized();  // a unit up leaning by the horizontal part
  };
  ap::TiltDisagreement d;
  d.observe(at(0.0), measured(h));
  EXPECT_NEAR(d.variance(), measured(h).head<2>().squaredNorm(), 1e-15);
  d.observe(at(0.01), measured(-h));
  EXPECT_NEAR(d.variance(), 0.0, 1e-15);
  ap::TiltDisagreement lasting;
  int k = 0;
  for (; k <= 100 * 60; ++k) lasting.observe(at(0.01 * k), measured(h));
  const double lean = measured(h).head<2>().squaredNorm();
  EXPECT_NEAR(lasting.variance(), lean, 1e-6 * lean);
  const double window = ap::kTiltDisagreementWindow;
  const int n = static_cast<int>(std::lround(window / 0.01));
  for (int j = 1; j <= n; ++j) lasting.observe(at(0.01 * (k - 1 + j)), up);
  EXPECT_NEAR(lasting.variance(), lean * std::exp(-2.0), 1e-6 * lean);
  lasting.reset();
  EXPECT_EQ(lasting.variance(), 0.0);
}

// The published tilt covariance takes the disagreement beyond what the filter's own allows
// (AttitudeEngine::state): a body at rest, its attitude given, whose accelerometer reads a
// lasting horizontal acceleration of 1 m/s^2 (a turn) and is trusted so little (accel_stddev
// 100, the most accepted) that the estimate all but stays: the measured up leans by theta = atan(1
// / g) from the estimate's, so the published tilt variance per axis becomes sin^2 theta, far beyond
// the filter's own; the heading's variance is the same as without the acceleration.
TEST(TiltDisagreement, APublishedTiltVarianceIsTheLastingLean) {
  ap::EngineConfig c = aidedConfig();
  c.aiding.align = false;
  c.aiding.accel_stddev = 100.0;
  c.kinematic.initial_q_WB = rpy(0.2, -0.1, 0.7);
  c.initial_orientation_stddev = 0.001;
  // 10 s of the force the acceleration a_W gives at rest; with `reset`, then a reset (the
  // initial state again) and 1 s of gravity alone.
  auto publish = [&](const Eigen::Vector3d& a_W, bool reset = false) {
    Recorder sink;
    ap::AttitudeEngine engine(c, sink);
    const Eigen::Quaterniond& q = c.kinematic.initial_q_WB;
    auto feed = [&](const Eigen::Vector3d& f_W, int from, int to) {
      for (int k = from; k <= to; ++k) {
        engine.submit(imu(at(0.01 * k), Eigen::Vector3d::Zero()));
        engine.submitAcceleration(at(0.01 * k), q.conjugate() * f_W, Eigen::Matrix3d::Zero());
      }
    };
    feed(a_W + Eigen::Vector3d(0, 0, g), 0, 1000);
    if (reset) {
      engine.reset();
      feed(Eigen::Vector3d(0, 0, g), 1001, 1100);
    }
    return engine.state();
  };
  const ap::EngineState turning = publish(Eigen::Vector3d(0.6, 0.8, 0.0));
  const ap::EngineState still = publish(Eigen::Vector3d::Zero());
  const Eigen::Vector3d u = ap::bodyUp(turning.q_WB);
  const Eigen::Matrix3d plane = Eigen::Matrix3d::Identity() - u * u.transpose();
  const double sin_theta = 1.0 / std::sqrt(1.0 + g * g);
  EXPECT_NEAR(0.5 * (plane * turning.P_B * plane).trace(), sin_theta * sin_theta,
              1e-4 * sin_theta * sin_theta);
  EXPECT_LT(0.5 * (plane * still.P_B * plane).trace(), 1e-3 * sin_theta * sin_theta);
  // A reset forgets the lean: what it published before is no part of the state after.
  const ap::EngineState after_reset = publish(Eigen::Vector3d(0.6, 0.8, 0.0), true);
  EXPECT_LT(0.5 * (plane * after_reset.P_B * plane).trace(), 1e-3 * sin_theta * sin_theta);
  EXPECT_NEAR(u.dot(turning.P_B * u), u.dot(still.P_B * u), 1e-6 * u.dot(still.P_B * u));
  EXPECT_LE((turning.P_B * u - u * u.dot(turning.P_B * u)).norm(),
            1e-6);  // no tilt-heading term added
}

// The force's magnitude shows a linear acceleration whatever the estimate explains:
// |f|^2 - g^2 = |a|^2 + 2 g a_up, so for one at right angles to gravity (a turn) |a|^2, from the
// first sample on, with a residual of zero (the tilt has followed the force); its size counts,
// not its sign; the sensor's noise (its trace, E|n|^2) is no acceleration. The direction's noise
// takes |a|^2 whole in each axis (a lasting acceleration keeps one direction in the plane), the
// spread a third of it.
TEST(LinearAcceleration, TheForcesMagnitudeShowsAHorizontalAccelerationFromTheFirstSample) {
  const Eigen::Vector3d none = Eigen::Vector3d::Zero();
  const double window = ap::kLinearAccelerationWindow;
  ap::LinearAcceleration turn;
  const double f = std::sqrt(g * g + 9.0);  // 3 m/s^2 across gravity
  const ap::LinearVariance first = turn.observe(at(0.0), none, 0.0, window, f);
  EXPECT_NEAR(first.direction, 9.0, 1e-9);
  EXPECT_NEAR(first.spread, 3.0, 1e-9);
  ap::LinearVariance v;
  for (int k = 1; k <= 500; ++k) v = turn.observe(at(0.01 * k), none, 0.0, window, f);
  EXPECT_NEAR(v.direction, 9.0, 1e-9);
  EXPECT_NEAR(v.spread, 3.0, 1e-9);
  // The field's heading allows the tilt the even spread, over g^2 (rad^2 per axis).
  EXPECT_NEAR(v.fieldTiltVariance(), 3.0 / (g * g), 1e-12);
  ap::LinearAcceleration falling;  // |f| < g: accelerating downward
  const ap::LinearVariance down =
      falling.observe(at(0.0), none, 0.0, window, std::sqrt(g * g - 9.0));
  EXPECT_NEAR(down.direction, 9.0, 1e-9);
  EXPECT_NEAR(down.spread, 3.0, 1e-9);
  // The noise's trace, 0.03, is what |f|^2 - g^2 holds on average without acceleration; at 0.06
  // the rest, 0.03, is the acceleration's.
  ap::LinearAcceleration noise;
  const ap::LinearVariance still =
      noise.observe(at(0.0), none, 0.03, window, std::sqrt(g * g + 0.03));
  EXPECT_NEAR(still.direction, 0.0, 1e-12);
  EXPECT_NEAR(still.spread, 0.0, 1e-12);
  ap::LinearAcceleration little;
  const ap::LinearVariance some =
      little.observe(at(0.0), none, 0.03, window, std::sqrt(g * g + 0.06));
  EXPECT_NEAR(some.direction, 0.03, 1e-9);
  EXPECT_NEAR(some.spread, 0.01, 1e-9);
  // Without the force (0), the unexplained part alone, from zero.
  ap::LinearAcceleration residual_only;
  const ap::LinearVariance alone =
      residual_only.observe(at(0.0), Eigen::Vector3d(3.0, 0, 0), 0.0, window, 0.0);
  EXPECT_EQ(alone.direction, 0.0);
  EXPECT_EQ(alone.spread, 0.0);
  // A vertical oscillation a_up = A sin(w t) is no lasting acceleration: 2 g a_up averages out
  // over the window, to within the exponential average's gain at w, 1 / sqrt(1 + (w W)^2)
  // (and a_up^2 = A^2 / 2 (1 - cos 2 w t) to within its gain at 2 w), 5 % for the sampling.
  const double A = 1.0, w = 2.0 * M_PI / 0.5;
  ap::LinearAcceleration heave;
  double largest = 0.0, largest_spread = 0.0;
  for (int k = 0; k <= 2000; ++k) {
    const double t = 0.01 * k, up = A * std::sin(w * t);
    v = heave.observe(at(t), none, 0.0, window, std::hypot(0.0, g + up));
    if (t > 10.0 * window) {
      largest = std::max(largest, v.direction);
      largest_spread = std::max(largest_spread, v.spread);
    }
  }
  const double bound = A * A / 2.0 * (1.0 + 1.0 / std::hypot(1.0, 2.0 * w * window)) +
                       2.0 * g * A / std::hypot(1.0, w * window);
  EXPECT_LE(largest, 1.05 * bound);
  EXPECT_LE(largest_spread, 1.05 * bound / 3.0);
  EXPECT_LT(bound, 2.0 * g * A / 5.0);  // a fifth of what one sample says, or less
}

// A level body in a constant turn from its first sample: a centripetal acceleration a at right
// angles to gravity, so |f|^2 = g^2 + a^2 and the accelerometer's direction leans atan(a / g) for
// as long as it lasts. The tilt starts right (initial_orientation, stddev s0) and the gyro is
// next to noiseless, so the tilt is a static state seen through m samples of one noise R each
// (isotropic in the plane): its estimate moves toward the lean by the closed-form share
// (m / R) / (1 / s0^2 + m / R) (information form). R holds the acceleration the magnitude shows
// from the first sample, a^2 in each axis less the sensor's noise; the unexplained part alone
// shows nothing at first, the first samples would then count as the sensor's noise, and the
// tilt would lean with the force within a tenth of a second.
TEST(LinearAcceleration, AConstantHorizontalAccelerationMovesTheTiltByTheClosedFormShare) {
  const double a = 2.0, s0 = 0.002, sigma = 0.05;
  ap::EngineConfig c = aidedConfig();
  c.aiding.align = false;
  c.initial_orientation_stddev = s0;
  c.rate_stddev = 1e-7;
  ASSERT_EQ(c.aiding.accel_stddev, sigma);
  Recorder sink;
  ap::AttitudeEngine engine(c, sink);
  const Eigen::Vector3d f(0.0, a, g);  // the force leans toward the body's +y
  for (int k = 0; k < 1000; ++k) {     // 10 s
    engine.submit(imu(at(0.01 * k), Eigen::Vector3d::Zero()));
    engine.submitAcceleration(at(0.01 * k), f, Eigen::Matrix3d::Zero());
  }
  const double m = static_cast<double>(engine.counters().accel.accepted);
  ASSERT_GE(m, 999.0);
  const double f2 = f.squaredNorm(), off = (std::sqrt(f2) - g) / g;
  const double R = sigma * sigma / f2 + off * off + (a * a - 3.0 * sigma * sigma) / (g * g);
  const double share = (m / R) / (1.0 / (s0 * s0) + m / R);
  const double lean = std::atan2(a, g);
  const double tilt = simulated_imu::tiltError(engine.state().q_WB, Eigen::Quaterniond::Identity());
  EXPECT_NEAR(tilt, share * lean, 0.01 * share * lean);
  EXPECT_LT(share, 0.3);  // the scene: the turn moves the tilt by less than a third of its lean
}

TEST(RateDelay, AGravitySampleIsMovedBackWithItsRate) {
  ap::EngineConfig c = aidedConfig();
  c.rate_delay = 0.01;
  Recorder sink;
  ap::AttitudeEngine engine(c, sink);
  engine.submit(imu(at(1.0), Eigen::Vector3d::Zero()));
  EXPECT_EQ(engine.submitAcceleration(at(1.0), {0, 0, g}, Eigen::Matrix3d::Zero()),
            ap::AidingOutcome::Aligned);
  EXPECT_EQ(engine.pendingMeasurements(), 0u);
}

// A reset (or a clock jumping back) returns to the initial state: the tilt is unknown again and
// the next gravity sample aligns it again.
TEST(Alignment, AfterAResetTheNextGravitySampleAlignsAgain) {
  Recorder sink;
  ap::AttitudeEngine engine(aidedConfig(), sink);
  const Eigen::Vector3d f = rpy(0.3, 0, 0).conjugate() * Eigen::Vector3d(0, 0, g);
  engine.submit(imu(at(0.0), Eigen::Vector3d::Zero()));
  ASSERT_EQ(engine.submitAcceleration(at(0.0), f, Eigen::Matrix3d::Zero()),
            ap::AidingOutcome::Aligned);
  engine.reset();
  EXPECT_FALSE(engine.tiltKnown());
  engine.submit(imu(at(0.1), Eigen::Vector3d::Zero()));
  EXPECT_EQ(engine.submitAcceleration(at(0.1), f, Eigen::Matrix3d::Zero()),
            ap::AidingOutcome::Aligned);
  EXPECT_EQ(engine.counters().accel.aligned, 2u);
}

// A field off the one learned (a magnet near the sensor: 30 % stronger) is a disturbance: not
// used, counted; once it has lasted kMagRecovery seconds it is the field (a new place) and
// the reference starts again from it.
// The field's gate allows the tilt the linear acceleration spread evenly over three axes
// (LinearVariance::fieldTiltVariance), not the gravity sample's own noise. A level body whose
// force stays vertical but 3 m/s^2 over g (|f|^2 - g^2 = 9: a 9 m^2/s^4 direction noise per axis,
// 3 spread) for 5 s, the tilt and heading known to 1 mrad: the field turned by theta about the
// world's up has S = R_h + (3 - tr/3)/g^2 tan^2(dip) (H P H^T negligible), so 0.6 rad passes
// the gate (d^2 4.7 < 10.83) and 1.2 rad does not (19.0); with the direction's 9 per axis it
// would (6.3). Without the acceleration 0.6 rad is refused (S = R_h alone).
TEST(MagneticHeading, ItsGateAllowsTheTiltTheLinearAccelerationSpreadOverThreeAxes) {
  const double dip = 1.0;
  auto outcome = [dip](double over_g, double theta) {
    ap::EngineConfig c = fieldConfig();
    c.initial_orientation_stddev = 1e-3;
    Recorder sink;
    ap::AttitudeEngine engine(c, sink);
    const Eigen::Vector3d f(0.0, 0.0, std::sqrt(g * g + over_g));
    int k = 0;
    for (; k <= 500; ++k) {
      engine.submit(imu(at(0.01 * k), Eigen::Vector3d::Zero()));
      engine.submitAcceleration(at(0.01 * k), f, Eigen::Matrix3d::Zero());
    }
    const Eigen::Vector3d m = engine_fixtures::aboutAxis({0, 0, 1}, theta).conjugate() *
                              simulated_imu::earthField(50e-6, dip, 0.0);
    engine.submit(imu(at(0.01 * k), Eigen::Vector3d::Zero()));
    return engine.submitMagneticField(at(0.01 * k), m, Eigen::Matrix3d::Zero());
  };
  EXPECT_EQ(outcome(9.0, 0.6), ap::AidingOutcome::Accepted);
  EXPECT_EQ(outcome(9.0, 1.2), ap::AidingOutcome::RejectedGate);
  EXPECT_EQ(outcome(0.0, 0.6), ap::AidingOutcome::RejectedGate);
}

TEST(MagneticDisturbance, AFieldOffTheLearnedMagnitudeIsRejectedUntilItLasts) {
  ap::EngineConfig c = fieldConfig();
  c.aiding.use_accel = false;
  Recorder sink;
  ap::AttitudeEngine engine(c, sink);
  const Eigen::Vector3d m = simulated_imu::earthField(50e-6, 1.0, 0.0);
  const double h = 0.1;
  int k = 0;
  for (; k < 10; ++k) {
    engine.submit(imu(at(k * h), Eigen::Vector3d::Zero()));
    engine.submitMagneticField(at(k * h), m, Eigen::Matrix3d::Zero());
  }
  EXPECT_EQ(engine.counters().mag.accepted, 10u);
  const int n = static_cast<int>(std::lround(ap::kMagRecovery / h));
  for (int i = 0; i <= n; ++i, ++k) {
    engine.submit(imu(at(k * h), Eigen::Vector3d::Zero()));
    const ap::AidingOutcome o =
        engine.submitMagneticField(at(k * h), 1.3 * m, Eigen::Matrix3d::Zero());
    EXPECT_EQ(o, i < n ? ap::AidingOutcome::RejectedMagnitude : ap::AidingOutcome::Accepted) << i;
  }
  EXPECT_EQ(engine.counters().mag.rejected_magnitude, static_cast<std::uint64_t>(n));
  // Within the tolerance (10 % for 15 %) it is the field, and no disturbance.
  engine.submit(imu(at(k * h), Eigen::Vector3d::Zero()));
  EXPECT_EQ(engine.submitMagneticField(at(k * h), 1.3 * 1.1 * m, Eigen::Matrix3d::Zero()),
            ap::AidingOutcome::Accepted);
}

// A gravity sample handed in apart from its rate (late) is moved back by rate_delay as its
// rate was: the same as the stream stamped rate_delay earlier without it.
TEST(RateDelay, ALateGravitySampleIsMovedBackAsItsRateWas) {
  auto run = [](double delay, double shift) {
    ap::EngineConfig c = aidedConfig();
    c.aiding.use_mag = true;  // the history from the start
    c.rate_delay = delay;
    Recorder sink;
    ap::AttitudeEngine engine(c, sink);
    const auto samples = simulated_imu::simulate(tumble(), simulated_imu::Sensor{}, 1.0);
    for (std::size_t k = 0; k < samples.size(); ++k) {
      engine.submit(imu(at(samples[k].t + shift), samples[k].w_B));
      if (k >= 2) {
        engine.submitAcceleration(at(samples[k - 2].t + shift), samples[k - 2].f_B,
                                  Eigen::Matrix3d::Zero());
      }
    }
    return engine.state();
  };
  const ap::EngineState delayed = run(0.004, 0.0);
  const ap::EngineState shifted = run(0.0, -0.004);
  EXPECT_LE(ap::rotationAngle(delayed.q_WB, shifted.q_WB), 1e-12);
  EXPECT_LE((delayed.P_B - shifted.P_B).cwiseAbs().maxCoeff(), 1e-15);
}

// ---- the bias: what gravity makes observable ------------------------------------------------

// Level and still, a bias on every axis: gravity makes the two horizontal components
// observable, never the vertical one, whose standard deviation stays at its prior (with no
// random walk; the estimate's own small tilt, from the horizontal bias before it converged,
// turns the unobserved axis by some 1e-4 rad, so "at its prior" to that part) while the
// horizontal ones shrink a hundredfold and converge to the truth.
TEST(Bias, GravityMakesTheHorizontalBiasObservableAndNeverTheVertical) {
  ap::EngineConfig c = aidedConfig();
  c.aiding.align = false;
  c.fixes.estimate_gyro_bias = true;
  c.fixes.gyro_bias_stddev = 0.01;
  c.fixes.gyro_bias_random_walk = 0.0;
  c.rate_stddev = 1e-3;
  Recorder sink;
  ap::AttitudeEngine engine(c, sink);
  const Eigen::Vector3d bias(0.004, -0.003, 0.005);
  const double h = 0.01;
  for (int k = 0; k <= 6000; ++k) {
    engine.submit(imu(at(k * h), bias));
    engine.submitAcceleration(at(k * h), {0, 0, g}, Eigen::Matrix3d::Zero());
  }
  const ap::EngineState s = engine.state();
  EXPECT_NEAR(s.gyro_bias_stddev_B.z(), 0.01, 1e-4 * 0.01);
  EXPECT_LT(s.gyro_bias_stddev_B.x(), 1e-4);
  EXPECT_LT(s.gyro_bias_stddev_B.y(), 1e-4);
  EXPECT_NEAR(s.gyro_bias_estimate_B.x(), bias.x(), 0.05 * kDeg);
  EXPECT_NEAR(s.gyro_bias_estimate_B.y(), bias.y(), 0.05 * kDeg);
  EXPECT_LE(std::abs(s.gyro_bias_estimate_B.z()), 1e-4 * bias.z());
  EXPECT_EQ(engine.counters().accel.accepted, 6001u);
}

// The attitude unknown (its covariance at the cap on every axis) and the gyro alone at rest:
// each step the bias' uncertainty grows the attitude's (the error dtheta' = dtheta - h db, so
// p' = p - 2 h c + h^2 (q + r^2), c' = c - h q with c = Cov(dtheta_i, db_i), q = P_bb,ii) past
// the cap, and the clamp brings p back to it with c scaled by sqrt(cap / p'), the correlation
// kept: the scalar recurrence below, per axis. Then one level gravity sample: what it learns
// of the horizontal bias is through c alone, P_bb,ii' = q - c^2 / (cap + R), R = (accel_stddev /
// g)^2 the direction's noise (the sample exact, no linear acceleration seen). Dropping the
// correlations at each clamp leaves c = -h q and the bias' stddev at its prior.
TEST(Bias, TheAttitudesCorrelationWithTheBiasOutlivesTheClampAtTheCap) {
  ap::EngineConfig c = aidedConfig();
  c.aiding.align = false;
  c.initial_orientation_stddev = 4.0;  // beyond the cap: clamped to it
  c.fixes.estimate_gyro_bias = true;
  c.fixes.gyro_bias_stddev = 0.01;
  c.fixes.gyro_bias_random_walk = 0.0;
  Recorder sink;
  ap::AttitudeEngine engine(c, sink);
  const double h = 0.01;
  const int n = 10000;
  for (int k = 0; k <= n; ++k) engine.submit(imu(at(k * h), Eigen::Vector3d::Zero()));
  const double cap = ap::kMaxOrientationVariance;
  const double q = 0.01 * 0.01;
  const double r2 = c.rate_stddev * c.rate_stddev;
  double cov = 0.0;
  for (int k = 0; k < n; ++k) {
    const double p = cap - 2.0 * h * cov + h * h * (q + r2);
    cov = std::sqrt(cap / p) * (cov - h * q);
  }
  EXPECT_LT(cov, -0.9 * n * h * q);  // most of the correlation the drift builds is there
  EXPECT_EQ(engine.state().P_B.diagonal(), Eigen::Vector3d::Constant(cap));
  EXPECT_NEAR(engine.state().gyro_bias_stddev_B.x(), 0.01, 1e-15);
  engine.submitAcceleration(at(n * h), {0, 0, g}, Eigen::Matrix3d::Zero());
  ASSERT_EQ(engine.counters().accel.accepted, 1u);
  const Eigen::Vector3d stddev = engine.state().gyro_bias_stddev_B;
  const double R = std::pow(c.aiding.accel_stddev / g, 2);
  const double expected = std::sqrt(q - cov * cov / (cap + R));
  EXPECT_NEAR(stddev.x(), expected, 1e-12);
  EXPECT_NEAR(stddev.y(), expected, 1e-12);
  EXPECT_NEAR(stddev.z(), 0.01, 1e-12);  // the vertical: not seen by gravity
  EXPECT_LT(stddev.x(), 0.01 - 1e-4);
}

// One step of the error state at rest (w = 0: Phi = I, G = h I), the closed form of
// P <- F P F^T + Q: P_B - h (P_Bb + P_Bb^T) + h^2 (P_bb + R), P_Bb - h P_bb, P_bb + q^2 h I; and
// without the bias estimate the attitude block's own step, the bias blocks left as they were.
TEST(ErrorState, OneStepAtRestIsTheClosedFormOfFPFTransposedPlusQ) {
  const JointTruth truth = genericJoint({0.02, 0.3, 0.5});
  const Matrix6 P = truth.covariance();
  ap::ErrorState e = errorStateOf(P);
  const double h = 0.01, q = 0.003;
  const Eigen::Matrix3d R = anisotropicRateNoise();
  ap::ErrorState with = e;
  ap::propagateErrorState(with, h, Eigen::Vector3d::Zero(), R, true, q);
  const Eigen::Matrix3d P_B = e.P_B - h * (e.P_Bb + e.P_Bb.transpose()) + h * h * (e.P_bb + R);
  EXPECT_LE((with.P_B - P_B).norm(), 1e-15);
  EXPECT_LE((with.P_Bb - (e.P_Bb - h * e.P_bb)).norm(), 1e-15);
  EXPECT_LE((with.P_bb - (e.P_bb + q * q * h * Eigen::Matrix3d::Identity())).norm(), 1e-15);
  ap::ErrorState without = e;
  ap::propagateErrorState(without, h, Eigen::Vector3d(0.3, -0.2, 0.1), R, false, q);
  EXPECT_EQ(without.P_B,
            ap::propagateOrientationCovariance(e.P_B, h, Eigen::Vector3d(0.3, -0.2, 0.1), R));
  EXPECT_EQ(without.P_Bb, e.P_Bb);
  EXPECT_EQ(without.P_bb, e.P_bb);
}

// The same step at a generic rate, against the nonlinear error it linearises: the estimate turns
// by Exp(h w) (w the rate less the bias estimate), the truth q (x) Exp(dtheta) by Exp(h (w - db -
// n)) (n the rate's noise), so the next error is Log(Exp(-h w) Exp(dtheta) Exp(h (w - db - n))).
// Its Jacobians by central differences give F = [Phi, F_b; 0, I] and the noise's G, and the
// covariance must be F P F^T + diag(G R G^T, q^2 h I). A turn of 0.6 rad in the step tells Phi
// from Phi^T and the right Jacobian from the left one.
TEST(ErrorState, OneStepAtAGenericRateIsTheLinearisedNonlinearError) {
  const JointTruth truth = genericJoint({0.02, 0.3, 0.5});
  const Matrix6 P = truth.covariance();
  ap::ErrorState e = errorStateOf(P);
  const double h = 0.01, q = 0.003;
  const Eigen::Vector3d w(36.0, -42.0, 24.0);  // rad/s: |h w| = 0.6 rad
  const Eigen::Matrix3d R = anisotropicRateNoise();
  auto next = [&](const Eigen::Vector3d& dtheta, const Eigen::Vector3d& db) {
    return ap::logMap(ap::expMap(-h * w) * ap::expMap(dtheta) * ap::expMap(h * (w - db)));
  };
  const double d = 1e-6;
  Eigen::Matrix3d Phi, F_b;
  for (int i = 0; i < 3; ++i) {
    const Eigen::Vector3d u = d * Eigen::Vector3d::Unit(i);
    const Eigen::Vector3d z = Eigen::Vector3d::Zero();
    Phi.col(i) = (next(u, z) - next(-u, z)) / (2 * d);
    F_b.col(i) = (next(z, u) - next(z, -u)) / (2 * d);
  }
  ASSERT_GT((Phi - Phi.transpose()).norm(), 0.5);  // the step's turn is large enough to tell
  Matrix6 F = Matrix6::Identity();
  F.topLeftCorner<3, 3>() = Phi;
  F.topRightCorner<3, 3>() = F_b;
  Matrix6 Q = Matrix6::Zero();
  Q.topLeftCorner<3, 3>() = F_b * R * F_b.transpose();  // the noise enters as the bias error does
  Q.bottomRightCorner<3, 3>() = q * q * h * Eigen::Matrix3d::Identity();
  const Matrix6 expected = F * P * F.transpose() + Q;
  ap::propagateErrorState(e, h, w, R, true, q);
  EXPECT_LE((e.P_B - expected.topLeftCorner<3, 3>()).norm(), 1e-8);
  EXPECT_LE((e.P_Bb - expected.topRightCorner<3, 3>()).norm(), 1e-8);
  EXPECT_LE((e.P_bb - expected.bottomRightCorner<3, 3>()).norm(), 1e-15);
}

// Each axis' bias variance is capped at kMaxGyroBiasStddev^2 by a congruence: the capped axes
// end exactly at the cap, the others and the attitude block stay as they were, and every
// correlation coefficient, attitude-bias and bias-bias, is kept (the joint matrix stays one).
TEST(ClampedCovariance, TheBiasCapKeepsEveryCorrelationCoefficient) {
  const double ceiling = ap::kMaxGyroBiasStddev * ap::kMaxGyroBiasStddev;
  JointTruth truth = genericJoint({0.02, 0.3, 0.5});
  truth.sigma_b = Eigen::Vector3d(2.0 * ap::kMaxGyroBiasStddev, 0.02, 1.5 * ap::kMaxGyroBiasStddev);
  const Matrix6 P = truth.covariance();
  ap::ErrorState e = errorStateOf(P);
  ap::capBiasCovariance(e);
  EXPECT_EQ(e.P_bb(0, 0), ceiling);
  EXPECT_EQ(e.P_bb(2, 2), ceiling);
  EXPECT_EQ(e.P_bb(1, 1), P(4, 4));
  EXPECT_EQ(e.P_B, Eigen::Matrix3d(P.topLeftCorner<3, 3>()));
  JointTruth capped = truth;
  capped.sigma_b = Eigen::Vector3d(ap::kMaxGyroBiasStddev, 0.02, ap::kMaxGyroBiasStddev);
  const Matrix6 expected = capped.covariance();
  EXPECT_LE((e.P_Bb - expected.topRightCorner<3, 3>()).norm(), 1e-12);
  EXPECT_LE((e.P_bb - expected.bottomRightCorner<3, 3>()).norm(), 1e-12 * ceiling);
  EXPECT_GE(smallestEigenvalue(joint(e.P_B, e.P_Bb, e.P_bb)), -1e-12 * ceiling);
}

// The update of the attitude and the bias together, with the heading's gain kept to the vertical
// (a gain that is not the optimal one): the attitude block after it can rise above the cap in a
// direction between the heading and the tilt, where it is clamped; the bias' cross-covariance
// is scaled with it, so the joint covariance stays semi-definite and no correlation passes one.
TEST(ClampedCovariance, AnUpdateThatClampsTheAttitudeScalesItsCorrelationsWithTheBias) {
  const double cap = ap::kMaxOrientationVariance;
  const JointTruth before = genericJoint({cap, 0.999 * cap, 0.998 * cap});
  const Matrix6 P = before.covariance();
  ap::ErrorState e = errorStateOf(P);
  // A steep field (dip 1.2 rad): the heading's H reaches the tilt by tan(dip), the gain does not.
  const Eigen::Vector3d m_W = simulated_imu::earthField(50e-6, 1.2, 0.0);
  const Eigen::Quaterniond truth = rpy(0.05, -0.02, 0.3) * kGeneric;
  const ap::MagneticHeading m(truth.conjugate() * m_W, 1e-14 * Eigen::Matrix3d::Identity(), 0.0,
                              1e9);
  Eigen::Quaterniond q = kGeneric;
  ASSERT_TRUE(ap::fuseMeasurement(m, q, e).accepted);
  // The update without the clamp (Joseph form, the documented gain) rises above the cap: the
  // case is one where the clamp acts.
  const ap::Linearized lin = m.linearize(kGeneric);
  Eigen::Matrix<double, 1, 6> H = Eigen::Matrix<double, 1, 6>::Zero();
  H.leftCols<3>() = lin.H;
  const double S = (H * P * H.transpose())(0, 0) + lin.R(0, 0);
  Eigen::Matrix<double, 6, 1> K = P * H.transpose() / S;
  K.head<3>() = m.correctionAxes(kGeneric) * K.head<3>();
  const Matrix6 I_KH = Matrix6::Identity() - K * H;
  const Matrix6 raw = I_KH * P * I_KH.transpose() + K * lin.R(0, 0) * K.transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(raw.topLeftCorner<3, 3>());
  ASSERT_GT(eig.eigenvalues().maxCoeff(), cap * (1.0 + 1e-6));
  EXPECT_LE(Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(e.P_B).eigenvalues().maxCoeff(),
            cap * (1.0 + 1e-12));
  EXPECT_GE(smallestEigenvalue(joint(e.P_B, e.P_Bb, e.P_bb)), -1e-12 * cap);
  // Each of the raw block's directions keeps its correlation coefficients with the bias.
  for (int i = 0; i < 3; ++i) {
    const Eigen::Vector3d v = eig.eigenvectors().col(i);
    for (int j = 0; j < 3; ++j) {
      const double rho_raw = v.dot(raw.topRightCorner<3, 3>().col(j)) /
                             std::sqrt(eig.eigenvalues()(i) * raw(3 + j, 3 + j));
      const double rho = v.dot(e.P_Bb.col(j)) / std::sqrt(v.dot(e.P_B * v) * e.P_bb(j, j));
      EXPECT_NEAR(rho, rho_raw, 1e-9) << i << " " << j;
    }
  }
}

// ---- late samples ----------------------------------------------------------------------------

// A tumbling body sampled at 100 Hz with gravity and field samples: handed in on time, or each
// 30 ms late (after three more rates), or the field samples stamped between rates, the newest
// state is the same to round-off, since a late sample is applied at its stamp and the steps
// since repeated. With the linear acceleration's average on, a sample's noise is taken from the
// state it arrives at, which a late one finds a little different: the same to that difference.
simulated_imu::Motion tumble() {
  return {
      [](double t) { return rpy(0.5 * std::sin(0.7 * t), 0.4 * std::sin(0.5 * t + 1.0), 0.8 * t); },
      nullptr};
}

ap::EngineState runAided(int accel_delay, double mag_offset, int mag_delay,
                         double linear_window = 0.0) {
  ap::EngineConfig c = aidedConfig();
  c.aiding.linear_window = linear_window;
  c.aiding.use_mag = true;
  c.aiding.mag_stddev = 0.3e-6;
  c.fixes.estimate_gyro_bias = true;
  c.fixes.gyro_bias_stddev = 0.01;
  simulated_imu::Sensor sensor;
  sensor.gyro_noise = 0.002;
  sensor.gyro_bias = Eigen::Vector3d(0.003, -0.004, 0.002);
  sensor.accel_noise = 0.05;
  sensor.mag_noise = 0.3e-6;
  const auto samples = simulated_imu::simulate(tumble(), sensor, 5.0);
  Recorder sink;
  ap::AttitudeEngine engine(c, sink);
  for (std::size_t k = 0; k < samples.size(); ++k) {
    engine.submit(imu(at(samples[k].t), samples[k].w_B));
    if (k >= static_cast<std::size_t>(accel_delay)) {
      const auto& s = samples[k - accel_delay];
      engine.submitAcceleration(at(s.t), s.f_B, Eigen::Matrix3d::Zero());
    }
    if (k >= static_cast<std::size_t>(mag_delay)) {
      const auto& s = samples[k - mag_delay];
      engine.submitMagneticField(at(s.t + mag_offset), s.m_B, Eigen::Matrix3d::Zero());
    }
  }
  // The samples still on their way arrive after the last rate.
  const std::size_t n = samples.size();
  for (std::size_t k = n - accel_delay; k < n; ++k) {
    engine.submitAcceleration(at(samples[k].t), samples[k].f_B, Eigen::Matrix3d::Zero());
  }
  for (std::size_t k = n - mag_delay; k < n; ++k) {
    engine.submitMagneticField(at(samples[k].t + mag_offset), samples[k].m_B,
                               Eigen::Matrix3d::Zero());
  }
  return engine.state();
}

TEST(Late, GravityAndFieldSamplesHandedInLateGiveTheStateTheyGiveOnTime) {
  const ap::EngineState on_time = runAided(0, 0.0, 0);
  const ap::EngineState late = runAided(3, 0.0, 5);
  EXPECT_LE(ap::rotationAngle(on_time.q_WB, late.q_WB), 1e-9);
  EXPECT_LE((on_time.P_B - late.P_B).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LE((on_time.gyro_bias_estimate_B - late.gyro_bias_estimate_B).norm(), 1e-10);
  // Between rates (4 ms after one): the same whether handed in at once or 50 ms later.
  const ap::EngineState between = runAided(0, 0.004, 1);
  const ap::EngineState between_late = runAided(0, 0.004, 6);
  EXPECT_LE(ap::rotationAngle(between.q_WB, between_late.q_WB), 1e-9);
  // The average on: the noise of a late sample from the state it arrives at.
  const ap::EngineState adaptive = runAided(0, 0.0, 0, ap::kLinearAccelerationWindow);
  const ap::EngineState adaptive_late = runAided(3, 0.0, 5, ap::kLinearAccelerationWindow);
  EXPECT_LE(ap::rotationAngle(adaptive.q_WB, adaptive_late.q_WB), 2e-3);
}

// use_accel_covariance and use_mag_covariance false: a message's own covariance is ignored and
// the settings' stddevs stand, as for a message whose covariance is all zero, even where the
// covariance is not one (a driver's NaN is not refused then). The same stream with the covariance
// used gives another state, and the NaN is refused as invalid, so the setting is what differs.
struct CovarianceRun {
  ap::EngineState state;
  ap::AidingCounters accel, mag;
};

// A tumble of `seconds` read by a gyro, an accelerometer and a magnetometer (own_B added to every
// field read) through an engine configured with `c`; the sensor's covariances as given.
CovarianceRun runFieldTumble(const ap::EngineConfig& c, double seconds,
                             const Eigen::Matrix3d& accel_R, const Eigen::Matrix3d& mag_R,
                             const Eigen::Vector3d& own_B = Eigen::Vector3d::Zero()) {
  simulated_imu::Sensor sensor;
  sensor.gyro_noise = 0.002;
  sensor.accel_noise = 0.05;
  sensor.mag_noise = 0.3e-6;
  const auto samples = simulated_imu::simulate(tumble(), sensor, seconds);
  Recorder sink;
  ap::AttitudeEngine engine(c, sink);
  for (const auto& x : samples) {
    engine.submit(imu(at(x.t), x.w_B));
    engine.submitAcceleration(at(x.t), x.f_B, accel_R);
    engine.submitMagneticField(at(x.t), x.m_B + own_B, mag_R);
  }
  return {engine.state(), engine.counters().accel, engine.counters().mag};
}

CovarianceRun runWithCovariances(bool use_message_covariance, const Eigen::Matrix3d& accel_R,
                                 const Eigen::Matrix3d& mag_R) {
  ap::EngineConfig c = aidedConfig();
  c.aiding.linear_window = 0.0;
  c.aiding.use_mag = true;
  c.aiding.mag_stddev = 0.3e-6;
  c.aiding.use_accel_covariance = use_message_covariance;
  c.aiding.use_mag_covariance = use_message_covariance;
  return runFieldTumble(c, 2.0, accel_R, mag_R);
}

TEST(MessageCovariance, IgnoredWhenTheSettingsSaySoTheStddevsStand) {
  const Eigen::Matrix3d none = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d accel_R;  // anisotropic and correlated, far from accel_stddev's
  accel_R << 4.0, 0.5, 0.0, 0.5, 1.0, -0.3, 0.0, -0.3, 2.0;
  const Eigen::Matrix3d mag_R = 2.7e-6 * Eigen::Matrix3d::Identity();  // 1.7 mT: another unit
  const CovarianceRun stddevs = runWithCovariances(true, none, none);
  const CovarianceRun ignored = runWithCovariances(false, accel_R, mag_R);
  EXPECT_EQ(ignored.state.q_WB.coeffs(), stddevs.state.q_WB.coeffs());
  EXPECT_EQ(ignored.state.P_B, stddevs.state.P_B);
  EXPECT_EQ(ignored.accel.accepted, stddevs.accel.accepted);
  EXPECT_EQ(ignored.mag.accepted, stddevs.mag.accepted);
  const CovarianceRun used = runWithCovariances(true, accel_R, mag_R);
  EXPECT_GT((used.state.P_B - stddevs.state.P_B).norm(), 1e-3 * stddevs.state.P_B.norm());
  const Eigen::Matrix3d nan = Eigen::Matrix3d::Constant(NAN);
  const CovarianceRun ignored_nan = runWithCovariances(false, nan, nan);
  EXPECT_EQ(ignored_nan.state.q_WB.coeffs(), stddevs.state.q_WB.coeffs());
  EXPECT_EQ(ignored_nan.accel.invalid + ignored_nan.mag.invalid, 0u);
  const CovarianceRun refused = runWithCovariances(true, nan, nan);
  EXPECT_EQ(refused.accel.invalid, stddevs.accel.accepted + stddevs.accel.aligned);
  EXPECT_GT(refused.mag.invalid, 0u);
}

// mag_bias: the magnetometer's own field (hard iron), fixed in the body, is taken off every
// sample before it is judged or used. A tumble read with such a field added (generic, a third of
// the earth's, on no axis) and mag_bias set to it ends where the same tumble without it ends; the
// same field not given (or given with the wrong sign) leaves another heading. A body-fixed field
// turns with the body in the world, so the reads' magnitude and dip swing as the body tumbles.
CovarianceRun runWithOwnField(const Eigen::Vector3d& own_B, const Eigen::Vector3d& mag_bias) {
  ap::EngineConfig c = aidedConfig();
  c.aiding.use_mag = true;
  c.aiding.mag_stddev = 0.3e-6;
  c.aiding.mag_bias = mag_bias;
  const Eigen::Matrix3d none = Eigen::Matrix3d::Zero();
  return runFieldTumble(c, 4.0, none, none, own_B);
}

TEST(MagBias, TheMagnetometersOwnFieldIsTakenOffEverySample) {
  const Eigen::Vector3d own_B(7e-6, -11e-6, 13e-6);
  const Eigen::Vector3d none = Eigen::Vector3d::Zero();
  const CovarianceRun clean = runWithOwnField(none, none);
  const CovarianceRun taken_off = runWithOwnField(own_B, own_B);
  ASSERT_GT(clean.mag.accepted, 100u);
  EXPECT_EQ(taken_off.mag.accepted, clean.mag.accepted);
  EXPECT_EQ(taken_off.mag.rejected_magnitude, clean.mag.rejected_magnitude);
  // (m + b) - b is m to the last bits: the same path.
  EXPECT_LE(ap::rotationAngle(taken_off.state.q_WB, clean.state.q_WB), 1e-9);
  EXPECT_LE((taken_off.state.P_B - clean.state.P_B).norm(), 1e-9 * clean.state.P_B.norm());
  for (const Eigen::Vector3d& wrong : {none, Eigen::Vector3d(-own_B)}) {
    const CovarianceRun kept = runWithOwnField(own_B, wrong);
    const bool other_samples = kept.mag.accepted != clean.mag.accepted;
    EXPECT_TRUE(other_samples || ap::rotationAngle(kept.state.q_WB, clean.state.q_WB) > 1e-3)
        << wrong.transpose();
  }
}

// The engine's sphere fit (fieldFit, HardIronFit) takes every field read as read: its centre
// is the own field the reads carry whatever mag_bias is given (the value to give, not what is
// left of it), whether or not the read is then used (here none is: no rate has come, so the
// tilt is not known), and it outlasts a reset. A read the fit refuses (NaN) is not counted;
// without use_mag nothing is read.
TEST(MagBias, TheEnginesSphereFitTakesTheReadsAsRead) {
  const Eigen::Vector3d own_B(12e-6, -31e-6, 7e-6);
  const int n = 200;
  for (const Eigen::Vector3d& given :
       {Eigen::Vector3d::Zero().eval(), own_B, Eigen::Vector3d(-own_B)}) {
    ap::EngineConfig c = aidedConfig();
    c.aiding.use_mag = true;
    c.aiding.mag_bias = given;
    Recorder sink;
    ap::AttitudeEngine engine(c, sink);
    for (int k = 0; k < n; ++k) {
      if (k == n / 2) engine.reset();
      engine.submitMagneticField(at(0.01 * k), own_B + 48e-6 * evenDirection(k, n),
                                 Eigen::Matrix3d::Zero());
    }
    engine.submitMagneticField(at(2.0), Eigen::Vector3d::Constant(NAN), Eigen::Matrix3d::Zero());
    EXPECT_EQ(engine.fieldFit().count(), static_cast<std::uint64_t>(n));
    EXPECT_EQ(engine.counters().mag.accepted, 0u);
    const std::optional<ap::HardIronSphere> sphere = engine.fieldFit().solve();
    ASSERT_TRUE(sphere.has_value());
    EXPECT_LE((sphere->centre - own_B).norm(), 1e-12) << given.transpose();
    EXPECT_NEAR(sphere->radius, 48e-6, 1e-12);
  }
  ap::EngineConfig off = aidedConfig();
  Recorder sink;
  ap::AttitudeEngine engine(off, sink);
  engine.submitMagneticField(at(0.0), own_B, Eigen::Matrix3d::Zero());
  EXPECT_EQ(engine.fieldFit().count(), 0u);
}

// With absolute fixes at the same time: a late gravity sample is applied before the fixes
// stamped after it, which are applied again after it, as on time.
// The tumble started from its true attitude, with the history from the start and the
// linear acceleration's average off (the noise fixed, see above); a gyro and an accelerometer
// with noise.
ap::EngineConfig withFixesConfig() {
  ap::EngineConfig c = aidedConfig();
  c.aiding.linear_window = 0.0;
  c.aiding.use_mag = true;  // the history from the start
  c.aiding.align = false;
  c.kinematic.initial_q_WB = tumble().attitude(0.0);
  c.initial_orientation_stddev = 0.01;
  c.fixes.stddev = 0.01;
  return c;
}

simulated_imu::Sensor noisySensor() {
  simulated_imu::Sensor sensor;
  sensor.gyro_noise = 0.002;
  sensor.accel_noise = 0.05;
  return sensor;
}

ap::EngineState runWithFixes(int accel_delay) {
  const ap::EngineConfig c = withFixesConfig();
  const simulated_imu::Sensor sensor = noisySensor();
  const auto samples = simulated_imu::simulate(tumble(), sensor, 2.0);
  Recorder sink;
  ap::AttitudeEngine engine(c, sink);
  const std::size_t n = samples.size();
  for (std::size_t k = 0; k < n + accel_delay; ++k) {
    if (k < n) {
      engine.submit(imu(at(samples[k].t), samples[k].w_B));
      if (k % 20 == 10) {
        engine.submitFix(at(samples[k].t), samples[k].truth * ap::expMap({0.002, -0.001, 0.003}),
                         Eigen::Matrix3d::Zero());
      }
    }
    if (k >= static_cast<std::size_t>(accel_delay)) {
      const auto& s = samples[k - accel_delay];
      engine.submitAcceleration(at(s.t), s.f_B, Eigen::Matrix3d::Zero());
    }
  }
  EXPECT_GT(engine.counters().fixes_accepted, 8u);
  return engine.state();
}

// A flood of late gravity samples (each 3 s late on 1 kHz rates, 3000 states to replay) is
// bounded as late fixes are (replay_budget.h): per second at most (4096 + 20 x 1000) / 3000 = 8
// are applied, the rest counted over_budget, and every rate is taken.
TEST(Late, AFloodOfLateGravitySamplesIsBoundedByTheReplayBudget) {
  ap::EngineConfig c = aidedConfig();
  c.aiding.use_mag = true;  // the history from the start
  c.fixes.history = 10.0;
  engine_fixtures::DiscardingSink sink;
  ap::AttitudeEngine engine(c, sink);
  const Eigen::Vector3d f(0.0, 0.0, ap::kStandardGravity);
  int late = 0;
  for (int k = 0; k <= 8000; ++k) {
    engine.submit(imu(at(0.001 * k), Eigen::Vector3d::Zero()));
    if (k == 0) engine.submitAcceleration(at(0.0), f, Eigen::Matrix3d::Zero());  // aligns
    if (k < 5000) continue;
    engine.submitAcceleration(at(0.001 * k - 3.0), f, Eigen::Matrix3d::Zero());
    ++late;
  }
  const ap::AidingCounters& a = engine.counters().accel;
  EXPECT_EQ(engine.counters().accepted, 8001u);
  EXPECT_EQ(a.accepted + a.over_budget, static_cast<std::uint64_t>(late));
  EXPECT_GT(a.over_budget, 0u);
  EXPECT_LE(a.accepted, 8u * 4u);  // seconds 5, 6, 7 and 8
}

TEST(Late, ALateGravitySampleGoesBeforeTheFixesStampedAfterIt) {
  const ap::EngineState on_time = runWithFixes(0);
  const ap::EngineState late = runWithFixes(4);
  EXPECT_LE(ap::rotationAngle(on_time.q_WB, late.q_WB), 1e-9);
  EXPECT_LE((on_time.P_B - late.P_B).cwiseAbs().maxCoeff(), 1e-12);
}

// At most kMaxPendingMeasurements (64, limits.h) samples stamped ahead of the newest rate wait;
// past it the one stamped furthest ahead is dropped and counted queue_full: the 63rd and 64th
// wait, a 65th further ahead than all is dropped itself, one less far ahead takes the furthest
// one's place. When the rates reach them, every one still waiting is applied.
TEST(Pending, AtMostKMaxPendingMeasurementsWaitTheFurthestAheadDropped) {
  ap::EngineConfig c = aidedConfig();
  Recorder sink;
  ap::AttitudeEngine engine(c, sink);
  const Eigen::Vector3d f(0.0, 0.0, ap::kStandardGravity);
  const Eigen::Matrix3d none = Eigen::Matrix3d::Zero();
  engine.submit(imu(at(0.0), Eigen::Vector3d::Zero()));
  ASSERT_EQ(engine.submitAcceleration(at(0.0), f, none), ap::AidingOutcome::Aligned);
  EXPECT_EQ(ap::kMaxPendingMeasurements, 64u);  // the documented bound
  const int n = static_cast<int>(ap::kMaxPendingMeasurements);
  for (int k = 1; k <= n; ++k) {
    EXPECT_EQ(engine.submitAcceleration(at(0.01 * k + 0.001), f, none), ap::AidingOutcome::Waiting)
        << k;
    EXPECT_EQ(engine.counters().accel.queue_full, 0u) << k;
  }
  EXPECT_EQ(engine.submitAcceleration(at(0.01 * (n + 1) + 0.001), f, none),
            ap::AidingOutcome::QueueFull);
  EXPECT_EQ(engine.counters().accel.queue_full, 1u);
  EXPECT_EQ(engine.submitAcceleration(at(0.0055), f, none), ap::AidingOutcome::Waiting);
  EXPECT_EQ(engine.counters().accel.queue_full, 2u);  // the one at 0.641 s went
  for (int k = 1; k <= n + 2; ++k) engine.submit(imu(at(0.01 * k), Eigen::Vector3d::Zero()));
  EXPECT_EQ(engine.counters().accel.accepted, static_cast<std::uint64_t>(n));
}

// Gravity and field samples wait in one queue: a gravity sample nearer than the field samples
// filling it pushes the furthest field sample out, which is counted as the field's, not gravity's.
TEST(Pending, ASampleDroppedFromTheFullQueueIsCountedUnderItsOwnKind) {
  ap::EngineConfig c = aidedConfig();
  c.aiding.use_mag = true;
  Recorder sink;
  ap::AttitudeEngine engine(c, sink);
  const Eigen::Vector3d f(0.0, 0.0, ap::kStandardGravity);
  const Eigen::Vector3d m = simulated_imu::earthField(50e-6, 1.2, 0.0);
  const Eigen::Matrix3d none = Eigen::Matrix3d::Zero();
  engine.submit(imu(at(0.0), Eigen::Vector3d::Zero()));
  ASSERT_EQ(engine.submitAcceleration(at(0.0), f, none), ap::AidingOutcome::Aligned);
  const int n = static_cast<int>(ap::kMaxPendingMeasurements);
  for (int k = 1; k <= n; ++k) {
    ASSERT_EQ(engine.submitMagneticField(at(0.01 * k + 0.001), m, none), ap::AidingOutcome::Waiting)
        << k;
  }
  EXPECT_EQ(engine.submitAcceleration(at(0.0055), f, none), ap::AidingOutcome::Waiting);
  EXPECT_EQ(engine.counters().mag.queue_full, 1u);
  EXPECT_EQ(engine.counters().accel.queue_full, 0u);
  EXPECT_EQ(engine.pendingMeasurements(), static_cast<std::size_t>(n));
}

// ---- late samples and fixes in one interval ---------------------------------------------------

// Samples 0..n of the tumble at 100 Hz with fixes between samples k and k + 1 (k = 10, 30, ...)
// at fractions `fix_a` of the interval, and gravity samples at the rates' stamps, handed in
// `accel_delay` samples late; with `field_a` >= 0 a field sample in the same interval too, at
// that fraction, handed in `field_delay` samples late. Each fix is handed in with the sample
// `fix_delay[i]` after its interval's start (1: as soon as the rates reach it).
struct InOneInterval {
  std::vector<double> fix_a;
  std::vector<int> fix_delay;
  int accel_delay = 0;
  double field_a = -1.0;
  int field_delay = 1;
};

ap::EngineState runInOneInterval(const InOneInterval& run) {
  ap::EngineConfig c = withFixesConfig();
  c.aiding.mag_stddev = 0.3e-6;
  simulated_imu::Sensor sensor = noisySensor();
  sensor.mag_noise = 0.3e-6;
  const auto samples = simulated_imu::simulate(tumble(), sensor, 1.0);
  const double h = 1.0 / sensor.rate;
  Recorder sink;
  ap::AttitudeEngine engine(c, sink);
  const int n = static_cast<int>(samples.size());
  // Each fix is the truth at its stamp turned by a generic small rotation, with an anisotropic,
  // correlated covariance.
  Eigen::Matrix3d R;
  R << 1.0e-4, 0.3e-4, -0.2e-4, 0.3e-4, 2.5e-4, 0.4e-4, -0.2e-4, 0.4e-4, 0.6e-4;
  const std::vector<Eigen::Vector3d> offsets{
      {0.004, -0.002, 0.006}, {-0.003, 0.005, 0.002}, {0.002, 0.003, -0.005}};
  auto handIn = [&](int k) {
    if (k < n) engine.submit(imu(at(samples[k].t), samples[k].w_B));
    if (k >= run.accel_delay && k - run.accel_delay < n) {
      const auto& s = samples[k - run.accel_delay];
      engine.submitAcceleration(at(s.t), s.f_B, Eigen::Matrix3d::Zero());
    }
    // The intervals with fixes start at samples 10, 30, 50, ...
    auto startsAnInterval = [&](int start) { return start % 20 == 10 && start + 1 < n; };
    for (std::size_t i = 0; i < run.fix_a.size(); ++i) {
      const int start = k - run.fix_delay[i];
      if (!startsAnInterval(start)) continue;
      const double t = samples[start].t + run.fix_a[i] * h;
      // Applied as it arrives (the rates are past its stamp): the order of arrival is the case.
      EXPECT_EQ(engine.submitFix(at(t), tumble().attitude(t) * ap::expMap(offsets[i]), R),
                ap::FixOutcome::Accepted);
    }
    const int start = k - run.field_delay;
    if (run.field_a >= 0.0 && startsAnInterval(start)) {
      // The field at the interval's first sample, stamped a fraction of the interval later.
      EXPECT_EQ(engine.submitMagneticField(at(samples[start].t + run.field_a * h),
                                           samples[start].m_B, Eigen::Matrix3d::Zero()),
                ap::AidingOutcome::Accepted);
    }
  };
  for (int k = 0; k < n + 8; ++k) handIn(k);
  EXPECT_GT(engine.counters().fixes_accepted, 3u);
  return engine.state();
}

// A fix between samples k and k + 1 corrects the entry at k in place. A late gravity sample
// stamped at k, handed in after it, must find that entry as it was without the fix (set back),
// or the fix, applied again after the sample, counts twice: the newest state is the on-time one.
TEST(Late, AGravitySampleBeforeAFixInItsIntervalFindsTheStateWithoutTheFix) {
  InOneInterval on_time{{0.4}, {1}, 0};
  InOneInterval late = on_time;
  late.accel_delay = 4;
  const ap::EngineState a = runInOneInterval(on_time);
  const ap::EngineState b = runInOneInterval(late);
  EXPECT_LE(ap::rotationAngle(a.q_WB, b.q_WB), 1e-9);
  EXPECT_LE((a.P_B - b.P_B).cwiseAbs().maxCoeff(), 1e-12);
}

// Each gravity sample here comes with its rate and is applied at the newest state, after it in
// the history. Two fixes between the same two samples, the later handed in first: when the
// earlier one arrives, the entry the later one changed (the gravity sample's) is set back. The
// newest state is the on-time one (before each entry got an id of its own, the gravity sample's
// kept its slot's old one, the set-back missed it, and the later fix counted twice: 1.5 mrad).
TEST(Late, TwoFixesHandedInReversedAmongGravitySamplesAreTheOnTimeOnes) {
  const ap::EngineState a = runInOneInterval({{0.1, 0.3}, {1, 1}, 0});
  const ap::EngineState b = runInOneInterval({{0.1, 0.3}, {4, 1}, 0});
  EXPECT_LE(ap::rotationAngle(a.q_WB, b.q_WB), 1e-9);
  EXPECT_LE((a.P_B - b.P_B).cwiseAbs().maxCoeff(), 1e-12);
}

// A correction goes before the measurements applied in its interval and stamped after it, and
// interpolates towards the next state as the step gives it without them (docs/design.md §6.9).
// A fix handed in after a field sample stamped later in the same interval: the on-time state
// (before, the fix went after the field sample and towards the state with it: 71 urad).
TEST(Late, ALateFixGoesBeforeAFieldSampleStampedAfterItInItsInterval) {
  const ap::EngineState a = runInOneInterval({{0.3}, {1}, 0, 0.6, 1});
  const ap::EngineState b = runInOneInterval({{0.3}, {3}, 0, 0.6, 1});
  EXPECT_LE(ap::rotationAngle(a.q_WB, b.q_WB), 1e-9);
  EXPECT_LE((a.P_B - b.P_B).cwiseAbs().maxCoeff(), 1e-12);
}

// Two fixes and a field sample in one interval (0.1, 0.3, 0.6 of it): handed in in stamp order,
// or the later fix first, the field sample after it and the earlier fix last, the newest state
// is the same. The field sample was applied with the later fix in the state; when the earlier
// fix arrives, the field's entry must not be where it acts (before: 3.9 mrad off).
TEST(Late, AFieldSampleAfterAFixInItsIntervalIsSetBackWithIt) {
  const ap::EngineState a = runInOneInterval({{0.1, 0.3}, {1, 1}, 0, 0.6, 1});
  const ap::EngineState b = runInOneInterval({{0.1, 0.3}, {4, 1}, 0, 0.6, 2});
  EXPECT_LE(ap::rotationAngle(a.q_WB, b.q_WB), 1e-9);
  EXPECT_LE((a.P_B - b.P_B).cwiseAbs().maxCoeff(), 1e-12);
}

// ---- against a truth ------------------------------------------------------------------------

// The tumble with a MEMS gyro (0.3 deg/s of bias): after 10 s the tilt stays within a degree,
// and the normalised estimation error squared of the tilt averages near its 2 degrees of
// freedom: the covariance says what the error is.
TEST(Truth, TheTiltFollowsTheTruthAndItsCovarianceIsConsistent) {
  ap::EngineConfig c = aidedConfig();
  c.fixes.estimate_gyro_bias = true;
  c.fixes.gyro_bias_stddev = 0.01;
  c.fixes.gyro_bias_random_walk = 1e-5;
  simulated_imu::Sensor sensor;
  sensor.gyro_noise = 0.005;
  c.rate_stddev = sensor.gyro_noise;
  sensor.gyro_bias = 0.3 * kDeg * Eigen::Vector3d(1, -1, 0.5).normalized();
  sensor.accel_noise = 0.05;
  c.aiding.accel_stddev = sensor.accel_noise;
  double sum_nees = 0.0, max_tilt = 0.0;
  int n = 0;
  for (unsigned seed = 1; seed <= 4; ++seed) {
    sensor.seed = seed;
    const auto samples = simulated_imu::simulate(tumble(), sensor, 60.0);
    Recorder sink;
    ap::AttitudeEngine engine(c, sink);
    for (const auto& s : samples) {
      engine.submit(imu(at(s.t), s.w_B));
      engine.submitAcceleration(at(s.t), s.f_B, Eigen::Matrix3d::Zero());
      if (s.t < 10.0) continue;
      const ap::EngineState st = engine.state();
      const Eigen::Vector3d err = ap::logMap(st.q_WB.conjugate() * s.truth);  // body frame
      const Eigen::Matrix<double, 3, 2> B = ap::normalPlane(ap::bodyUp(st.q_WB));
      const Eigen::Vector2d tilt = B.transpose() * err;
      const Eigen::Matrix2d P = B.transpose() * st.P_B * B;
      sum_nees += tilt.dot(P.ldlt().solve(tilt));
      max_tilt = std::max(max_tilt, simulated_imu::tiltError(st.q_WB, s.truth));
      ++n;
    }
  }
  const double nees = sum_nees / n;
  EXPECT_LT(max_tilt, 1.0 * kDeg);
  EXPECT_GT(nees, 1.0);
  EXPECT_LT(nees, 3.5);
}

}  // namespace
