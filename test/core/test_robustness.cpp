// Robustness of the core against hostile input: nothing from outside may crash, hang or
// corrupt a propagator. Each reported attack is reproduced through the core API, then a
// randomized property test throws extreme values (1e-300..1e300, denormals, mixed signs, NaN,
// infinities) at every kinematic and dynamic integrator. Bounded time is asserted by counting
// work units (steps, dopri5 trials), never by the clock.
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include "attitude_propagator/config/parameters.h"
#include "attitude_propagator/estimation/orientation_covariance.h"
#include "attitude_propagator/limits.h"
#include "attitude_propagator/models/dynamic_propagator.h"
#include "attitude_propagator/models/kinematic_propagator.h"
#include "attitude_propagator/numerics/dynamic_step.h"
#include "attitude_propagator/numerics/quaternion.h"
#include "attitude_propagator/numerics/torque_free_motion.h"
#include "rotation_matchers.h"

namespace ap = attitude_propagator;
using ap::StampOutcome;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kDenormMin = std::numeric_limits<double>::denorm_min();
const double kSqrtHalf = std::sqrt(0.5);

// A committed quaternion is unit to round-off (the propagators accept sqrt(eps) at most).
constexpr double kUnitTol = 1e-8;

const std::vector<ap::Integrator> kKinematic = ap::integratorsFor(ap::Model::Kinematic);
const std::vector<ap::Integrator> kDynamic = ap::integratorsFor(ap::Model::Dynamic);

ap::DynamicConfig dynamicConfig(ap::Integrator integrator, const Eigen::Vector3d& moments) {
  ap::DynamicConfig config;
  config.body = ap::RigidBody::fromPrincipalMoments(moments);
  config.integrator = integrator;
  config.max_step = 0.01;
  return config;
}

void expectSaneState(const ap::DynamicPropagator& p, int line = __builtin_LINE()) {
  SCOPED_TRACE(line);
  const ap::DynamicState& x = p.state();
  ASSERT_TRUE(x.q_WB.coeffs().allFinite()) << x.q_WB.coeffs().transpose();
  ASSERT_TRUE(x.w_B.allFinite()) << x.w_B.transpose();
  EXPECT_NEAR(x.q_WB.norm(), 1.0, kUnitTol);
  EXPECT_LE(x.w_B.norm(), ap::kMaxStateRate);
  EXPECT_TRUE(std::isfinite(p.kineticEnergy()));
  EXPECT_TRUE(p.angularMomentum_B().allFinite());
}

/// Quaternion coefficients equal to round-off (two ulps of 1).
void expectCoeffsNear(const Eigen::Quaterniond& q, const Eigen::Vector4d& xyzw,
                      int line = __builtin_LINE()) {
  SCOPED_TRACE(line);
  EXPECT_LE((q.coeffs() - xyzw).cwiseAbs().maxCoeff(), 2.0 * std::numeric_limits<double>::epsilon())
      << q.coeffs().transpose();
}

void expectSameState(const ap::DynamicState& a, const ap::DynamicState& b,
                     int line = __builtin_LINE()) {
  SCOPED_TRACE(line);
  EXPECT_EQ(a.q_WB.coeffs(), b.q_WB.coeffs());
  EXPECT_EQ(a.w_B, b.w_B);
}

void expectRejected(const ap::Parameters& p, const std::string& name) {
  try {
    ap::validateParameters(p);
    ADD_FAILURE() << "accepted a bad " << name;
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()).rfind(name + ": ", 0), 0u) << e.what();
  }
}

ap::Parameters dynamicParameters(const std::string& integrator) {
  ap::Parameters p;
  p.inertia = {1.0, 2.0, 3.0};
  p.integrator = integrator;
  return p;
}

}  // namespace

// ---- 1. The exact torque-free model and rates of 1e200 ---------------------------------------

