// The exact torque-free motion against published values (Hairer-Lubich-Wanner's free body,
// docs/numerics.md §8), the textbook's modulus, rate and period (landau_lifshitz.h), and an
// independent tight numerical reference (free_body_reference.h): Bulirsch-Stoer in long
// double on the Euler equations written with the full inertia tensor in the user's frame (no
// principal axes, no sorting), after the start and, by time reversal, before it. The flip
// times near the middle axis are in test_dzhanibekov_flip.cpp.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <vector>

#include "attitude_propagator/numerics/torque_free_motion.h"
#include "free_body_reference.h"
#include "landau_lifshitz.h"
#include "rotation_matchers.h"

namespace ap = attitude_propagator;
namespace ll = landau_lifshitz;

namespace {

using free_body_reference::BackwardReference;
using free_body_reference::TensorReference;

using Ignore = ap::RigidBody::TriangleInequality;

/// Which way from t0 a comparison runs.
enum class Direction { Forward, Backward };

/// Largest attitude error (rad) and rate error (relative to max(1, |w0|)) along a run.
struct Deviation {
  double q = 0.0;
  double w = 0.0;
};

/// The exact motion through x0 at t0 against the reference, every `every` seconds over `span`
/// seconds after t0 or before it (the reference then runs by time reversal).
Deviation deviationFromReference(const ap::RigidBody& body, const ap::DynamicState& x0, double span,
                                 double every, Direction direction, double t0 = 0.0) {
  const ap::TorqueFreeMotion exact(body, x0, t0);
  TensorReference forward(body.tensor_B(), x0);
  BackwardReference backward(body.tensor_B(), x0);
  const bool ahead = direction == Direction::Forward;
  Deviation worst;
  for (double s = 0.0; s <= span + 1e-9; s += every) {
    const ap::DynamicState a = exact.evaluate(ahead ? t0 + s : t0 - s);
    const ap::DynamicState b = ahead ? forward.advanceTo(s) : backward.before(s);
    worst.q = std::max(worst.q, ap::rotationAngle(a.q_WB, b.q_WB));
    worst.w = std::max(worst.w, (a.w_B - b.w_B).norm() / std::max(1.0, x0.w_B.norm()));
  }
  return worst;
}

/// Compares the exact motion with the reference every `every` seconds up to t_end after the
/// start and as far before it (evaluate() takes any t).
void expectMatchesReference(const ap::RigidBody& body, const ap::DynamicState& x0, double t_end,
                            double tol, double every = 5.0) {
  for (const Direction direction : {Direction::Forward, Direction::Backward}) {
    SCOPED_TRACE(direction == Direction::Forward ? "forward" : "backward");
    const Deviation worst = deviationFromReference(body, x0, t_end, every, direction);
    EXPECT_LE(worst.q, tol) << "attitude error (rad)";
    EXPECT_LE(worst.w, tol) << "relative rate error";
  }
}

ap::DynamicState stateWithMomentum(const ap::RigidBody& body, const Eigen::Vector3d& M_B,
                                   const Eigen::Quaterniond& q = Eigen::Quaterniond::Identity()) {
  ap::DynamicState x;
  x.q_WB = q;
  x.w_B = body.tensor_B().inverse() * M_B;
  return x;
}

}  // namespace

