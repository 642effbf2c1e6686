// Negative steps of the dynamic integrators (a step h "may be zero or negative", dynamic_step.h)
// against truths that do not come from the integrators: the free body's time reversal (a step
// of -h from (q, w) is the reversal of a step of h from (q, -w), for any one-step method built
// on the right-hand side), a backward reference integration (free_body_reference.h), the
// declared orders, and the symmetric methods' property that a step of -h undoes a step of h.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "attitude_propagator/numerics/dynamic_step.h"
#include "free_body_reference.h"
#include "integrator_cases.h"
#include "rotation_matchers.h"

namespace ap = attitude_propagator;
using free_body_reference::BackwardReference;
using free_body_reference::reversed;

namespace {

// A triaxial body in a general attitude, its principal axes turned away from the body axes,
// so that the frame conversions take part.
ap::RigidBody tiltedBody() {
  std::uint64_t seed = 53;
  const Eigen::Matrix3d R = randomUnitQuaternion(seed).toRotationMatrix();
  return ap::RigidBody::fromTensor(R * Eigen::Vector3d(1.0, 2.0, 2.5).asDiagonal() * R.transpose());
}

ap::DynamicState startState() {
  std::uint64_t seed = 59;
  return {randomUnitQuaternion(seed), Eigen::Vector3d(0.4, -0.7, 0.9)};
}

/// Largest attitude error (rad) along n steps of -h from x0 against the backward reference.
double backwardError(ap::Integrator method, double h, int n, double tolerance = 1e-9) {
  const ap::RigidBody body = tiltedBody();
  const ap::DynamicStepper stepper(method, body, tolerance);
  BackwardReference reference(body.tensor_B(), startState());
  ap::DynamicState x = startState();
  double worst = 0.0;
  for (int i = 1; i <= n; ++i) {
    x = stepper.step(x, {}, -h);
    worst = std::max(worst, ap::rotationAngle(x.q_WB, reference.before(i * h).q_WB));
  }
  return worst;
}

double largestStateDifference(const ap::DynamicState& a, const ap::DynamicState& b) {
  return std::max(ap::rotationAngle(a.q_WB, b.q_WB), (a.w_B - b.w_B).norm());
}

// Every dynamic method, and the ones that are symmetric (a step of -h is the inverse of a step
// of h): the implicit midpoint rule, the Strang splitting and its symmetric composition.
const std::vector<ap::Integrator> kAll = ap::integratorsFor(ap::Model::Dynamic);
const std::vector<ap::Integrator> kSymmetric = {
    ap::Integrator::ImplicitMidpoint, ap::Integrator::Splitting, ap::Integrator::Splitting4};

}  // namespace

// Time reversal, step by step: step(x, -h) = reversed(step(reversed(x), h)) for every method.
// Negation is exact, so only the methods' own rounding may differ.
TEST(DynBackwardSteps, ANegativeStepIsTheReversedForwardStep) {
  const ap::RigidBody body = tiltedBody();
  for (const ap::Integrator method : kAll) {
    SCOPED_TRACE(ap::integratorName(method));
    const ap::DynamicStepper backward_stepper(method, body, 1e-10);
    const ap::DynamicStepper forward_stepper(method, body, 1e-10);
    ap::DynamicState back = startState();
    ap::DynamicState forth = reversed(startState());
    double worst = 0.0;
    for (int i = 0; i < 50; ++i) {
      back = backward_stepper.step(back, {}, -0.1);
      forth = forward_stepper.step(forth, {}, 0.1);
      worst = std::max(worst, largestStateDifference(back, reversed(forth)));
    }
    // Measured: 0 (bit for bit) for every method; bound a few ulps.
    EXPECT_LE(worst, 1e-15);
  }
}

