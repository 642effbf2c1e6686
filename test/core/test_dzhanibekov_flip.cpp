// The Dzhanibekov flip: a body spun close to its middle axis turns over every half period of
// the motion of M, so M2 changes sign at times spaced T/2 apart. The truths are the period of
// the textbook formulas (landau_lifshitz.h: k and omega from the energy and |M|, K(k) from the
// arithmetic-geometric mean) and the flip times of an integration written here (classical RK4
// in long double on the Euler equations); the exact motion and the propagators must flip at
// those times.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <functional>
#include <vector>

#include <boost/math/tools/toms748_solve.hpp>

#include "attitude_propagator/models/dynamic_propagator.h"
#include "attitude_propagator/numerics/torque_free_motion.h"
#include "landau_lifshitz.h"

namespace ap = attitude_propagator;
namespace ll = landau_lifshitz;

namespace {

// I = (1, 2, 3), M0 = (1e-3, 1, 2e-3): M^2 - 2 E I2 = 1e-6 (1 - 2 + 4 - 8/3) = 3.3e-7 > 0, so
// M circulates about the largest axis, close to the separatrix (k^2 = 1 - 1.3e-6).
const Eigen::Vector3d kMoments(1.0, 2.0, 3.0);
const Eigen::Vector3d kRate(1e-3 / 1.0, 1.0 / 2.0, 2e-3 / 3.0);
constexpr double kMiddle = 2.0;  // I2: M2 = I2 w2

ap::RigidBody body() { return ap::RigidBody::fromPrincipalMoments(kMoments); }

ap::DynamicState initialState() {
  ap::DynamicState x;
  x.w_B = kRate;
  return x;
}

/// The times in (0, t_end] where f changes sign, bracketed on a grid of `scan` seconds and
/// refined with TOMS 748 to a few ulps.
std::vector<double> signChanges(const std::function<double(double)>& f, double t_end, double scan) {
  std::vector<double> roots;
  double a = 0.0;
  double fa = f(a);
  for (double b = scan; b <= t_end; b += scan) {
    const double fb = f(b);
    if ((fa < 0.0) != (fb < 0.0)) {
      std::uintmax_t iterations = 100;
      const auto bracket = boost::math::tools::toms748_solve(
          f, a, b, fa, fb, boost::math::tools::eps_tolerance<double>(50), iterations);
      roots.push_back(0.5 * (bracket.first + bracket.second));
    }
    a = b;
    fa = fb;
  }
  return roots;
}

/// Flip times of classical RK4 in long double with step h on the Euler equations in principal
/// axes, I1 dw1/dt = (I2 - I3) w2 w3 and cyclic. A sign change of w2 between two steps is
/// placed by linear interpolation, whose error is O(h^3): where w2 = 0, d^2w2/dt^2 =
/// ((I3 - I1)/I2) d(w3 w1)/dt is proportional to w2 and vanishes.
std::vector<double> rk4FlipTimes(double h, double t_end) {
  using Real = long double;
  using Vector = Eigen::Matrix<Real, 3, 1>;
  const Vector I = kMoments.cast<Real>();
  auto f = [&I](const Vector& w) {
    return Vector((I[1] - I[2]) * w[1] * w[2] / I[0], (I[2] - I[0]) * w[2] * w[0] / I[1],
                  (I[0] - I[1]) * w[0] * w[1] / I[2]);
  };
  std::vector<double> flips;
  Vector w = kRate.cast<Real>();
  const long steps = std::lround(t_end / h);
  for (long n = 0; n < steps; ++n) {
    const Vector k1 = f(w);
    const Vector k2 = f(w + Real(h / 2) * k1);
    const Vector k3 = f(w + Real(h / 2) * k2);
    const Vector k4 = f(w + Real(h) * k3);
    const Vector next = w + Real(h / 6) * (k1 + 2 * k2 + 2 * k3 + k4);
    if ((w[1] < 0) != (next[1] < 0)) {
      flips.push_back(static_cast<double>((n + w[1] / (w[1] - next[1])) * Real(h)));
    }
    w = next;
  }
  return flips;
}

/// Flip times of a propagator advanced through stamps `every` seconds apart, each placed by
/// linear interpolation between the two stamps around it (error O(every^3), as above).
std::vector<double> propagatorFlipTimes(ap::Integrator integrator, double every, double t_end) {
  ap::DynamicConfig config;
  config.body = body();
  config.integrator = integrator;
  config.max_step = 0.01;
  config.tolerance = 1e-12;
  config.initial = initialState();
  ap::DynamicPropagator propagator(config);
  propagator.advanceTo(0.0);
  std::vector<double> flips;
  double w2 = propagator.state().w_B.y();
  const long steps = std::lround(t_end / every);
  for (long n = 1; n <= steps; ++n) {
    EXPECT_EQ(propagator.advanceTo(n * every), ap::StampOutcome::Advanced);
    const double next = propagator.state().w_B.y();
    if ((w2 < 0.0) != (next < 0.0)) flips.push_back((n - 1 + w2 / (w2 - next)) * every);
    w2 = next;
  }
  return flips;
}

/// Largest |a_i - b_i|, with the counts required equal.
double largestDifference(const std::vector<double>& a, const std::vector<double>& b) {
  EXPECT_EQ(a.size(), b.size());
  double worst = 0.0;
  for (std::size_t i = 0; i < std::min(a.size(), b.size()); ++i) {
    worst = std::max(worst, std::abs(a[i] - b[i]));
  }
  return worst;
}

/// Largest deviation of the spacing of successive flips from `half_period`.
double largestSpacingError(const std::vector<double>& flips, double half_period) {
  double worst = 0.0;
  for (std::size_t i = 1; i < flips.size(); ++i) {
    worst = std::max(worst, std::abs(flips[i] - flips[i - 1] - half_period));
  }
  return worst;
}

}  // namespace