TEST(Robustness, ExactModelRefusesOverflowingRatesAtTheDoor) {
  ap::DynamicPropagator p(dynamicConfig(ap::Integrator::Auto, {1.0, 2.0, 3.0}));
  ASSERT_EQ(p.modelName(), "exact_triaxial");
  EXPECT_EQ(p.advanceTo(1.0), StampOutcome::Anchored);
  const ap::DynamicState before = p.state();
  // Through the node, one rate sample: rejected, counted by the caller, state unchanged.
  EXPECT_EQ(p.setRate(1.01, Eigen::Vector3d::Constant(1e200)), StampOutcome::RejectedOutOfRange);
  EXPECT_EQ(p.time(), 1.0);
  expectSameState(p.state(), before);
  EXPECT_EQ(p.advanceTo(1.5), StampOutcome::Advanced);
  expectSaneState(p);

  // set_state with such a rate: refused, the state untouched.
  const ap::DynamicState at_1_5 = p.state();
  ap::DynamicState fast;
  fast.w_B = Eigen::Vector3d::Constant(1e200);
  EXPECT_THROW(p.setState(2.0, fast), std::invalid_argument);
  expectSameState(p.state(), at_1_5);
  EXPECT_EQ(p.time(), 1.5);
  EXPECT_TRUE(std::isfinite(p.kineticEnergy()));

  // As the initial state: the core and the validator refuse it.
  ap::DynamicConfig config = dynamicConfig(ap::Integrator::Auto, {1.0, 2.0, 3.0});
  config.initial = fast;
  EXPECT_THROW(ap::DynamicPropagator{config}, std::invalid_argument);
  ap::Parameters parameters = dynamicParameters("auto");
  parameters.initial_angular_velocity = {1e200, 1e200, 1e200};
  expectRejected(parameters, "initial_angular_velocity");
  // At the bound itself it is accepted and runs.
  const double w = ap::kMaxBodyRate / std::sqrt(3.0) * (1.0 - 1e-15);
  parameters.initial_angular_velocity = {w, w, w};
  ap::DynamicPropagator at_bound(*ap::validateParameters(parameters).dynamic);
  at_bound.advanceTo(0.0);
  EXPECT_EQ(at_bound.advanceTo(0.5), StampOutcome::Advanced);
  expectSaneState(at_bound);
}

// ---- 2. dopri5 and step-size control ----------------------------------------------------------

TEST(Robustness, Dopri5NeverThrows) {
  ap::DynamicConfig config = dynamicConfig(ap::Integrator::Dopri5, {1.0, 2.0, 3.0});
  ap::DynamicPropagator p(config);
  // The reported samples: the first anchors, the 1e12 rad/s ones are refused at the door.
  EXPECT_EQ(p.setRate(0.0, Eigen::Vector3d(0.1, 0.0, 1.0)), StampOutcome::Anchored);
  EXPECT_EQ(p.setRate(0.01, Eigen::Vector3d(1e12, 0.0, 1.0)), StampOutcome::RejectedOutOfRange);
  EXPECT_EQ(p.setRate(0.02, Eigen::Vector3d(1e12, 0.0, 1.0)), StampOutcome::RejectedOutOfRange);
  EXPECT_EQ(p.advanceTo(0.5), StampOutcome::Advanced);
  expectSaneState(p);

  // Step-size control that cannot succeed (a tolerance below round-off) is refused when the
  // propagator is built, not only by the node's validator.
  config.tolerance = 1e-300;
  EXPECT_THROW(ap::DynamicPropagator{config}, std::invalid_argument);
  config.tolerance = 2.2704045656165723e-318;  // a denormal, found by the fuzzer
  EXPECT_THROW(ap::DynamicPropagator{config}, std::invalid_argument);

  // The stepper itself, given such a tolerance: stepPrincipal throws, tryStepPrincipal
  // reports and leaves x alone.
  config.initial.w_B = Eigen::Vector3d(0.3, 2.0, 0.1);
  const ap::DynamicStepper stepper(ap::Integrator::Dopri5, config.body, 1e-300);
  ap::PrincipalState x = stepper.toPrincipal(config.initial);
  const ap::PrincipalState x0 = x;
  ap::StepInfo info;
  EXPECT_EQ(stepper.tryStepPrincipal(x, {}, 0.01, 1000, &info), ap::StepStatus::NoConvergence);
  EXPECT_EQ(x.q_WP.coeffs(), x0.q_WP.coeffs());
  EXPECT_EQ(x.w_P, x0.w_P);
  EXPECT_THROW(stepper.stepPrincipal(x, {}, 0.01), std::runtime_error);
}

TEST(Robustness, Dopri5StopsAtTheStepBudget) {
  // A fast spin at the tightest accepted tolerance needs ~1e5 sub-steps per second: a call
  // over 0.5 s with a budget of 1000 trials fails within the budget (early, once it is
  // hopeless at the current sub-step size), state held.
  ap::DynamicConfig config = dynamicConfig(ap::Integrator::Dopri5, {1.0, 2.0, 3.0});
  config.tolerance = ap::kMinTolerance;
  config.step_budget = 1000;
  config.initial.w_B = Eigen::Vector3d(0.1, 0.5, 0.3) * ap::kMaxBodyRate;
  ap::DynamicPropagator p(config);
  p.advanceTo(0.0);
  EXPECT_EQ(p.advanceTo(0.5), StampOutcome::FailedStep);
  EXPECT_EQ(p.lastFailure(), ap::StepStatus::OverBudget);
  EXPECT_LE(p.lastCallWork(), config.step_budget);
  EXPECT_GT(p.lastCallWork(), 0u);
  expectSameState(p.state(), config.initial);
  expectSaneState(p);
}