// Backward runs converge to the backward reference at the declared order: halving h divides
// the largest attitude error along 10 s by at least minHalvingRatio(p).
TEST(DynBackwardSteps, NegativeStepsConvergeAtTheDeclaredOrder) {
  for (const ap::Integrator method : kAll) {
    const int order = ap::declaredOrder(method, ap::Model::Dynamic);
    if (order == 0) continue;  // adaptive or exact: below
    SCOPED_TRACE(ap::integratorName(method));
    const double coarse = backwardError(method, 0.1, 100);
    const double fine = backwardError(method, 0.05, 200);
    const double finer = backwardError(method, 0.025, 400);
    // Measured (h = 0.1, 0.05, 0.025): rk4 2.1e-6, 1.3e-7, 7.9e-9; implicit_midpoint 5.9e-3,
    // 1.5e-3, 3.7e-4; splitting 9.3e-4, 2.3e-4, 5.8e-5; splitting4 2.5e-6, 1.6e-7, 9.8e-9.
    const double bound = integrator_cases::minHalvingRatio(order);
    EXPECT_GE(coarse / fine, bound) << coarse << " " << fine;
    EXPECT_GE(fine / finer, bound) << fine << " " << finer;
    EXPECT_NEAR(std::log2(fine / finer), order, 0.3);
  }
}

// dopri5 meets its tolerance backward, and the exact solution is exact backward.
TEST(DynBackwardSteps, AdaptiveAndExactStepsBackwardMatchTheReference) {
  for (const double tolerance : {1e-6, 1e-10}) {
    const double error = backwardError(ap::Integrator::Dopri5, 0.1, 100, tolerance);
    // Measured: 3.7e-9 at 1e-6, 1.25e-10 at 1e-10; bound 10 tolerance.
    EXPECT_LE(error, 10.0 * tolerance);
  }
  const double exact = backwardError(ap::Integrator::Exact, 0.1, 100);
  EXPECT_LE(exact, 1e-12);  // measured 1.75e-13 rad over 10 s
}

// A symmetric method's step of -h undoes its step of h (to round-off); rk4, not symmetric,
// leaves its local error h^5.
TEST(DynBackwardSteps, SymmetricMethodsUndoAStep) {
  const ap::RigidBody body = tiltedBody();
  for (const ap::Integrator method : kSymmetric) {
    SCOPED_TRACE(ap::integratorName(method));
    const ap::DynamicStepper stepper(method, body);
    const ap::DynamicState x0 = startState();
    const ap::DynamicState there = stepper.step(x0, {}, 0.2);
    const ap::DynamicState back = stepper.step(there, {}, -0.2);
    // Measured: 1.1e-15 to 1.5e-15; bound 1e-14.
    EXPECT_LE(largestStateDifference(back, x0), 1e-14);
  }
  const ap::DynamicStepper rk4(ap::Integrator::Rk4, body);
  const ap::DynamicState x0 = startState();
  const double rk4_defect = largestStateDifference(rk4.step(rk4.step(x0, {}, 0.2), {}, -0.2), x0);
  EXPECT_GT(rk4_defect, 1e-8);  // measured 2.4e-7
}

// The exact stepper, asked for a step back from the state it produced last, returns along the
// same closed form (the propagator keeps principal states, as here): forward then as far
// backward lands on the start, whose time along the motion sums back to zero exactly.
TEST(DynBackwardSteps, ExactStepsBackRetraceTheirPath) {
  const ap::RigidBody body = tiltedBody();
  const ap::DynamicStepper stepper(ap::Integrator::Exact, body);
  const ap::PrincipalState x0 = stepper.toPrincipal(startState());
  ap::PrincipalState x = x0;
  for (int i = 0; i < 70; ++i) stepper.stepPrincipal(x, {}, 0.1);
  for (int i = 0; i < 70; ++i) stepper.stepPrincipal(x, {}, -0.1);
  const double error = std::max(ap::rotationAngle(x.q_WP, x0.q_WP), (x.w_P - x0.w_P).norm());
  EXPECT_LE(error, 1e-15);  // measured 1.5e-16
}