// docs/numerics.md §8: I = (2, 1, 2/3), M0 = (cos 1.1, 0, sin 1.1). Their body frame is ours (P =
// B), so M(t) compares component by component.
TEST(DynTorqueFree, HairerLubichWannerPublishedValues) {
  const ap::RigidBody body =
      ap::RigidBody::fromPrincipalMoments({2.0, 1.0, 2.0 / 3.0}, Ignore::Ignore);
  const ap::DynamicState x0 =
      stateWithMomentum(body, Eigen::Vector3d(std::cos(1.1), 0.0, std::sin(1.1)));
  const ap::TorqueFreeMotion motion(body, x0);
  EXPECT_EQ(motion.form(), ap::TorqueFreeMotion::Form::Triaxial);
  EXPECT_EQ(motion.regime(), ap::TorqueFreeMotion::Regime::AboutSmallest);  // their 3rd axis
  EXPECT_NEAR(motion.modulus(), 0.508968105239, 1e-12);
  EXPECT_NEAR(std::abs(motion.lambda()), 0.630178767743, 1e-12);
  EXPECT_NEAR(motion.bodyPeriod(), 10.731465234882, 1e-11);
  // The same three from the textbook formulas (energy and |M| only, K by the AGM).
  // Measured: equal in double; bounds a few ulps.
  const ll::EllipticMotion truth = ll::ellipticMotion(body.principalMoments(), x0.w_B);
  EXPECT_NEAR(motion.modulus(), double(std::sqrt(truth.k2)), 1e-15);
  EXPECT_NEAR(std::abs(motion.lambda()), double(truth.frequency), 2e-15);
  EXPECT_NEAR(motion.bodyPeriod(), double(truth.period), 2e-15 * double(truth.period));

  const Eigen::Vector3d M10 = body.angularMomentum_B(motion.evaluate(10.0).w_B);
  const Eigen::Vector3d M100 = body.angularMomentum_B(motion.evaluate(100.0).w_B);
  EXPECT_NEAR((M10 - Eigen::Vector3d(0.407066136588041, 0.283007426812843, 0.868449167661562))
                  .cwiseAbs()
                  .maxCoeff(),
              0.0, 5e-15);  // measured 6.7e-16
  EXPECT_NEAR((M100 - Eigen::Vector3d(-0.177348313874983, -0.590418524333421, 0.787371285791935))
                  .cwiseAbs()
                  .maxCoeff(),
              0.0, 1e-14);  // measured 1.6e-15
}

TEST(DynTorqueFree, FreeBodyMatchesReference) {
  const ap::RigidBody body =
      ap::RigidBody::fromPrincipalMoments({2.0, 1.0, 2.0 / 3.0}, Ignore::Ignore);
  std::uint64_t seed = 3;
  expectMatchesReference(body,
                         stateWithMomentum(body, Eigen::Vector3d(std::cos(1.1), 0.0, std::sin(1.1)),
                                           randomUnitQuaternion(seed)),
                         100.0, 2e-13);  // measured 3.9e-14 rad, 4.7e-15 (rate)
}

TEST(DynTorqueFree, BothSidesOfTheSeparatrixMatchReference) {
  const ap::RigidBody body = ap::RigidBody::fromPrincipalMoments({1.0, 2.0, 3.0});
  std::uint64_t seed = 5;
  // Delta2 = M3^2/3 - M1^2: negative about e1 (case i), positive about e3 (case ii).
  const ap::DynamicState about_smallest =
      stateWithMomentum(body, {1.0, 0.3, 0.4}, randomUnitQuaternion(seed));
  const ap::DynamicState about_largest =
      stateWithMomentum(body, {-0.2, 0.5, -1.0}, randomUnitQuaternion(seed));
  EXPECT_EQ(ap::TorqueFreeMotion(body, about_smallest).regime(),
            ap::TorqueFreeMotion::Regime::AboutSmallest);
  EXPECT_EQ(ap::TorqueFreeMotion(body, about_largest).regime(),
            ap::TorqueFreeMotion::Regime::AboutLargest);
  // Measured: 1.5e-14 rad and 1e-14 rad, rates 3e-15; bound 1e-13.
  expectMatchesReference(body, about_smallest, 100.0, 1e-13);
  expectMatchesReference(body, about_largest, 100.0, 1e-13);
}

namespace {

// On body (1, 2, 3), M = (M1, 1, M3) with Delta2 = M3^2/3 - M1^2 = side * 1e-6 relative: just
// inside (side -1) or outside (+1) the separatrix, at a random attitude.
ap::DynamicState nearTheSeparatrix(const ap::RigidBody& body, double side, std::uint64_t& seed) {
  const double M1 = 0.5;
  const double M3 = std::sqrt(3.0) * M1 * std::sqrt(1.0 + side * 1e-6);
  return stateWithMomentum(body, {M1, 1.0, M3}, randomUnitQuaternion(seed));
}

}  // namespace