TEST(Robustness, AFailedIntervalIsNotRetriedUntilSomethingChanges) {
  // dopri5 with a tiny budget on a fast spin: the first interval fails after some work; the
  // next ones, with the same state and inputs, fail at once with none; a new torque (an input
  // that changes what the integrator faces) makes it try again.
  ap::DynamicConfig config = dynamicConfig(ap::Integrator::Dopri5, {1.0, 2.0, 3.0});
  config.torque_input = true;
  config.tolerance = ap::kMinTolerance;
  config.step_budget = 1000;
  config.initial.w_B = Eigen::Vector3d(0.1, 0.5, 0.3) * ap::kMaxBodyRate;
  ap::DynamicPropagator p(config);
  p.advanceTo(0.0);
  EXPECT_EQ(p.advanceTo(0.01), StampOutcome::FailedStep);
  EXPECT_GT(p.lastCallWork(), 0u);
  for (int k = 2; k <= 5; ++k) {
    EXPECT_EQ(p.advanceTo(0.01 * k), StampOutcome::FailedStep);
    EXPECT_EQ(p.lastCallWork(), 0u);
    EXPECT_EQ(p.time(), 0.01 * k);
  }
  expectSameState(p.state(), config.initial);
  p.setTorque(0.05, Eigen::Vector3d(1.0, 0.0, 0.0), ap::TorqueFrame::Body);
  EXPECT_EQ(p.advanceTo(0.06), StampOutcome::FailedStep);
  EXPECT_GT(p.lastCallWork(), 0u);  // tried again
  expectSaneState(p);
}

// ---- 3. Configurations that would hang ---------------------------------------------------------

TEST(Robustness, ValidatorRefusesConfigurationsThatWouldHang) {
  ap::Parameters p = dynamicParameters("rk4");
  p.max_step = 1e-12;
  expectRejected(p, "max_step");
  p = dynamicParameters("dopri5");
  p.tolerance = 1e-300;
  expectRejected(p, "tolerance");
  p = dynamicParameters("dopri5");
  p.publish_rate = 1e9;
  expectRejected(p, "publish_rate");
  p = ap::Parameters{};  // the kinematic model too
  p.publish_rate = 1e9;
  expectRejected(p, "publish_rate");
  p = dynamicParameters("rk4");
  p.max_dt = 1e6;
  expectRejected(p, "max_dt");
  p = dynamicParameters("rk4");
  p.max_dt = 60.0;
  p.max_step = 1e-4;  // 6e5 steps per call
  expectRejected(p, "max_step");
  p = dynamicParameters("rk4");
  p.torque_timeout = 1e300;
  expectRejected(p, "torque_timeout");
  p = dynamicParameters("rk4");
  p.inertia = {1e300, 1e300, 1e300};
  expectRejected(p, "inertia");
  p = dynamicParameters("rk4");
  p.inertia = {1e-300, 1e-300, 1e-300};
  expectRejected(p, "inertia");

  // The limits themselves are accepted.
  p = dynamicParameters("dopri5");
  p.publish_rate = ap::kMaxPublishRate;
  p.tolerance = ap::kMinTolerance;
  EXPECT_NO_THROW(ap::validateParameters(p));
  p.tolerance = ap::kMaxTolerance;
  p.max_step = ap::kMinMaxStep;
  EXPECT_NO_THROW(ap::validateParameters(p));
  p.max_dt = ap::kMaxMaxDt;
  p.max_step = ap::kMaxMaxDt / ap::kMaxGridStepsPerCall;
  p.torque_timeout = ap::kMaxTorqueTimeout;
  EXPECT_NO_THROW(ap::validateParameters(p));

  // The core refuses a grid its step budget cannot cross.
  ap::DynamicConfig config = dynamicConfig(ap::Integrator::Rk4, {1.0, 2.0, 3.0});
  config.max_step = 1e-12;
  EXPECT_THROW(ap::DynamicPropagator{config}, std::invalid_argument);
}

// The finest grid the validator accepts costs one step per grid point, within the budget.
TEST(Robustness, FinestAcceptedGridRunsInBoundedSteps) {
  ap::Parameters parameters = dynamicParameters("rk4");
  parameters.max_step = ap::kMinMaxStep;
  parameters.initial_angular_velocity = {0.1, 2.0, 0.0};
  ap::DynamicPropagator p(*ap::validateParameters(parameters).dynamic);
  p.advanceTo(0.0);
  EXPECT_EQ(p.advanceTo(1.0), StampOutcome::Advanced);  // max_dt: the longest forward call
  EXPECT_LE(p.lastCallWork(), 1.0 / ap::kMinMaxStep + ap::kBudgetHeadroomSteps);
  EXPECT_GE(p.lastCallWork(), 1.0 / ap::kMinMaxStep - 1.0);
  expectSaneState(p);
}