// The closed form's modulus, rate and period equal the textbook's, computed from E and |M|.
TEST(DynDzhanibekov, PeriodIsTheTextbookPeriod) {
  const ll::EllipticMotion truth = ll::ellipticMotion(kMoments, kRate);
  ASSERT_LT(truth.m_c, 2e-6);  // close to the separatrix: K = 8.2, far from pi/2
  const ap::TorqueFreeMotion motion(body(), initialState());
  EXPECT_EQ(motion.regime(), ap::TorqueFreeMotion::Regime::AboutLargest);
  // Measured: |k - k_LL| 1.1e-16, lambda equal, period 4.7e-15 relative (m_c = 1.3e-6 carries
  // the round-off of Delta2 relative to itself, K = ln(4/k') + ... passes it on divided by
  // 2K); bounds about 5x, lambda a few ulps.
  EXPECT_NEAR(motion.modulus(), double(std::sqrt(truth.k2)), 1e-15);
  EXPECT_NEAR(std::abs(motion.lambda()), double(truth.frequency), 1e-15 * double(truth.frequency));
  EXPECT_NEAR(motion.bodyPeriod(), double(truth.period), 3e-14 * double(truth.period));
}

// The exact motion's M2 changes sign every half period of the textbook, and returns to its
// value after whole periods.
TEST(DynDzhanibekov, ExactMotionFlipsEveryHalfPeriod) {
  const double period = double(ll::ellipticMotion(kMoments, kRate).period);  // 113.4 s
  const ap::TorqueFreeMotion motion(body(), initialState());
  const auto M2 = [&motion](double t) { return kMiddle * motion.evaluate(t).w_B.y(); };
  const std::vector<double> flips = signChanges(M2, 8.25 * period, 1.0);
  ASSERT_EQ(flips.size(), 16u);
  // Measured: 6.6e-13 s over 8 periods (6e-15 of the period); bound 5e-12 s.
  EXPECT_LE(largestSpacingError(flips, 0.5 * period), 5e-12);
  const double M2_0 = M2(0.0);
  // M2 = -B sn(u): M2(t + T/2) = -M2(t), M2(t + T) = M2(t). Expected error |dM2/dt| = 2e-3
  // at t = 0 times the period's (5e-13 s at 7.5 T): 1e-15; measured 0; bound 1e-14.
  EXPECT_NEAR(M2(0.5 * period), -M2_0, 1e-14);
  EXPECT_NEAR(M2(period), M2_0, 1e-14);
  EXPECT_NEAR(M2(7.5 * period), -M2_0, 1e-14);
}

// The test's own two truths agree (the textbook period and an RK4 integration), and the exact
// motion flips at the integration's flip times: the phase, not only the period.
TEST(DynDzhanibekov, ExactMotionFlipsWhenAnIndependentIntegrationFlips) {
  const double period = double(ll::ellipticMotion(kMoments, kRate).period);
  const double t_end = 2.25 * period;
  const std::vector<double> rk4 = rk4FlipTimes(1e-3, t_end);
  ASSERT_EQ(rk4.size(), 4u);
  // Measured (h = 1e-3): spacing error 1.4e-11 s; bound 1e-10.
  EXPECT_LE(largestSpacingError(rk4, 0.5 * period), 1e-10);
  const ap::TorqueFreeMotion motion(body(), initialState());
  const std::vector<double> exact =
      signChanges([&motion](double t) { return motion.evaluate(t).w_B.y(); }, t_end, 1.0);
  // Measured: 9.1e-12 s, RK4's own error; bound 5e-11.
  EXPECT_LE(largestDifference(exact, rk4), 5e-11);
}

// The propagators keep the flip times: the exact model and dopri5 at a tight tolerance, as
// the node runs them (a fixed grid, states at stamps).
TEST(DynDzhanibekov, PropagatorsFlipWhenTheIndependentIntegrationFlips) {
  const double period = double(ll::ellipticMotion(kMoments, kRate).period);
  const double t_end = 2.25 * period;
  const std::vector<double> rk4 = rk4FlipTimes(1e-3, t_end);
  struct Case {
    ap::Integrator integrator;
    double bound;  // s
  };
  // Measured: exact 3.0e-11 s against RK4, 8.5e-12 s spacing (RK4's error and the
  // interpolation between stamps 2 ms apart); dopri5 at 1e-12 3.1e-8 s and 2.7e-8 s.
  for (const Case& c :
       {Case{ap::Integrator::Exact, 1.5e-10}, Case{ap::Integrator::Dopri5, 1.5e-7}}) {
    SCOPED_TRACE(ap::integratorName(c.integrator));
    const std::vector<double> flips = propagatorFlipTimes(c.integrator, 2e-3, t_end);
    EXPECT_LE(largestDifference(flips, rk4), c.bound);
    EXPECT_LE(largestSpacingError(flips, 0.5 * period), c.bound);
  }
}