TEST(DynTorqueFree, NearTheSeparatrixMatchesReference) {
  const ap::RigidBody body = ap::RigidBody::fromPrincipalMoments({1.0, 2.0, 3.0});
  std::uint64_t seed = 11;
  for (const double side : {-1.0, 1.0}) {
    const ap::DynamicState x0 = nearTheSeparatrix(body, side, seed);
    SCOPED_TRACE(side);
    // Measured: 1.2e-11 rad forward, 7.9e-11 rad backward (rates 6e-11); bound 3e-10. Both
    // peak at the flips and are the reference's: run at tolerances 1e-16, 1e-17, 1e-18 its
    // deviation there spreads over 1e-11 to 1.7e-10 with no trend, while the exact motion is
    // symmetric under time reversal to the last bit (ExactTimeReversalNearTheSeparatrix).
    expectMatchesReference(body, x0, 100.0, 3e-10, 2.5);
  }
}

// The free body is reversible: the state s before x0 is the reversal (q, -w) of the state s
// after the reversed (q0, -w0) (free_body_reference.h). The exact motion keeps that near the
// separatrix, where the comparison with the reference is loosest.
TEST(DynTorqueFree, ExactTimeReversalNearTheSeparatrix) {
  const ap::RigidBody body = ap::RigidBody::fromPrincipalMoments({1.0, 2.0, 3.0});
  std::uint64_t seed = 11;
  for (const double side : {-1.0, 1.0}) {
    const ap::DynamicState x0 = nearTheSeparatrix(body, side, seed);
    const ap::TorqueFreeMotion motion(body, x0);
    const ap::TorqueFreeMotion reversed_motion(body, free_body_reference::reversed(x0));
    SCOPED_TRACE(side);
    for (double s = 0.0; s <= 100.0; s += 2.5) {
      const ap::DynamicState before = motion.evaluate(-s);
      const ap::DynamicState mirrored = free_body_reference::reversed(reversed_motion.evaluate(s));
      // Measured: 0 (the same operations on numbers of opposite signs); bound a few ulps.
      EXPECT_ROTATION_NEAR(before.q_WB, mirrored.q_WB, 1e-15);
      EXPECT_NEAR((before.w_B - mirrored.w_B).norm(), 0.0, 1e-15);
    }
  }
}

TEST(DynTorqueFree, OnTheSeparatrixMatchesReference) {
  // I = (1, 3, 6), w = (0.75, 0.2, 0.25): Delta2 = I3 I32 w3^2 - I1 I21 w1^2 = 18 w3^2 -
  // 2 w1^2 = 0 exactly.
  const ap::RigidBody body = ap::RigidBody::fromPrincipalMoments({1.0, 3.0, 6.0}, Ignore::Ignore);
  std::uint64_t seed = 17;
  ap::DynamicState x0;
  x0.q_WB = randomUnitQuaternion(seed);
  x0.w_B = Eigen::Vector3d(0.75, 0.2, 0.25);
  const ap::TorqueFreeMotion motion(body, x0);
  EXPECT_EQ(motion.regime(), ap::TorqueFreeMotion::Regime::Separatrix);
  // The separatrix is unstable: perturbations of 1e-16 grow like exp(lambda t), so compare
  // while lambda t stays below ~12.
  // Measured: 2.3e-13 rad, rates 1.9e-13; bound 1e-12.
  expectMatchesReference(body, x0, 10.0 / motion.lambda() * 1.2, 1e-12, 1.0);
}