// ---- 4. rk4 from an overflowing initial rate; spinning up past the state bound -----------------

TEST(Robustness, Rk4RefusesOverflowingInitialRateAndFailsVisiblyWhenSpunUp) {
  ap::DynamicConfig config = dynamicConfig(ap::Integrator::Rk4, {1.0, 2.0, 3.0});
  config.torque_input = true;
  config.initial.w_B = Eigen::Vector3d::Constant(1e200);
  EXPECT_THROW(ap::DynamicPropagator{config}, std::invalid_argument);
  ap::Parameters parameters = dynamicParameters("rk4");
  parameters.initial_angular_velocity = {1e200, 1e200, 1e200};
  expectRejected(parameters, "initial_angular_velocity");

  // The largest torque on the smallest moment: w grows by 1e28 rad/s^2, past kMaxStateRate
  // within the first grid step. Every such interval is a FailedStep, the state held, never a
  // frozen state full of infinities.
  config.initial.w_B = Eigen::Vector3d::Zero();
  ap::DynamicPropagator p(config);
  EXPECT_EQ(p.setTorque(0.0, Eigen::Vector3d(ap::kMaxTorque, 0.0, 0.0), ap::TorqueFrame::Body),
            StampOutcome::Anchored);
  EXPECT_EQ(
      p.setTorque(0.1, Eigen::Vector3d(2.0 * ap::kMaxTorque, 0.0, 0.0), ap::TorqueFrame::Body),
      StampOutcome::RejectedOutOfRange);
  for (int k = 1; k <= 5; ++k) {
    EXPECT_EQ(p.advanceTo(0.1 * k), StampOutcome::FailedStep);
    EXPECT_EQ(p.lastFailure(), ap::StepStatus::NonFinite);
    EXPECT_EQ(p.time(), 0.1 * k);
    expectSameState(p.state(), config.initial);
    expectSaneState(p);
  }
  EXPECT_EQ(p.failedSteps(), 5u);
  // A torque that can be integrated lets it move on (from its stamp: the interval before it
  // still had the huge one).
  EXPECT_EQ(p.setTorque(0.6, Eigen::Vector3d(0.0, 0.0, 1.0), ap::TorqueFrame::Body),
            StampOutcome::FailedStep);
  EXPECT_EQ(p.advanceTo(0.7), StampOutcome::Advanced);
  // I3 dw3/dt = 1 from rest, exactly integrated by rk4: w3 = 0.1 / 3.
  EXPECT_NEAR(p.state().w_B.z(), 0.1 / 3.0, 1e-15);
}

// ---- 5. Covariances -----------------------------------------------------------------------------

TEST(Robustness, RateCovarianceCheck) {
  using Check = ap::RateCovarianceCheck;
  const Eigen::Matrix3d I = Eigen::Matrix3d::Identity();
  EXPECT_EQ(ap::checkRateCovariance(Eigen::Matrix3d::Zero()), Check::Ok);  // "none given"
  EXPECT_EQ(ap::checkRateCovariance(1e-4 * I), Check::Ok);
  EXPECT_EQ(ap::checkRateCovariance(ap::kMaxRateVariance * I), Check::Ok);
  EXPECT_EQ(ap::checkRateCovariance(-0.5 * I), Check::NegativeVariance);
  EXPECT_EQ(ap::checkRateCovariance(1e308 * I), Check::VarianceTooLarge);
  Eigen::Matrix3d R = 1e-4 * I;
  R(0, 1) = 5e-5;
  EXPECT_EQ(ap::checkRateCovariance(R), Check::NotSymmetric);
  R(1, 0) = 5e-5;
  EXPECT_EQ(ap::checkRateCovariance(R), Check::Ok);
  R(0, 1) = R(1, 0) = 2e-4;  // correlation 2
  EXPECT_EQ(ap::checkRateCovariance(R), Check::NotACovariance);
  R = 1e-4 * I;
  R(2, 2) = kNaN;
  EXPECT_EQ(ap::checkRateCovariance(R), Check::NonFinite);
  EXPECT_STREQ(ap::rateCovarianceCheckName(Check::NegativeVariance), "negative_variance");

  ap::Parameters p;
  p.angular_velocity_stddev = 1e308;
  expectRejected(p, "angular_velocity_stddev");
  p.angular_velocity_stddev = kNaN;
  expectRejected(p, "angular_velocity_stddev");
  p.angular_velocity_stddev = ap::kMaxRateStddev;
  EXPECT_NO_THROW(ap::validateParameters(p));
}

