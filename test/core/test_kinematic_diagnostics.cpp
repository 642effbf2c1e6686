// The kinematic propagator's diagnostics against counted events and closed forms: steps()
// (integration steps since the last anchor, as AttitudeState's `steps`), normError() (|q| - 1
// of the last step before renormalisation) and filledSamples(), and the refusal of a step
// whose result is not finite.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "attitude_propagator/models/kinematic_propagator.h"
#include "integrator_cases.h"

namespace ap = attitude_propagator;
using ap::StampOutcome;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kEps = std::numeric_limits<double>::epsilon();
const Eigen::Vector3d kSpin(0.3, -0.4, 1.2);  // rad/s, |w| = 1.3

ap::KinematicConfig configFor(ap::Integrator method) {
  ap::KinematicConfig config;
  config.integrator = method;
  config.time_policy.max_dt = 0.5;
  config.time_policy.backward_jump = 1.0;
  return config;
}

// A rate that changes from sample to sample, for the norm-error closed forms.
Eigen::Vector3d varyingRate(int k) {
  return Eigen::Vector3d(std::sin(0.7 * k), 2.0 * std::cos(0.3 * k), 1.0 + 0.5 * std::sin(k));
}

// Uneven sample intervals between 0.02 s and 0.4 s.
double unevenInterval(int k) { return 0.02 + 0.38 * ((k * 7919) % 17) / 17.0; }

class EveryKinematicMethod : public ::testing::TestWithParam<ap::Integrator> {};

}  // namespace

// steps() counts the Advanced outcomes since the last anchor (the first sample, a gap, a jump
// back, setState); refused and dropped samples do not count, reset() clears it.
TEST_P(EveryKinematicMethod, StepsCountTheIntervalsIntegratedSinceTheAnchor) {
  ap::KinematicPropagator p(configFor(GetParam()));
  EXPECT_EQ(p.steps(), 0u);
  // 11 samples accepted: the first anchors, each other closes one interval.
  for (int k = 0; k <= 10; ++k) p.addSample(0.1 * k, kSpin);
  EXPECT_EQ(p.steps(), 10u);
  EXPECT_EQ(p.addSample(1.0, kSpin), StampOutcome::DroppedStale);
  EXPECT_EQ(p.addSample(1.1, Eigen::Vector3d(kNaN, 0, 0)), StampOutcome::RejectedNonFinite);
  EXPECT_EQ(p.addSample(1.1, Eigen::Vector3d(2e5, 0, 0)), StampOutcome::RejectedOutOfRange);
  EXPECT_EQ(p.steps(), 10u);
  EXPECT_EQ(p.addSample(1.1, kSpin), StampOutcome::Advanced);
  EXPECT_EQ(p.steps(), 11u);
  // A gap re-anchors: counting starts again.
  EXPECT_EQ(p.addSample(2.0, kSpin), StampOutcome::HeldGap);
  EXPECT_EQ(p.steps(), 0u);
  for (int k = 1; k <= 3; ++k) EXPECT_EQ(p.addSample(2.0 + 0.1 * k, kSpin), StampOutcome::Advanced);
  EXPECT_EQ(p.steps(), 3u);
  EXPECT_EQ(p.addSample(0.5, kSpin), StampOutcome::DroppedStale);
  EXPECT_EQ(p.steps(), 3u);
  p.reset();
  EXPECT_EQ(p.addSample(0.5, kSpin), StampOutcome::Anchored);
  EXPECT_EQ(p.steps(), 0u);
  for (int k = 1; k <= 4; ++k) p.addSample(0.5 + 0.1 * k, kSpin);
  EXPECT_EQ(p.steps(), 4u);
  p.setState(5.0, Eigen::Quaterniond::Identity(), kSpin);
  EXPECT_EQ(p.steps(), 0u);
  p.addSample(5.25, kSpin);
  p.addSample(5.5, kSpin);
  EXPECT_EQ(p.steps(), 2u);
  p.reset();
  EXPECT_EQ(p.steps(), 0u);
  EXPECT_EQ(p.normError(), 0.0);
}

INSTANTIATE_TEST_SUITE_P(Kinematic, EveryKinematicMethod,
                         ::testing::ValuesIn(ap::integratorsFor(ap::Model::Kinematic)),
                         integrator_cases::MethodName());

// Interval-averaged samples after a lost one: the filled-in interval is a step of its own.
TEST(KinematicDiagnostics, AFilledSampleIsAStep) {
  ap::KinematicConfig config = configFor(ap::Integrator::Cf4);
  config.rate_samples = ap::RateSamples::IntervalAverage;
  ap::KinematicPropagator p(config);
  for (int k = 0; k <= 5; ++k) p.addSample(0.01 * k, kSpin);
  EXPECT_EQ(p.steps(), 5u);
  EXPECT_EQ(p.addSample(0.07, kSpin), StampOutcome::Advanced);  // the sample at 0.06 is lost
  EXPECT_EQ(p.filledSamples(), 1u);
  EXPECT_EQ(p.steps(), 7u);
  EXPECT_EQ(p.addSample(0.08, kSpin), StampOutcome::Advanced);
  EXPECT_EQ(p.filledSamples(), 1u);
  EXPECT_EQ(p.steps(), 8u);
}

