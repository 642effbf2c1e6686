// Kinematic integrators against closed forms: constant rate (exact for the Lie-group methods)
// and the coning motion (measured orders of convergence).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "attitude_propagator/coning_motion.h"
#include "attitude_propagator/kinematic_propagator.h"
#include "attitude_propagator/kinematic_step.h"
#include "attitude_propagator/quaternion.h"
#include "integrator_cases.h"
#include "rotation_matchers.h"

namespace ap = attitude_propagator;
using ap::ConingMotion;
using ap::Integrator;

namespace {

constexpr double kEps = std::numeric_limits<double>::epsilon();

// Closed form for a constant body rate w from q0: q0 (x) (cos(|w|t/2), sin(|w|t/2) w/|w|),
// written with std::cos/std::sin rather than the expMap under test.
Eigen::Quaterniond constantRateTruth(const Eigen::Quaterniond& q0, const Eigen::Vector3d& w,
                                     double t) {
  const double angle = w.norm() * t;
  const Eigen::Vector3d axis = w.normalized();
  const Eigen::Quaterniond turn(std::cos(angle / 2), std::sin(angle / 2) * axis.x(),
                                std::sin(angle / 2) * axis.y(), std::sin(angle / 2) * axis.z());
  return q0 * turn;
}

ap::KinematicPropagator makePropagator(Integrator method, const Eigen::Quaterniond& q0) {
  ap::KinematicConfig config;
  config.integrator = method;
  config.initial_q_WB = q0;
  config.time_policy.max_dt = 1e3;  // the sweeps below use steps of several seconds
  return ap::KinematicPropagator(config);
}

// Samples after the anchor whose state still carries the start-up error: until four samples
// exist no causal method can do better than the linear interpolant over the first interval
// (a local error of order h^3). cf4 integrates again from the anchor once the fourth sample
// arrives, so from then on the state is fourth order; the three earlier states were already
// reported and are left out of the path error.
constexpr int kStartUpSamples = 3;

// Largest attitude error along the whole path after start-up (not only at the end: at whole
// cone periods a first-order error telescopes away, docs/numerics.md §2).
double coningMaxError(Integrator method, double rate_hz, double duration) {
  const ConingMotion cone;
  auto propagator = makePropagator(method, cone.attitude(0.0));
  const int samples = static_cast<int>(std::lround(duration * rate_hz));
  double worst = 0.0;
  for (int k = 0; k <= samples; ++k) {
    const double t = k / rate_hz;
    propagator.addSample(t, cone.bodyRate(t));
    if (k < kStartUpSamples) continue;
    worst = std::max(worst, ap::rotationAngle(propagator.orientation(), cone.attitude(t)));
  }
  return worst;
}

class LieGroupMethods : public ::testing::TestWithParam<Integrator> {};
class AllKinematicMethods : public ::testing::TestWithParam<Integrator> {};

}  // namespace

// The closed form used as truth below must itself satisfy dq/dt = 1/2 q (x) (0, w).
TEST(ConingMotion, ClosedFormSatisfiesTheKinematics) {
  const ConingMotion cone;
  const double h = 1e-5;
  for (double t : {0.0, 0.3, 1.7, 12.9}) {
    const Eigen::Vector4d derivative =
        (cone.attitude(t + h).coeffs() - cone.attitude(t - h).coeffs()) / (2 * h);
    const Eigen::Vector4d expected =
        0.5 * (cone.attitude(t) * ap::pureQuaternion(cone.bodyRate(t))).coeffs();
    EXPECT_LE((derivative - expected).norm(), 1e-8) << "t = " << t;
  }
}

TEST_P(LieGroupMethods, IntegrateConstantRateExactlyAtAnyStep) {
  const Eigen::Quaterniond q0 = ap::expMap(Eigen::Vector3d(0.3, -1.2, 0.5));
  const Eigen::Vector3d w(1.1, -0.7, 2.3);   // |w| = 2.64 rad/s
  for (double dt : {1e-3, 0.1, 1.0, 2.0}) {  // |w| dt up to 5.3 rad
    auto propagator = makePropagator(GetParam(), q0);
    for (int k = 0; k <= 50; ++k) {
      propagator.addSample(k * dt, w);
    }
    EXPECT_ROTATION_NEAR(propagator.orientation(), constantRateTruth(q0, w, 50 * dt), 1e-13)
        << "dt = " << dt;
  }
}