// Whatever the rate noise, the orientation covariance stays symmetric, semi-definite and
// below the ceiling: negative or huge variances cannot make it negative or overflow.
TEST(Robustness, OrientationCovarianceStaysACovariance) {
  const Eigen::Vector3d w(0.3, -0.2, 1.0);
  for (const double variance : {-0.5, 1e308, 1e6, -1e308}) {
    SCOPED_TRACE(variance);
    const Eigen::Matrix3d R = variance * Eigen::Matrix3d::Identity();
    Eigen::Matrix3d P = Eigen::Matrix3d::Zero();
    for (int k = 0; k < 1000; ++k) {
      P = ap::propagateOrientationCovariance(P, 0.01, w, R);
      ASSERT_TRUE(P.allFinite());
      ASSERT_EQ(P, P.transpose());
      ASSERT_GE(P.diagonal().minCoeff(), 0.0);
      ASSERT_LE(P.diagonal().maxCoeff(), ap::kMaxOrientationVariance);
      const Eigen::Vector3d lambda =
          Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(P).eigenvalues();
      ASSERT_GE(lambda.minCoeff(), -1e-15 * ap::kMaxOrientationVariance);
      ASSERT_LE(lambda.maxCoeff(), ap::kMaxOrientationVariance * (1.0 + 1e-15));
    }
  }
  // At rest the random walk h^2 sigma^2 per step saturates at the ceiling: isotropic noise
  // gives pi^2 I, "no knowledge", exactly.
  Eigen::Matrix3d P = Eigen::Matrix3d::Zero();
  for (int k = 0; k < 100; ++k) {
    P = ap::propagateOrientationCovariance(P, 1.0, Eigen::Vector3d::Zero(),
                                           Eigen::Matrix3d::Identity());
  }
  EXPECT_LT((P - ap::kMaxOrientationVariance * Eigen::Matrix3d::Identity()).norm(), 1e-14);
  // Non-finite input: the ceiling.
  EXPECT_EQ(ap::propagateOrientationCovariance(P, kInf, w, Eigen::Matrix3d::Identity()),
            ap::kMaxOrientationVariance * Eigen::Matrix3d::Identity());
}

// ---- 6, 7. Quaternions at any scale
// --------------------------------------------------------------

TEST(Robustness, SafeNormalizedAtAnyScale) {
  // Eigen's 4-argument constructor is (w, x, y, z).
  const auto unit = [](double w, double x, double y, double z) {
    return ap::safeNormalized(Eigen::Quaterniond(w, x, y, z));
  };
  ASSERT_TRUE(unit(1e200, 0, 0, 1e200));
  expectCoeffsNear(*unit(1e200, 0, 0, 1e200), Eigen::Vector4d(0, 0, kSqrtHalf, kSqrtHalf));
  EXPECT_EQ(unit(1e-300, 0, 0, 0)->coeffs(), Eigen::Vector4d(0, 0, 0, 1));
  EXPECT_EQ(unit(0, kDenormMin, 0, 0)->coeffs(), Eigen::Vector4d(1, 0, 0, 0));
  EXPECT_EQ(unit(0, 0, -std::numeric_limits<double>::max(), 0)->coeffs(),
            Eigen::Vector4d(0, -1, 0, 0));
  EXPECT_NEAR(unit(3e-310, 4e-310, 0, 0)->norm(), 1.0, 1e-15);  // denormal components
  EXPECT_FALSE(unit(0, 0, 0, 0));
  EXPECT_FALSE(unit(1, kNaN, 0, 0));
  EXPECT_FALSE(unit(kInf, 0, 0, 0));
}

