// DynamicPropagator: model selection, the time policy of DESIGN §6, stamp independence of the
// state (DESIGN §4), torque handling, and bad input.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

#include "attitude_propagator/dynamic_propagator.h"
#include "rotation_matchers.h"

namespace ap = attitude_propagator;

namespace {

ap::DynamicConfig freeBodyConfig(ap::Integrator integrator) {
  ap::DynamicConfig config;
  config.body = ap::RigidBody::fromPrincipalMoments({2.0, 1.0, 2.0 / 3.0},
                                                    ap::RigidBody::TriangleInequality::Ignore);
  config.integrator = integrator;
  config.max_step = 0.01;
  config.initial.w_B = Eigen::Vector3d(std::cos(1.1) / 2.0, 0.0, std::sin(1.1) * 1.5);
  return config;
}

void expectSameState(const ap::DynamicState& a, const ap::DynamicState& b, double tol,
                     int line = __builtin_LINE()) {
  SCOPED_TRACE(line);
  EXPECT_NEAR((a.q_WB.coeffs() - b.q_WB.coeffs()).cwiseAbs().maxCoeff(), 0.0, tol);
  EXPECT_NEAR((a.w_B - b.w_B).cwiseAbs().maxCoeff(), 0.0, tol);
}

const std::vector<ap::Integrator> kNumerical = {
    ap::Integrator::Rk4, ap::Integrator::ImplicitMidpoint, ap::Integrator::Splitting,
    ap::Integrator::Splitting4, ap::Integrator::Dopri5};

}  // namespace

TEST(DynPropagator, ModelSelection) {
  ap::DynamicConfig config = freeBodyConfig(ap::Integrator::Auto);
  config.torque_input = true;
  EXPECT_EQ(ap::DynamicPropagator(config).integrator(), ap::Integrator::Rk4);
  EXPECT_EQ(ap::DynamicPropagator(config).modelName(), "numerical_rk4");

  config.torque_input = false;
  config.body = ap::RigidBody::fromPrincipalMoments({2.0, 2.0, 2.0});
  EXPECT_EQ(ap::DynamicPropagator(config).modelName(), "exact_sphere");
  config.body = ap::RigidBody::fromPrincipalMoments({1.0, 2.0, 2.0});
  EXPECT_EQ(ap::DynamicPropagator(config).modelName(), "exact_symmetric_top");

  config.integrator = ap::Integrator::Splitting4;
  EXPECT_EQ(ap::DynamicPropagator(config).modelName(), "numerical_splitting4");
}

TEST(DynPropagator, InvalidConfigurationThrows) {
  ap::DynamicConfig config = freeBodyConfig(ap::Integrator::Exact);
  config.torque_input = true;
  EXPECT_THROW(ap::DynamicPropagator{config}, std::invalid_argument);
  config = freeBodyConfig(ap::Integrator::Cf4);
  EXPECT_THROW(ap::DynamicPropagator{config}, std::invalid_argument);
  config = freeBodyConfig(ap::Integrator::Rk4);
  config.max_step = 0.0;
  EXPECT_THROW(ap::DynamicPropagator{config}, std::invalid_argument);
  config = freeBodyConfig(ap::Integrator::Dopri5);
  config.tolerance = -1.0;
  EXPECT_THROW(ap::DynamicPropagator{config}, std::invalid_argument);
  config = freeBodyConfig(ap::Integrator::Rk4);
  config.torque_timeout = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(ap::DynamicPropagator{config}, std::invalid_argument);
  config = freeBodyConfig(ap::Integrator::Rk4);
  config.initial.q_WB = Eigen::Quaterniond(0.0, 0.0, 0.0, 0.0);
  EXPECT_THROW(ap::DynamicPropagator{config}, std::invalid_argument);
  config = freeBodyConfig(ap::Integrator::Rk4);
  config.initial.w_B.x() = std::numeric_limits<double>::infinity();
  EXPECT_THROW(ap::DynamicPropagator{config}, std::invalid_argument);
}