TEST(DynTorqueFree, SymmetricTopSphereAndTensorMatchReference) {
  std::uint64_t seed = 23;
  // Measured: at most 2.5e-14 rad, rates 3.5e-15 (the sphere's rate exactly); bound 1e-13.
  const ap::RigidBody prolate = ap::RigidBody::fromPrincipalMoments({2.0, 2.0, 1.0});
  const ap::RigidBody oblate = ap::RigidBody::fromPrincipalMoments({3.0, 2.0, 3.0});
  const ap::RigidBody sphere = ap::RigidBody::fromPrincipalMoments({1.5, 1.5, 1.5});
  EXPECT_EQ(ap::TorqueFreeMotion(prolate, {}).form(), ap::TorqueFreeMotion::Form::SymmetricTop);
  EXPECT_EQ(ap::TorqueFreeMotion(sphere, {}).form(), ap::TorqueFreeMotion::Form::Sphere);
  expectMatchesReference(prolate,
                         stateWithMomentum(prolate, {0.3, -0.4, 1.0}, randomUnitQuaternion(seed)),
                         100.0, 1e-13);
  expectMatchesReference(oblate,
                         stateWithMomentum(oblate, {0.3, -0.4, 1.0}, randomUnitQuaternion(seed)),
                         100.0, 1e-13);
  expectMatchesReference(sphere,
                         stateWithMomentum(sphere, {0.3, -0.4, 1.0}, randomUnitQuaternion(seed)),
                         100.0, 1e-13);
  // A full tensor: principal axes rotated away from the body axes.
  const Eigen::Matrix3d R = randomUnitQuaternion(seed).toRotationMatrix();
  const Eigen::Matrix3d I_B = R * Eigen::Vector3d(1.0, 2.5, 3.0).asDiagonal() * R.transpose();
  const ap::RigidBody tensor = ap::RigidBody::fromTensor(I_B);
  expectMatchesReference(tensor,
                         stateWithMomentum(tensor, {0.7, 0.2, -0.5}, randomUnitQuaternion(seed)),
                         100.0, 1e-13);
}

// Evaluations far ahead cost the same and stay consistent: the state at t2 from the motion
// through the state at t1 equals the state at t2 directly.
TEST(DynTorqueFree, RestartingFromAnEvaluatedStateIsConsistent) {
  const ap::RigidBody body = ap::RigidBody::fromPrincipalMoments({1.0, 2.0, 3.0});
  std::uint64_t seed = 29;
  const ap::DynamicState x0 = stateWithMomentum(body, {1.0, 0.3, 0.4}, randomUnitQuaternion(seed));
  const ap::TorqueFreeMotion motion(body, x0);
  const ap::DynamicState x1 = motion.evaluate(1234.5);
  const ap::TorqueFreeMotion restarted(body, x1, 1234.5);
  const ap::DynamicState a = motion.evaluate(1300.0);
  const ap::DynamicState b = restarted.evaluate(1300.0);
  // Measured: 1.4e-13 rad, 1.4e-14; bounds 1e-12, 1e-13.
  EXPECT_ROTATION_NEAR(a.q_WB, b.q_WB, 1e-12);
  EXPECT_NEAR((a.w_B - b.w_B).norm(), 0.0, 1e-13);
}

// Before t0: the motion through a state at t0 = 1000 s, compared with the reference run
// backward from that state by time reversal, and forward as well (tau = t - t0 either way).
TEST(DynTorqueFree, BeforeALaterStartMatchesReference) {
  const ap::RigidBody body = ap::RigidBody::fromPrincipalMoments({1.0, 2.0, 3.0});
  std::uint64_t seed = 37;
  const ap::DynamicState x0 = stateWithMomentum(body, {1.0, 0.3, 0.4}, randomUnitQuaternion(seed));
  for (const Direction direction : {Direction::Forward, Direction::Backward}) {
    const Deviation worst = deviationFromReference(body, x0, 100.0, 5.0, direction, 1000.0);
    // Measured: 1.9e-14 rad, rates 2.4e-15; bound 1e-13.
    EXPECT_LE(worst.q, 1e-13);
    EXPECT_LE(worst.w, 1e-13);
  }
}