TEST(Robustness, SettersAndValidatorNormaliseAtAnyScale) {
  // DynamicPropagator::setState with q = (1e200, 0, 0, 1e200): a unit quaternion, never zero.
  for (const ap::Integrator integrator : kDynamic) {
    SCOPED_TRACE(ap::integratorName(integrator));
    ap::DynamicConfig config = dynamicConfig(integrator, {1.0, 2.0, 3.0});
    ap::DynamicPropagator p(config);
    p.setState(1.0, ap::DynamicState{Eigen::Quaterniond(1e200, 0, 0, 1e200), {0.1, 0.2, 0.3}});
    expectCoeffsNear(p.state().q_WB, Eigen::Vector4d(0, 0, kSqrtHalf, kSqrtHalf));
    p.setState(2.0, ap::DynamicState{Eigen::Quaterniond(1e-300, 0, 0, 0), {}});
    EXPECT_EQ(p.state().q_WB.coeffs(), Eigen::Vector4d(0, 0, 0, 1));
    EXPECT_EQ(p.advanceTo(2.5), StampOutcome::Advanced);
    expectSaneState(p);
    // Refused without a trace.
    const ap::DynamicState before = p.state();
    EXPECT_THROW(p.setState(3.0, ap::DynamicState{Eigen::Quaterniond(0, 0, 0, 0), {}}),
                 std::invalid_argument);
    EXPECT_THROW(p.setState(3.0, ap::DynamicState{Eigen::Quaterniond(kNaN, 0, 0, 1), {}}),
                 std::invalid_argument);
    EXPECT_THROW(p.setState(3.0, ap::DynamicState{{}, {0.0, 2.0 * ap::kMaxBodyRate, 0.0}}),
                 std::invalid_argument);
    expectSameState(p.state(), before);
    EXPECT_EQ(p.time(), 2.5);
  }

  ap::KinematicPropagator k(ap::KinematicConfig{});
  k.setState(1.0, Eigen::Quaterniond(1e-300, 0, 0, 0), Eigen::Vector3d::Zero());
  EXPECT_EQ(k.orientation().coeffs(), Eigen::Vector4d(0, 0, 0, 1));
  k.setState(1.0, Eigen::Quaterniond(1e200, 0, 0, 1e200), Eigen::Vector3d::Zero());
  expectCoeffsNear(k.orientation(), Eigen::Vector4d(0, 0, kSqrtHalf, kSqrtHalf));
  EXPECT_THROW(k.setState(2.0, Eigen::Quaterniond::Identity(), Eigen::Vector3d::Constant(1e200)),
               std::invalid_argument);
  expectCoeffsNear(k.orientation(), Eigen::Vector4d(0, 0, kSqrtHalf, kSqrtHalf));

  ap::Parameters p;
  p.initial_orientation = {1e300, 1e300, 0.0, 0.0};
  expectCoeffsNear(ap::validateParameters(p).kinematic.initial_q_WB,
                   Eigen::Vector4d(kSqrtHalf, kSqrtHalf, 0, 0));
  p.initial_orientation = {0.0, 0.0, 0.0, 1e-300};
  EXPECT_EQ(ap::validateParameters(p).kinematic.initial_q_WB.coeffs(), Eigen::Vector4d(0, 0, 0, 1));
  p.initial_orientation = {0.0, 0.0, 0.0, 0.0};
  expectRejected(p, "initial_orientation");
}

TEST(Robustness, KinematicRefusesRatesBeyondTheDoor) {
  for (const ap::Integrator integrator : kKinematic) {
    SCOPED_TRACE(ap::integratorName(integrator));
    ap::KinematicConfig config;
    config.integrator = integrator;
    ap::KinematicPropagator k(config);
    EXPECT_EQ(k.addSample(0.0, Eigen::Vector3d(0.0, 0.0, 1.0)), StampOutcome::Anchored);
    EXPECT_EQ(k.addSample(0.1, Eigen::Vector3d::Constant(1e200)), StampOutcome::RejectedOutOfRange);
    EXPECT_EQ(k.addSample(0.1, Eigen::Vector3d(ap::kMaxBodyRate * 1.01, 0, 0)),
              StampOutcome::RejectedOutOfRange);
    EXPECT_EQ(k.time(), 0.0);
    EXPECT_EQ(k.orientation().coeffs(), Eigen::Vector4d(0, 0, 0, 1));
    EXPECT_EQ(k.addSample(0.1, Eigen::Vector3d(ap::kMaxBodyRate, 0, 0)), StampOutcome::Advanced);
    EXPECT_TRUE(k.orientation().coeffs().allFinite());
    EXPECT_NEAR(k.orientation().norm(), 1.0, kUnitTol);
  }
}

// ---- Randomized property test over extreme inputs ----------------------------------------------

namespace {

/// A value from everywhere in the doubles: zeros, denormals, NaN, infinities, magnitudes
/// log-uniform over 1e-300..1e300, and (so that integration also happens) moderate ones
/// around the door bounds, each with a random sign.
double extremeValue(std::uint64_t& s) {
  const double u = uniformRandom(s);
  const double sign = uniformRandom(s) < 0.5 ? -1.0 : 1.0;
  if (u < 0.05) return 0.0;
  if (u < 0.08) return sign * kDenormMin * std::floor(1.0 + 1e6 * uniformRandom(s));
  if (u < 0.10) return kNaN;
  if (u < 0.12) return sign * kInf;
  if (u < 0.50) return sign * std::pow(10.0, -300.0 + 600.0 * uniformRandom(s));
  return sign * std::pow(10.0, -3.0 + 8.5 * uniformRandom(s));  // 1e-3..3e5
}

Eigen::Vector3d extremeVector(std::uint64_t& s) {
  return Eigen::Vector3d(extremeValue(s), extremeValue(s), extremeValue(s));
}

/// The next stamp: mostly ordinary forward steps, plus denormal and huge steps, stale and
/// backward stamps, gaps, and non-finite stamps.
double nextStamp(double t, std::uint64_t& s) {
  static const double kDeltas[] = {kDenormMin, 1e-300, 1e-12, 1e-3,  0.01,   0.037, 0.2,  0.99,
                                   1.5,        -1e-3,  -3.0,  1e300, -1e300, kNaN,  kInf, 0.0};
  constexpr int kCount = sizeof(kDeltas) / sizeof(kDeltas[0]);
  const double u = uniformRandom(s);
  if (u < 0.7) return t + 0.05 * uniformRandom(s);  // ordinary
  return t + kDeltas[static_cast<int>(uniformRandom(s) * kCount) % kCount];
}

bool finiteAndAbove(const Eigen::Vector3d& v, double bound) {
  return v.allFinite() && !(v.norm() <= bound);
}

}  // namespace