TEST(DynPropagator, TimePolicy) {
  ap::DynamicConfig config = freeBodyConfig(ap::Integrator::Rk4);
  config.time_policy.max_dt = 0.5;
  config.time_policy.backward_jump = 1.0;
  ap::DynamicPropagator p(config);
  EXPECT_FALSE(p.anchored());

  // The first stamp anchors: the initial state holds there.
  EXPECT_EQ(p.advanceTo(10.0), ap::StampOutcome::Anchored);
  EXPECT_TRUE(p.anchored());
  EXPECT_EQ(p.time(), 10.0);
  expectSameState(p.state(), config.initial, 0.0);

  EXPECT_EQ(p.advanceTo(10.3), ap::StampOutcome::Advanced);
  const ap::DynamicState at_10_3 = p.state();
  EXPECT_GT((at_10_3.w_B - config.initial.w_B).norm(), 1e-3);

  // Stale stamps (equal or a little earlier) do nothing.
  EXPECT_EQ(p.advanceTo(10.3), ap::StampOutcome::DroppedStale);
  EXPECT_EQ(p.advanceTo(9.9), ap::StampOutcome::DroppedStale);
  EXPECT_EQ(p.time(), 10.3);
  expectSameState(p.state(), at_10_3, 0.0);

  // A gap over max_dt is not integrated across: the state holds, time moves on.
  EXPECT_EQ(p.advanceTo(11.0), ap::StampOutcome::HeldGap);
  EXPECT_EQ(p.time(), 11.0);
  expectSameState(p.state(), at_10_3, 0.0);

  // And the propagation continues from there as from an anchor (setState normalises the
  // quaternion it is given: equal to round-off).
  ap::DynamicPropagator q(config);
  q.setState(11.0, at_10_3);
  EXPECT_EQ(p.advanceTo(11.2), ap::StampOutcome::Advanced);
  EXPECT_EQ(q.advanceTo(11.2), ap::StampOutcome::Advanced);
  expectSameState(p.state(), q.state(), 1e-15);

  // Non-finite stamps and values are rejected, the state untouched.
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(p.advanceTo(nan), ap::StampOutcome::RejectedNonFinite);
  EXPECT_EQ(p.setTorque(11.3, Eigen::Vector3d(nan, 0, 0), ap::TorqueFrame::Body),
            ap::StampOutcome::RejectedNonFinite);
  EXPECT_EQ(p.setRate(11.3, Eigen::Vector3d(0, std::numeric_limits<double>::infinity(), 0)),
            ap::StampOutcome::RejectedNonFinite);
  EXPECT_EQ(p.time(), 11.2);
  EXPECT_TRUE(p.state().q_WB.coeffs().allFinite() && p.state().w_B.allFinite());

  // Time going back by more than the threshold resets to the initial state at the new stamp.
  EXPECT_EQ(p.advanceTo(5.0), ap::StampOutcome::ResetBackwardJump);
  EXPECT_EQ(p.time(), 5.0);
  expectSameState(p.state(), config.initial, 0.0);

  p.reset();
  EXPECT_FALSE(p.anchored());
  EXPECT_EQ(p.advanceTo(1.0), ap::StampOutcome::Anchored);
  EXPECT_THROW(p.setState(2.0, ap::DynamicState{Eigen::Quaterniond(0, 0, 0, 0), {}}),
               std::invalid_argument);
}

// DESIGN §4: the state at a stamp does not depend on how the clock got there. One propagator
// visits many irregular stamps, the other only the inputs' stamps and the end; torque samples
// arrive at the same stamps for both (some between grid points, one late).
TEST(DynPropagator, StateAtStampIsIndependentOfIntermediateStamps) {
  for (const ap::Integrator integrator : kNumerical) {
    SCOPED_TRACE(ap::integratorName(integrator));
    ap::DynamicConfig config = freeBodyConfig(integrator);
    config.torque_input = true;
    config.torque_timeout = 0.137;
    config.time_policy.max_dt = 100.0;
    ap::DynamicPropagator bursty(config);
    ap::DynamicPropagator direct(config);
    ASSERT_EQ(bursty.advanceTo(0.0), ap::StampOutcome::Anchored);
    ASSERT_EQ(direct.advanceTo(0.0), ap::StampOutcome::Anchored);

    std::uint64_t state = 42;
    auto uniform = [&state]() {
      state = state * 6364136223846793005ULL + 1442695040888963407ULL;
      return static_cast<double>(state >> 11) * 0x1.0p-53;
    };
    double t = 0.0;
    while (t < 0.4) {
      t += 0.0037 * uniform();
      bursty.advanceTo(t);
    }
    bursty.setTorque(0.4123, Eigen::Vector3d(0.2, -0.1, 0.3), ap::TorqueFrame::Body);
    direct.setTorque(0.4123, Eigen::Vector3d(0.2, -0.1, 0.3), ap::TorqueFrame::Body);
    t = 0.4123;
    while (t < 0.9) {
      t += 0.02 * uniform();
      bursty.advanceTo(t);
    }
    bursty.setTorque(0.91, Eigen::Vector3d(0.0, 0.5, 0.0), ap::TorqueFrame::Fixed);
    direct.setTorque(0.91, Eigen::Vector3d(0.0, 0.5, 0.0), ap::TorqueFrame::Fixed);
    bursty.advanceTo(1.3);
    direct.advanceTo(1.3);
    // A sample that arrives after the clock passed its stamp (but within the current grid
    // step) acts from its stamp, as it does when it comes in time.
    direct.setTorque(1.3031, Eigen::Vector3d(-0.3, 0.0, 0.1), ap::TorqueFrame::Body);
    bursty.advanceTo(1.3045);
    bursty.setTorque(1.3031, Eigen::Vector3d(-0.3, 0.0, 0.1), ap::TorqueFrame::Body);
    t = 1.3045;
    while (t < 2.5) {
      t += 0.011 * uniform();
      bursty.advanceTo(t);
    }
    bursty.advanceTo(2.75);
    direct.advanceTo(2.75);
    expectSameState(bursty.state(), direct.state(), 1e-15);
  }
}

// Constant body torque T along a principal axis from rest: w = T t / I exactly for every
// method (w x I w = 0 on an axis), and a torque that times out stops accelerating the body.
TEST(DynPropagator, TorqueTimeoutZeroesTheTorque) {
  for (const ap::Integrator integrator : kNumerical) {
    SCOPED_TRACE(ap::integratorName(integrator));
    ap::DynamicConfig config = freeBodyConfig(integrator);
    config.initial.w_B.setZero();
    config.torque_input = true;
    config.torque_timeout = 0.5;
    ap::DynamicPropagator p(config);
    p.advanceTo(1.0);
    p.setTorque(1.0, Eigen::Vector3d(0.0, 0.3, 0.0), ap::TorqueFrame::Body);
    for (double t = 1.0; t < 2.0; t += 0.0333) p.advanceTo(t);
    p.advanceTo(2.0);
    EXPECT_NEAR(p.state().w_B.y(), 0.3 * 0.5 / 1.0, 1e-14);
    EXPECT_NEAR(p.state().w_B.x(), 0.0, 1e-15);
    EXPECT_NEAR(p.state().w_B.z(), 0.0, 1e-15);
  }
}