// euler's step q (x) (1, (0, h w/2)) from a unit q has the norm sqrt(1 + (|w| h/2)^2)
// (docs/numerics.md §2), with w the rate of the sample opening the interval (instantaneous
// samples) or closing it (interval averages); normError() reports that before renormalising.
TEST(KinematicDiagnostics, EulerNormErrorIsTheStepsGrowth) {
  for (const ap::RateSamples kind :
       {ap::RateSamples::Instantaneous, ap::RateSamples::IntervalAverage}) {
    SCOPED_TRACE(ap::rateSamplesName(kind));
    ap::KinematicConfig config = configFor(ap::Integrator::Euler);
    config.rate_samples = kind;
    config.max_gap_fill = 0;  // the uneven intervals are not lost samples
    ap::KinematicPropagator p(config);
    double t = 0.0;
    p.addSample(t, varyingRate(0));
    for (int k = 1; k <= 40; ++k) {
      const double h = unevenInterval(k);
      t += h;
      ASSERT_EQ(p.addSample(t, varyingRate(k)), StampOutcome::Advanced);
      const Eigen::Vector3d w = varyingRate(kind == ap::RateSamples::Instantaneous ? k - 1 : k);
      const double half_angle = 0.5 * h * w.norm();
      // Measured at most 1.1e-16; bound 4 eps.
      EXPECT_NEAR(p.normError(), std::sqrt(1.0 + half_angle * half_angle) - 1.0, 4 * kEps)
          << "k = " << k;
    }
  }
}

// rk4 at a constant rate is q (x) p(u), p(u) = 1 + u + u^2/2 + u^3/6 + u^4/24 at the pure
// quaternion u = (0, h w/2) with u^2 = -z^2, z = |w| h/2: |p|^2 = 1 - z^6/72 + z^8/576
// (docs/numerics.md §2), a loss of norm.
TEST(KinematicDiagnostics, Rk4NormErrorIsItsStabilityPolynomial) {
  ap::KinematicPropagator p(configFor(ap::Integrator::Rk4));
  double t = 0.0;
  p.addSample(t, kSpin);
  for (int k = 1; k <= 40; ++k) {
    const double h = unevenInterval(k);
    t += h;
    ASSERT_EQ(p.addSample(t, kSpin), StampOutcome::Advanced);
    const double z = 0.5 * h * kSpin.norm();
    const double z6 = z * z * z * z * z * z;
    // Measured at most 1.1e-16; bound 4 eps.
    EXPECT_NEAR(p.normError(), std::sqrt(1.0 - z6 / 72.0 + z6 * z * z / 576.0) - 1.0, 4 * kEps)
        << "k = " << k;
  }
}

// A step whose result overflows (a finite stamp 1e300 s ahead: euler's and rk4's polynomial
// steps leave the doubles) is refused as RejectedNonFinite and leaves no trace: the state, its
// time, steps() and normError() are unchanged, and the samples that follow are integrated bit
// for bit as if it had never come.
class PolynomialSteps : public ::testing::TestWithParam<ap::Integrator> {};

TEST_P(PolynomialSteps, ANonFiniteStepIsRefusedAndLeavesNoTrace) {
  ap::KinematicConfig config = configFor(GetParam());
  config.time_policy.max_dt = 1e301;  // so that the stamp 1e300 is an interval, not a gap
  ap::KinematicPropagator p(config), twin(config);
  // Samples 0.1 us apart: intervals under 1 us are no period of the stream
  // (kinematic_propagator.h), so no mean period is known and the stamp 1e300 is not a dropout
  // either.
  const double dt = 1e-7;
  for (int k = 0; k <= 5; ++k) {  // the window is full and evicts on the next push
    p.addSample(dt * k, varyingRate(k));
    twin.addSample(dt * k, varyingRate(k));
  }
  const Eigen::Quaterniond before = p.orientation();
  const double norm_error = p.normError();
  EXPECT_EQ(p.addSample(1e300, varyingRate(6)), StampOutcome::RejectedNonFinite);
  EXPECT_EQ(p.orientation().coeffs(), before.coeffs());
  EXPECT_EQ(p.time(), 5 * dt);
  EXPECT_EQ(p.rate(), varyingRate(5));
  EXPECT_EQ(p.steps(), 5u);
  EXPECT_EQ(p.normError(), norm_error);
  for (int k = 6; k <= 9; ++k) {
    EXPECT_EQ(p.addSample(0.1 * k, varyingRate(k)), StampOutcome::Advanced);
    twin.addSample(0.1 * k, varyingRate(k));
    EXPECT_EQ(p.orientation().coeffs(), twin.orientation().coeffs()) << "k = " << k;
    EXPECT_EQ(p.normError(), twin.normError());
  }
  EXPECT_EQ(p.steps(), 9u);
}

// The methods whose step is a polynomial in h (no unit-norm guarantee): the ones that can
// overflow.
INSTANTIATE_TEST_SUITE_P(Kinematic, PolynomialSteps,
                         ::testing::ValuesIn(integrator_cases::methodsWhere(
                             ap::Model::Kinematic,
                             [](const ap::IntegratorInfo& row) {
                               return (row.keeps & ap::keeps::kUnitNorm) == 0;
                             })),
                         integrator_cases::MethodName());