TEST(RobustnessProperty, DynamicIntegratorsSurviveExtremeInput) {
  const std::vector<std::vector<double>> bodies = {
      {1.0, 2.0, 3.0},         {2.0, 2.0, 2.0},    {1.0, 2.0, 2.0},
      {1e-15, 1.5e-15, 2e-15}, {5e14, 6e14, 1e15}, {1.0, 2.0, 2.5, 0.1, -0.2, 0.05}};
  std::uint64_t seed = 20240611;
  for (const ap::Integrator integrator : kDynamic) {
    for (const auto& inertia : bodies) {
      SCOPED_TRACE(ap::integratorName(integrator) + " inertia[0] " + std::to_string(inertia[0]));
      ap::DynamicConfig config;
      config.body = ap::RigidBody::fromParameter(inertia);
      config.integrator = integrator;
      const bool takes_torque = ap::integratorInfo(integrator).takes_torque;
      config.torque_input = takes_torque;
      config.max_step = 0.01;
      config.step_budget = 2000;  // keeps the test short; the default is 2^17
      config.initial.w_B = Eigen::Vector3d(0.1, 1.0, 0.2);
      ap::DynamicPropagator p(config);
      for (int call = 0; call < 400; ++call) {
        const ap::DynamicState before = p.state();
        const double t_before = p.time();
        const double t = nextStamp(p.time(), seed);
        const double u = uniformRandom(seed);
        StampOutcome outcome = StampOutcome::DroppedStale;
        bool out_of_range = false;
        bool non_finite = !std::isfinite(t);
        try {
          if (u < 0.3) {
            outcome = p.advanceTo(t);
          } else if (u < 0.65) {
            const Eigen::Vector3d w = extremeVector(seed);
            non_finite = non_finite || !w.allFinite();
            out_of_range = !non_finite && finiteAndAbove(w, ap::kMaxBodyRate);
            outcome = p.setRate(t, w);
          } else if (u < 0.9 && takes_torque) {
            const Eigen::Vector3d tau = extremeVector(seed);
            non_finite = non_finite || !tau.allFinite();
            out_of_range = !non_finite && finiteAndAbove(tau, ap::kMaxTorque);
            const auto frame =
                uniformRandom(seed) < 0.5 ? ap::TorqueFrame::Body : ap::TorqueFrame::Fixed;
            outcome = p.setTorque(t, tau, frame);
          } else {
            const Eigen::Quaterniond q(extremeValue(seed), extremeValue(seed), extremeValue(seed),
                                       extremeValue(seed));
            try {
              p.setState(t, ap::DynamicState{q, extremeVector(seed)});
            } catch (const std::invalid_argument&) {
              expectSameState(p.state(), before);  // refused without a trace
            }
            expectSaneState(p);
            continue;
          }
        } catch (const std::exception& e) {
          FAIL() << "call " << call << " threw " << e.what();
        }
        SCOPED_TRACE("call " + std::to_string(call) + " outcome " + ap::outcomeName(outcome));
        expectSaneState(p);
        EXPECT_LE(p.lastCallWork(), config.step_budget);
        if (non_finite) {
          EXPECT_EQ(outcome, StampOutcome::RejectedNonFinite);
        }
        if (out_of_range) {
          EXPECT_EQ(outcome, StampOutcome::RejectedOutOfRange);
        }
        if (!ap::stateHoldsAtStamp(outcome)) {
          expectSameState(p.state(), before);
          EXPECT_EQ(p.time(), t_before);
        } else {
          // At the stamp; an input a little late (placed behind time()) leaves time() alone.
          if (t > t_before) {
            EXPECT_EQ(p.time(), t);
          } else {
            EXPECT_TRUE(p.time() == t || p.time() == t_before) << p.time();
          }
        }
        if (HasFailure()) return;
      }
    }
  }
}

