// The long-double reference of the torqued rigid body (reference_dynamics.h), which the dynamic
// tests judge the integrators against, checked itself against published values (Hairer-Lubich-
// Wanner's free body), closed forms (torque from rest along a principal axis; a fixed-frame
// torque changes the space angular momentum m_W = Q I w at the rate tau_W, whatever the body
// does) and by halving its step.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include <Eigen/Eigenvalues>

#include "reference_dynamics.h"
#include "rotation_matchers.h"
#include "torqued_body.h"

namespace ap = attitude_propagator;
namespace ref = reference_dynamics;

namespace {

/// m_W = q_WB I_B w_B in long double.
ref::Vector3 spaceMomentum(const Eigen::Matrix3d& I_B, const ref::State& x) {
  const Eigen::Quaternion<ref::Real> q(x[0], x[1], x[2], x[3]);
  const ref::Vector3 w(x[4], x[5], x[6]);
  return q.normalized() * ref::Vector3(I_B.cast<ref::Real>() * w);
}

}  // namespace

// HLW's body I = (2, 1, 2/3), M(0) = (cos 1.1, 0, sin 1.1): M(10) and M(100) as published
// (15 digits). Measured differences 3.6e-16 at 10 s, the published values' last digit, and
// 5.5e-15 at 100 s, where the long-double round-off of 10^5 steps has built up to ~1e-15 (half
// the step moves the result by that much) and the input's rounding to doubles (2/3, the rate)
// shifts the phase by a few 1e-15.
TEST(ReferenceDynamics, MatchesPublishedFreeBody) {
  const Eigen::Matrix3d I_B = Eigen::Vector3d(2.0, 1.0, 2.0 / 3.0).asDiagonal();
  ap::DynamicState x0;
  x0.w_B = Eigen::Vector3d(std::cos(1.1) / 2.0, 0.0, std::sin(1.1) * 1.5);
  ref::Trajectory trajectory(I_B, x0, 0.0);
  const Eigen::Vector3d M10 = I_B * trajectory.advanceTo(10.0).w_B;
  EXPECT_LE((M10 - Eigen::Vector3d(0.407066136588041, 0.283007426812843, 0.868449167661562)).norm(),
            1e-15);
  const Eigen::Vector3d M100 = I_B * trajectory.advanceTo(100.0).w_B;
  EXPECT_LE(
      (M100 - Eigen::Vector3d(-0.177348313874983, -0.590418524333421, 0.787371285791935)).norm(),
      1e-14);
}

// Torque T along the principal axis a_B (here the tensor's eigenvector of moment I_a) from rest:
// w = (T t / I_a) a_B, and the body turns about a_B by T t^2 / (2 I_a), for a body torque and for
// a fixed-frame torque along the world image of a_B.
TEST(ReferenceDynamics, TorqueFromRestAlongAPrincipalAxis) {
  const Eigen::Matrix3d I_B = torqued_body::tensor_B();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(I_B);
  const Eigen::Vector3d a_B = eigen.eigenvectors().col(1);
  const double I_a = eigen.eigenvalues()(1);
  ap::DynamicState x0;
  x0.q_WB = torqued_body::initial().q_WB;
  constexpr double T = 0.7;
  constexpr double t = 3.0;
  for (const ap::TorqueFrame frame : {ap::TorqueFrame::Body, ap::TorqueFrame::Fixed}) {
    SCOPED_TRACE(torqued_body::frameName(frame));
    ap::TorqueInput torque;
    torque.frame = frame;
    torque.tau = frame == ap::TorqueFrame::Body ? Eigen::Vector3d(T * a_B)
                                                : Eigen::Vector3d(x0.q_WB * (T * a_B));
    const ap::DynamicState x = ref::solve(I_B, x0, 0.0, t, torque);
    // Measured 6.5e-16 rad/s and 8.5e-16 rad: the rounding of a_B and I_a to doubles.
    EXPECT_LE((x.w_B - T * t / I_a * a_B).norm(), 2e-15);
    EXPECT_ROTATION_NEAR(
        x.q_WB, x0.q_WB * Eigen::Quaterniond(Eigen::AngleAxisd(T * t * t / (2 * I_a), a_B)), 2e-15);
  }
}

// A fixed-frame torque on the spinning asymmetric body: dm_W/dt = tau_W exactly (the Euler
// equations in the world), so m_W(t) = m_W(0) + tau_W t. Measured 4.5e-17 over 10 s (|m_W| up
// to 7.4), far below the doubles' resolution; a torque taken as Q tau_W instead of Q^T tau_W
// breaks it at order one.
TEST(ReferenceDynamics, FixedFrameTorqueChangesTheSpaceMomentumLinearly) {
  const Eigen::Matrix3d I_B = torqued_body::tensor_B();
  const ap::TorqueInput torque = torqued_body::torque(ap::TorqueFrame::Fixed);
  ref::Trajectory trajectory(I_B, torqued_body::initial(), 0.0, {{0.0, torque}});
  const ref::Vector3 m0 = spaceMomentum(I_B, trajectory.state());
  for (int k = 1; k <= 10; ++k) {
    trajectory.advanceTo(k);
    const ref::Vector3 expected = m0 + ref::Real(k) * torque.tau.cast<ref::Real>();
    EXPECT_LE(static_cast<double>((spaceMomentum(I_B, trajectory.state()) - expected).norm()),
              1e-16);
  }
}

// Halving the step of the 8th-order reference changes it by what remains of its error (2^8 - 1
// times the error of the finer). Over 10 s of the torqued scene, between h = 2e-3 and 1e-3:
// measured 1.2e-17 (body torque) and 1.2e-16 (fixed-frame torque), so the reference at 1e-3 is
// exact to ~1e-18, far below the doubles' resolution (1.1e-16) on which the integrators are
// judged.
TEST(ReferenceDynamics, HalvingTheStepChangesNothingAtDoublePrecision) {
  for (const ap::TorqueFrame frame : {ap::TorqueFrame::Body, ap::TorqueFrame::Fixed}) {
    SCOPED_TRACE(torqued_body::frameName(frame));
    const std::vector<ref::TorqueSegment> torques{{0.0, torqued_body::torque(frame)}};
    ref::Trajectory coarse(torqued_body::tensor_B(), torqued_body::initial(), 0.0, torques, 2e-3);
    ref::Trajectory fine(torqued_body::tensor_B(), torqued_body::initial(), 0.0, torques, 1e-3);
    coarse.advanceTo(10.0);
    fine.advanceTo(10.0);
    EXPECT_LE(static_cast<double>(ref::difference(coarse.state(), fine.state())), 3e-16);
  }
}