TEST_P(LieGroupMethods, IntegrateConstantRateExactlyOnUnevenSamples) {
  const Eigen::Quaterniond q0 = Eigen::Quaterniond::Identity();
  const Eigen::Vector3d w(-0.4, 3.0, 1.5);
  auto propagator = makePropagator(GetParam(), q0);
  double t = 0.0;
  for (int k = 0; k < 40; ++k) {
    propagator.addSample(t, w);
    t += 0.05 + 0.9 * ((k * 7919) % 13) / 13.0;  // steps from 0.05 s to 0.9 s
  }
  EXPECT_ROTATION_NEAR(propagator.orientation(), constantRateTruth(q0, w, propagator.time()),
                       1e-13);
}

TEST_P(LieGroupMethods, KeepUnitNormToRoundOffEveryStep) {
  const ConingMotion cone;
  auto propagator = makePropagator(GetParam(), cone.attitude(0.0));
  double worst = 0.0;
  for (int k = 0; k <= 2000; ++k) {
    propagator.addSample(k * 0.01, 20.0 * cone.bodyRate(k * 0.01));
    worst = std::max(worst, std::abs(propagator.normError()));
  }
  EXPECT_LE(worst, 1e-15);
}

// The Lie-group steps: unit norm and a constant rate exact, as their rows declare.
INSTANTIATE_TEST_SUITE_P(Kinematic, LieGroupMethods,
                         ::testing::ValuesIn(integrator_cases::methodsKeeping(
                             ap::Model::Kinematic,
                             ap::keeps::kUnitNorm | ap::keeps::kConstantRate)),
                         integrator_cases::MethodName());

// `exp` holds the rate of the sample that opens the interval, so a piecewise-constant rate
// command stream is integrated exactly.
TEST(ExpMethod, HoldsTheOpeningSampleRate) {
  const Eigen::Vector3d w1(0, 0, 1.0), w2(2.0, 0, 0);
  auto propagator = makePropagator(Integrator::Exp, Eigen::Quaterniond::Identity());
  propagator.addSample(0.0, w1);
  propagator.addSample(1.5, w2);  // w1 held over [0, 1.5]
  propagator.addSample(2.0, w1);  // w2 held over [1.5, 2]
  const Eigen::Quaterniond truth =
      constantRateTruth(constantRateTruth(Eigen::Quaterniond::Identity(), w1, 1.5), w2, 0.5);
  EXPECT_ROTATION_NEAR(propagator.orientation(), truth, 4 * kEps);
}

// Body rates compose on the right: a quarter turn about body x, then one about body y, is a
// third of a turn about (1, 1, 1)/sqrt(3) (the octahedron of the notes §5).
TEST_P(AllKinematicMethods, OctahedronFromPiecewiseRates) {
  const double quarter = M_PI / 2;
  const int n = 20000;  // small steps so that even euler is close
  auto propagator = makePropagator(GetParam(), Eigen::Quaterniond::Identity());
  // exp and euler hold the opening rate; exp2, rk4 and cf4 see the switch as a ramp over one
  // sample interval, which costs them an error of order |w| h = 8e-5 rad.
  for (int k = 0; k <= n; ++k) propagator.addSample(k * 1.0 / n, Eigen::Vector3d(quarter, 0, 0));
  for (int k = 1; k <= n; ++k) {
    propagator.addSample(1.0 + k * 1.0 / n, Eigen::Vector3d(0, quarter, 0));
  }
  const double third = 2 * M_PI / 3;
  const Eigen::Quaterniond expected(
      Eigen::AngleAxisd(third, Eigen::Vector3d(1, 1, 1).normalized()));
  EXPECT_ROTATION_NEAR(propagator.orientation(), expected, 2e-4);
}

INSTANTIATE_TEST_SUITE_P(Kinematic, AllKinematicMethods,
                         ::testing::ValuesIn(ap::integratorsFor(ap::Model::Kinematic)),
                         integrator_cases::MethodName());

class ConingOrder : public ::testing::TestWithParam<Integrator> {};

TEST_P(ConingOrder, ErrorFallsAtTheDeclaredOrder) {
  const Integrator method = GetParam();
  const int p = ap::declaredOrder(method, ap::Model::Kinematic);
  ASSERT_GT(p, 0) << ap::integratorName(method) << " declares no order";
  const double min_ratio = integrator_cases::minHalvingRatio(p);
  const double duration = 20.0;
  std::vector<double> errors;
  for (double rate : {100.0, 200.0, 400.0})
    errors.push_back(coningMaxError(method, rate, duration));
  for (std::size_t i = 1; i < errors.size(); ++i) {
    EXPECT_GE(errors[i - 1] / errors[i], min_ratio)
        << ap::integratorName(method) << ": errors " << errors[i - 1] << " -> " << errors[i];
  }
  // Sanity of the declared order: 2^p within 25 %.
  const double observed = std::log2(errors[1] / errors[2]);
  EXPECT_NEAR(observed, p, 0.25 * p) << ap::integratorName(method);
}

