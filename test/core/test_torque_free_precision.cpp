// The exact torque-free motion close to the unstable middle axis, where the components of M
// off that axis are tiny: the attitude against the independent long-double reference
// (free_body_reference.h) at several distances d from the axis, on both sides of the
// separatrix, and the motion through a state that the separatrix brought within 1e-10 of the
// middle axis, which must lead back to where that state came from.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "attitude_propagator/numerics/torque_free_motion.h"
#include "free_body_reference.h"
#include "rotation_matchers.h"

namespace ap = attitude_propagator;

namespace {

using free_body_reference::BackwardReference;
using free_body_reference::TensorReference;

/// Largest attitude error (rad), rate error (rad/s) and error of the rate's components off the
/// middle axis, relative to their size.
struct Deviation {
  double q = 0.0;
  double w = 0.0;
  double off_axis = 0.0;
};

/// The error of the rate's components off the middle axis (body y: B = P here), relative to
/// their size.
double offAxisError(const Eigen::Vector3d& w, const Eigen::Vector3d& truth) {
  return std::hypot(w.x() - truth.x(), w.z() - truth.z()) / std::hypot(truth.x(), truth.z());
}

/// The exact motion through x0 against the reference, every `every` seconds over `span`
/// seconds after the start and before it.
Deviation bothWaysFromReference(const ap::RigidBody& body, const ap::DynamicState& x0, double span,
                                double every) {
  const ap::TorqueFreeMotion exact(body, x0);
  TensorReference forward(body.tensor_B(), x0);
  BackwardReference backward(body.tensor_B(), x0);
  Deviation worst;
  for (double s = 0.0; s <= span + 1e-9; s += every) {
    const ap::DynamicState ahead = forward.advanceTo(s);
    const ap::DynamicState behind = backward.before(s);
    const ap::DynamicState a = exact.evaluate(s);
    const ap::DynamicState b = exact.evaluate(-s);
    worst.q = std::max(
        {worst.q, ap::rotationAngle(a.q_WB, ahead.q_WB), ap::rotationAngle(b.q_WB, behind.q_WB)});
    worst.w = std::max({worst.w, (a.w_B - ahead.w_B).norm(), (b.w_B - behind.w_B).norm()});
    worst.off_axis =
        std::max({worst.off_axis, offAxisError(a.w_B, ahead.w_B), offAxisError(b.w_B, behind.w_B)});
  }
  return worst;
}

}  // namespace

// I = (1, 2, 3), w0 = (d, 0.5, c d): Delta2 = I3 I32 w3^2 - I1 I21 w1^2 = (3 c^2 - 1) d^2, so
// c = 2/3 circulates about the largest axis and c = 1/3 about the smallest, with m_c ~ d^2.
// Over 20 s (lambda t ~ 6) the off-axis components grow from d to ~ 400 d: the whole run stays
// near the middle axis, where the Jacobi amplitude is close to pi/2 and cn, dn are of order d.
TEST(DynTorqueFreePrecision, NearTheMiddleAxisKeepsTheAttitude) {
  const ap::RigidBody body = ap::RigidBody::fromPrincipalMoments({1.0, 2.0, 3.0});
  std::uint64_t seed = 47;
  for (const double c : {2.0 / 3.0, 1.0 / 3.0}) {
    for (const double d : {1e-7, 1e-9, 1e-10, 1e-12}) {
      ap::DynamicState x0;
      x0.q_WB = randomUnitQuaternion(seed);
      x0.w_B = Eigen::Vector3d(d, 0.5, c * d);
      const ap::TorqueFreeMotion motion(body, x0);
      ASSERT_EQ(motion.regime(), c > 0.5 ? ap::TorqueFreeMotion::Regime::AboutLargest
                                         : ap::TorqueFreeMotion::Regime::AboutSmallest);
      SCOPED_TRACE(::testing::Message() << "c = " << c << ", d = " << d);
      const Deviation worst = bothWaysFromReference(body, x0, 20.0, 0.5);
      // Measured: at most 6.5e-14 rad, rates 1.7e-16 rad/s, the small rates 1.9e-14 relative
      // (before the Landen steps kept cn and dn relative: 4.4e-5 rad at d = 1e-12, 1.2e-9 at
      // d = 1e-7); bounds 3e-13, 1e-15, 1e-13.
      EXPECT_LE(worst.q, 3e-13) << "attitude error (rad)";
      EXPECT_LE(worst.w, 1e-15) << "rate error (rad/s)";
      EXPECT_LE(worst.off_axis, 1e-13) << "relative error of the small rates";
    }
  }
}

// On the separatrix (I = (1, 3, 6), w = (0.75, 0.2, 0.25), Delta2 = 18 w3^2 - 2 w1^2 = 0
// exactly) the state 40 s before t0 lies within 1.2e-10 of the middle axis (the off-axis
// components shrink like exp(-lambda s), lambda = 0.59), on an elliptic orbit with m_c of the
// order of its round-off. The motion through that state must give it back at its own start,
// small components included, and lead back to the state at t0 (the free body is
// deterministic). The state 40 s before is not too ill-conditioned for this: the reference run
// from it returns to the state at t0 within 2e-13 rad and rad/s (measured).
TEST(DynTorqueFreePrecision, SeparatrixBackAndForthOverFortySeconds) {
  const ap::RigidBody lamina = ap::RigidBody::fromPrincipalMoments(
      {1.0, 3.0, 6.0}, ap::RigidBody::TriangleInequality::Ignore);
  std::uint64_t seed = 43;
  const ap::DynamicState x0{randomUnitQuaternion(seed), Eigen::Vector3d(0.75, 0.2, 0.25)};
  constexpr double t0 = 250.0;
  const ap::TorqueFreeMotion motion(lamina, x0, t0);
  ASSERT_EQ(motion.regime(), ap::TorqueFreeMotion::Regime::Separatrix);
  for (const double s : {7.0, 20.0, 40.0}) {
    SCOPED_TRACE(s);
    const ap::DynamicState earlier = motion.evaluate(t0 - s);
    const ap::TorqueFreeMotion restarted(lamina, earlier, t0 - s);
    // Measured (s = 7, 20, 40 s; the largest): at its own start 2.8e-16 rad, the small rates
    // 4.9e-15 relative (before: 14 relative and 2.1e-9 rad at 40 s); back at t0 4.9e-15 rad,
    // 1.8e-15 rad/s (before: 1.36 rad). Bounds 2e-15, 3e-14, 3e-14, 1e-14.
    const ap::DynamicState start = restarted.evaluate(t0 - s);
    EXPECT_ROTATION_NEAR(start.q_WB, earlier.q_WB, 2e-15);
    EXPECT_LE(offAxisError(start.w_B, earlier.w_B), 3e-14);
    const ap::DynamicState back = restarted.evaluate(t0);
    EXPECT_ROTATION_NEAR(back.q_WB, x0.q_WB, 3e-14);
    EXPECT_NEAR((back.w_B - x0.w_B).norm(), 0.0, 1e-14);
  }
}