TEST(RobustnessProperty, KinematicIntegratorsSurviveExtremeInput) {
  std::uint64_t seed = 7;
  for (const ap::Integrator integrator : kKinematic) {
    SCOPED_TRACE(ap::integratorName(integrator));
    ap::KinematicConfig config;
    config.integrator = integrator;
    ap::KinematicPropagator k(config);
    for (int call = 0; call < 4000; ++call) {
      const Eigen::Quaterniond before = k.orientation();
      const double t = nextStamp(k.time(), seed);
      StampOutcome outcome = StampOutcome::DroppedStale;
      try {
        if (uniformRandom(seed) < 0.95) {
          const Eigen::Vector3d w = extremeVector(seed);
          outcome = k.addSample(t, w);
          SCOPED_TRACE("call " + std::to_string(call) + " outcome " + ap::outcomeName(outcome));
          if (!std::isfinite(t) || !w.allFinite()) {
            EXPECT_EQ(outcome, StampOutcome::RejectedNonFinite);
          } else if (finiteAndAbove(w, ap::kMaxBodyRate)) {
            EXPECT_EQ(outcome, StampOutcome::RejectedOutOfRange);
          }
          if (!ap::stateHoldsAtStamp(outcome)) {
            EXPECT_EQ(k.orientation().coeffs(), before.coeffs());
          }
        } else {
          const Eigen::Quaterniond q(extremeValue(seed), extremeValue(seed), extremeValue(seed),
                                     extremeValue(seed));
          try {
            k.setState(t, q, extremeVector(seed));
          } catch (const std::invalid_argument&) {
            EXPECT_EQ(k.orientation().coeffs(), before.coeffs());
          }
        }
      } catch (const std::exception& e) {
        FAIL() << "call " << call << " threw " << e.what();
      }
      ASSERT_TRUE(k.orientation().coeffs().allFinite()) << "call " << call;
      ASSERT_NEAR(k.orientation().norm(), 1.0, kUnitTol) << "call " << call;
      ASSERT_TRUE(k.rate().allFinite());
      ASSERT_LE(k.rate().norm(), ap::kMaxBodyRate);
    }
  }
}

// The exact triaxial motion at rates whose squares leave the doubles: by the scaling law of
// the Euler equations, w(t; s w0) = s w(s t; w0) and q(t; s w0) = q(s t; w0), so the motion
// from 2^-600 w0 at 2^600 t is the motion from w0 at t with the rate scaled (the latter on
// the unscaled path that the other tests check against a numerical reference).
TEST(Robustness, ExactTriaxialAtAnyRateScale) {
  const ap::RigidBody body = ap::RigidBody::fromPrincipalMoments({1.0, 2.0, 3.0});
  const ap::DynamicState x0{Eigen::Quaterniond(0.9, 0.1, -0.3, 0.2).normalized(),
                            Eigen::Vector3d(0.3, 1.0, 0.2)};
  const ap::TorqueFreeMotion reference(body, x0);
  for (const int exponent : {-1000, -600, -100, 60}) {
    SCOPED_TRACE(exponent);
    ap::DynamicState scaled = x0;
    for (int i = 0; i < 3; ++i) scaled.w_B[i] = std::ldexp(x0.w_B[i], exponent);
    const ap::TorqueFreeMotion motion(body, scaled);
    for (const double t : {0.5, 3.7, 11.0}) {
      const ap::DynamicState expected = reference.evaluate(t);
      const ap::DynamicState x = motion.evaluate(std::ldexp(t, -exponent));
      EXPECT_ROTATION_NEAR(x.q_WB, expected.q_WB, 1e-14);
      for (int i = 0; i < 3; ++i) {
        EXPECT_NEAR(std::ldexp(x.w_B[i], -exponent), expected.w_B[i], 1e-14);
      }
    }
  }
  // Denormal rates: at most |w| t = 1e-323 rad turned, so the state is the initial one to
  // round-off (of the closed form's composition of rotations, and of the denormal rates).
  ap::DynamicConfig config = dynamicConfig(ap::Integrator::Exact, {1.0, 2.0, 3.0});
  config.initial.w_B = Eigen::Vector3d(kDenormMin, 3.0 * kDenormMin, 0.0);
  ap::DynamicPropagator p(config);
  p.advanceTo(0.0);
  EXPECT_EQ(p.advanceTo(0.9), StampOutcome::Advanced);
  EXPECT_ROTATION_NEAR(p.state().q_WB, config.initial.q_WB,
                       4.0 * std::numeric_limits<double>::epsilon());
  EXPECT_LE((p.state().w_B - config.initial.w_B).cwiseAbs().maxCoeff(), 2.0 * kDenormMin);
}