INSTANTIATE_TEST_SUITE_P(Kinematic, ConingOrder,
                         ::testing::ValuesIn(ap::integratorsFor(ap::Model::Kinematic)),
                         integrator_cases::MethodName());

// cf4 on unevenly spaced samples (jittered by up to +-30 %) still converges at fourth order.
TEST(Cf4, FourthOrderOnJitteredSamples) {
  const ConingMotion cone;
  std::vector<double> errors;
  for (double rate : {100.0, 200.0, 400.0}) {
    auto propagator = makePropagator(Integrator::Cf4, cone.attitude(0.0));
    double worst = 0.0;
    const int n = static_cast<int>(10.0 * rate);
    for (int k = 0; k <= n; ++k) {
      const double jitter = (k == 0 || k == n) ? 0.0 : 0.3 * std::sin(12.9898 * k);
      const double t = (k + jitter) / rate;
      propagator.addSample(t, cone.bodyRate(t));
      if (k < kStartUpSamples) continue;
      worst = std::max(worst, ap::rotationAngle(propagator.orientation(), cone.attitude(t)));
    }
    errors.push_back(worst);
  }
  EXPECT_GE(errors[0] / errors[1], 12.0) << errors[0] << " -> " << errors[1];
  EXPECT_GE(errors[1] / errors[2], 12.0) << errors[1] << " -> " << errors[2];
}

// The Magnus form of docs/numerics.md §2 is an independent fourth-order step: one cf4 step and one
// Magnus step on the same cubic agree to O(h^5).
TEST(Cf4, AgreesWithTheFourthOrderMagnusStep) {
  const ConingMotion cone;
  for (double h : {0.02, 0.01}) {
    ap::RateWindow window;
    for (int k = -2; k <= 1; ++k) window.push({k * h, cone.bodyRate(k * h)});
    const double c1 = 0.5 - std::sqrt(3.0) / 6, c2 = 0.5 + std::sqrt(3.0) / 6;
    const Eigen::Vector3d a = window.interpolate(c1 * h), b = window.interpolate(c2 * h);
    const Eigen::Quaterniond magnus =
        ap::expMap(0.5 * h * (a + b) + std::sqrt(3.0) / 12 * h * h * a.cross(b));
    const Eigen::Quaterniond cf4 =
        ap::kinematicStep(Integrator::Cf4, Eigen::Quaterniond::Identity(), window);
    EXPECT_LE(ap::rotationAngle(cf4, magnus), 50.0 * std::pow(cone.omega * h, 5));
  }
}

TEST(RateWindow, InterpolatesCubicsExactly) {
  ap::RateWindow window;
  auto cubic = [](double t) { return Eigen::Vector3d(t * t * t - 2 * t, 1.0 + t * t, -3 * t); };
  for (double t : {1e9 + 0.0, 1e9 + 0.013, 1e9 + 0.021, 1e9 + 0.04}) {
    window.push({t, cubic(t - 1e9)});
  }
  EXPECT_EQ(window.size(), ap::RateWindow::kCapacity);
  for (double tau : {0.005, 0.03, 0.039}) {
    EXPECT_LE((window.interpolate(1e9 + tau) - cubic(tau)).norm(), 1e-6);
  }
  window.push({1e9 + 0.05, cubic(0.05)});  // the oldest sample leaves
  EXPECT_EQ(window[0].t, 1e9 + 0.013);
}

TEST(KinematicStep, RejectsDynamicOnlyMethods) {
  ap::RateWindow window;
  window.push({0.0, Eigen::Vector3d::Zero()});
  window.push({1.0, Eigen::Vector3d::Zero()});
  EXPECT_THROW(ap::kinematicStep(Integrator::Splitting, Eigen::Quaterniond::Identity(), window),
               std::invalid_argument);
}

TEST(RateWindow, UndoPushRestoresTheWindow) {
  ap::RateWindow window;
  for (int k = 0; k < 6; ++k) {
    const ap::RateWindow before = window;
    const bool evicted = window.push({1.0 * k, Eigen::Vector3d::Constant(k)});
    EXPECT_EQ(evicted, k >= static_cast<int>(ap::RateWindow::kCapacity));
    EXPECT_EQ(window.newest().t, 1.0 * k);
    window.undoPush(evicted);
    ASSERT_EQ(window.size(), before.size());
    for (std::size_t i = 0; i < window.size(); ++i) EXPECT_EQ(window[i].t, before[i].t);
    window.push({1.0 * k, Eigen::Vector3d::Constant(k)});
  }
  EXPECT_EQ(window[0].t, 2.0);  // samples 2..5 remain
}