// Rates far from 1 rad/s are set up at order one and the time scaled; times before t0 take
// the same path. Truth: the reference at order one and the scaling law of the free body,
// w(t; c w0) = c w(c t; w0), q(t; c w0) = q(c t; w0).
TEST(DynTorqueFree, BeforeTheStartAtRatesFarFromOne) {
  const ap::RigidBody body = ap::RigidBody::fromPrincipalMoments({1.0, 2.0, 3.0});
  std::uint64_t seed = 41;
  const ap::DynamicState x1 =
      stateWithMomentum(body, {-0.2, 0.5, -1.0}, randomUnitQuaternion(seed));
  for (const double c : {0x1.0p-40, 0x1.0p+40}) {
    SCOPED_TRACE(c);
    const ap::TorqueFreeMotion motion(body, {x1.q_WB, c * x1.w_B});
    BackwardReference reference(body.tensor_B(), x1);
    double worst_q = 0.0, worst_w = 0.0;
    for (double s = 0.0; s <= 50.0; s += 5.0) {
      const ap::DynamicState a = motion.evaluate(-s / c);
      const ap::DynamicState b = reference.before(s);
      worst_q = std::max(worst_q, ap::rotationAngle(a.q_WB, b.q_WB));
      worst_w = std::max(worst_w, (a.w_B / c - b.w_B).norm());
    }
    // Measured: 4.6e-15 rad, rates 7.2e-16 relative; bound 3e-14.
    EXPECT_LE(worst_q, 3e-14);
    EXPECT_LE(worst_w, 3e-14);
  }
}

// Back and forth: the motion through the state it gives at t0 - s leads back to x0 at t0, in
// every form and regime.
TEST(DynTorqueFree, BackAndForthReturnsToTheStart) {
  const ap::RigidBody triaxial = ap::RigidBody::fromPrincipalMoments({1.0, 2.0, 3.0});
  const ap::RigidBody top = ap::RigidBody::fromPrincipalMoments({3.0, 2.0, 3.0});
  const ap::RigidBody sphere = ap::RigidBody::fromPrincipalMoments({1.5, 1.5, 1.5});
  const ap::RigidBody lamina = ap::RigidBody::fromPrincipalMoments({1.0, 3.0, 6.0}, Ignore::Ignore);
  std::uint64_t seed = 43;
  const Eigen::Quaterniond q0 = randomUnitQuaternion(seed);
  struct Case {
    const ap::RigidBody& body;
    Eigen::Vector3d w;
  };
  // Triaxial about the smallest axis, about the largest, on the separatrix (Delta2 = 0
  // exactly, as in OnTheSeparatrixMatchesReference); a top; a sphere. On the separatrix the
  // state s before t0 nears the middle axis like exp(-lambda s) (lambda = 0.59 here): 1e-10
  // of |w| off that axis at 40 s (test_torque_free_precision.cpp looks at that state closer).
  const Case cases[] = {{triaxial, {1.0, 0.15, 0.4 / 3.0}},
                        {triaxial, {-0.2, 0.25, -1.0 / 3.0}},
                        {lamina, {0.75, 0.2, 0.25}},
                        {top, {0.1, -0.2, 0.3}},
                        {sphere, {0.1, -0.2, 0.3}}};
  constexpr double t0 = 250.0;
  for (const Case& c : cases) {
    const ap::DynamicState x0{q0, c.w};
    const ap::TorqueFreeMotion motion(c.body, x0, t0);
    SCOPED_TRACE(motion.formName());
    for (const double s : {0.5, 7.0, 40.0}) {
      const ap::DynamicState earlier = motion.evaluate(t0 - s);
      const ap::DynamicState back = ap::TorqueFreeMotion(c.body, earlier, t0 - s).evaluate(t0);
      // Measured: at most 5.5e-15 rad (top, 40 s), 4.9e-15 (separatrix, 7 s), rates 1.8e-15
      // (separatrix, 40 s); bound 3e-14.
      EXPECT_ROTATION_NEAR(back.q_WB, x0.q_WB, 3e-14);
      EXPECT_NEAR((back.w_B - x0.w_B).norm(), 0.0, 3e-14);
    }
  }
}
