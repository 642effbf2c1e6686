// The time and bad-input policy of docs/design.md §6–§7 in the kinematic propagator.
#include <gtest/gtest.h>

#include <cmath>
#include <cstddef>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "attitude_propagator/models/kinematic_propagator.h"
#include "attitude_propagator/numerics/quaternion.h"
#include "integrator_cases.h"
#include "rotation_matchers.h"

namespace ap = attitude_propagator;
using ap::StampOutcome;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();
const Eigen::Vector3d kSpinZ(0.0, 0.0, 1.0);  // 1 rad/s about z

class KinematicPolicy : public ::testing::TestWithParam<ap::Integrator> {
 protected:
  KinematicPolicy() : propagator_(config()) {}
  ap::KinematicConfig config() const {
    ap::KinematicConfig c;
    c.integrator = GetParam();
    c.time_policy.max_dt = 0.5;
    c.time_policy.backward_jump = 1.0;
    c.initial_q_WB = initial_;
    return c;
  }
  // Angle the method turns through in one step of h at kSpinZ (1 rad/s), in closed form.
  // exp, exp2 and cf4 integrate a constant rate exactly (their rows say so). euler's step
  // q (x) (1, (0, h w/2)), renormalised, turns by 2 atan(h/2) (docs/numerics.md §2). rk4's
  // step is q (x) p(u), p(u) = 1 + u + u^2/2 + u^3/6 + u^4/24 the RK4 polynomial at the pure
  // quaternion u = (0, h w/2), whose square is -z^2 (z = h/2): it turns by
  // 2 atan2(z - z^3/6, 1 - z^2/2 + z^4/24).
  double turn(double h) const {
    const ap::Integrator method = GetParam();
    if (ap::integratorInfo(method).keeps & ap::keeps::kConstantRate) return h;
    const double z = 0.5 * h;
    if (method == ap::Integrator::Euler) return 2.0 * std::atan(z);
    if (method == ap::Integrator::Rk4) {
      return 2.0 * std::atan2(z - z * z * z / 6.0, 1.0 - z * z / 2.0 + z * z * z * z / 24.0);
    }
    ADD_FAILURE() << "no closed form for " << ap::integratorName(method);
    return 0.0;
  }
  // The initial orientation turned about z by `angle`.
  Eigen::Quaterniond spun(double angle) const {
    return initial_ * Eigen::Quaterniond(Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitZ()));
  }
  void feed(double t0, double t1, double dt) {
    for (double t = t0; t <= t1 + 1e-9; t += dt) propagator_.addSample(t, kSpinZ);
  }
  const Eigen::Quaterniond initial_ = ap::expMap(Eigen::Vector3d(0.1, 0.2, 0.3));
  ap::KinematicPropagator propagator_;
};

// Every method's state against its own closed form at a constant rate is exact to round-off
// (measured at most 3.4e-16 rad over the paths below); bound 1e-15.
constexpr double kRoundOff = 1e-15;

}  // namespace

TEST_P(KinematicPolicy, FirstSampleAnchorsTheInitialState) {
  EXPECT_FALSE(propagator_.anchored());
  EXPECT_EQ(propagator_.addSample(100.0, kSpinZ), StampOutcome::Anchored);
  EXPECT_TRUE(propagator_.anchored());
  EXPECT_EQ(propagator_.time(), 100.0);
  EXPECT_ROTATION_NEAR(propagator_.orientation(), initial_, 0.0);
  EXPECT_EQ(propagator_.addSample(100.1, kSpinZ), StampOutcome::Advanced);
  EXPECT_ROTATION_NEAR(propagator_.orientation(), spun(turn(100.1 - 100.0)), kRoundOff);
}

TEST_P(KinematicPolicy, DropsDuplicateAndStaleStamps) {
  feed(0.0, 1.0, 0.1);
  const Eigen::Quaterniond before = propagator_.orientation();
  const double t = propagator_.time();
  EXPECT_EQ(propagator_.addSample(t, kSpinZ), StampOutcome::DroppedStale);
  EXPECT_EQ(propagator_.addSample(t - 0.5, kSpinZ), StampOutcome::DroppedStale);
  EXPECT_EQ(propagator_.time(), t);
  EXPECT_ROTATION_NEAR(propagator_.orientation(), before, 0.0);
  // Integration carries on from where it was.
  EXPECT_EQ(propagator_.addSample(t + 0.1, kSpinZ), StampOutcome::Advanced);
  EXPECT_ROTATION_NEAR(propagator_.orientation(), spun(11 * turn(0.1)), kRoundOff);
}

TEST_P(KinematicPolicy, HoldsTheStateAcrossAGapLongerThanMaxDt) {
  feed(0.0, 1.0, 0.1);
  const Eigen::Quaterniond before = propagator_.orientation();
  const double t = propagator_.time();
  EXPECT_EQ(propagator_.addSample(t + 0.75, kSpinZ), StampOutcome::HeldGap);  // > max_dt
  EXPECT_ROTATION_NEAR(propagator_.orientation(), before, 0.0);
  EXPECT_EQ(propagator_.time(), t + 0.75);
  // A gap of exactly max_dt is still integrated.
  EXPECT_EQ(propagator_.addSample(t + 1.25, kSpinZ), StampOutcome::Advanced);
  EXPECT_ROTATION_NEAR(propagator_.orientation(), spun(10 * turn(0.1) + turn(0.5)), kRoundOff);
}

TEST_P(KinematicPolicy, NeverGoesBackInTimeAndStartsAfreshAfterAReset) {
  feed(10.0, 12.0, 0.1);
  const Eigen::Quaterniond at_12 = propagator_.orientation();
  const double t_12 = propagator_.time();
  // Back by seconds or by a hair: stale either way (a persistent jump is the engine's call).
  EXPECT_EQ(propagator_.addSample(5.0, kSpinZ), StampOutcome::DroppedStale);
  EXPECT_EQ(propagator_.addSample(std::nextafter(t_12, 0.0), kSpinZ), StampOutcome::DroppedStale);
  EXPECT_ROTATION_NEAR(propagator_.orientation(), at_12, 0.0);
  EXPECT_EQ(propagator_.time(), t_12);
  propagator_.reset();
  EXPECT_EQ(propagator_.addSample(5.0, kSpinZ), StampOutcome::Anchored);
  EXPECT_ROTATION_NEAR(propagator_.orientation(), initial_, 0.0);
  EXPECT_EQ(propagator_.time(), 5.0);
  feed(5.1, 5.5, 0.1);  // five intervals of 0.1 s up to the stamps' rounding
  EXPECT_ROTATION_NEAR(propagator_.orientation(), spun(5 * turn((propagator_.time() - 5.0) / 5)),
                       kRoundOff);
}

TEST_P(KinematicPolicy, RejectsNonFiniteSamplesAndNeverBecomesNaN) {
  feed(0.0, 0.5, 0.1);
  const Eigen::Quaterniond before = propagator_.orientation();
  for (const Eigen::Vector3d& bad :
       {Eigen::Vector3d(kNaN, 0, 0), Eigen::Vector3d(0, kInf, 0), Eigen::Vector3d(0, 0, -kInf)}) {
    EXPECT_EQ(propagator_.addSample(0.6, bad), StampOutcome::RejectedNonFinite);
  }
  EXPECT_EQ(propagator_.addSample(kNaN, kSpinZ), StampOutcome::RejectedNonFinite);
  EXPECT_EQ(propagator_.addSample(kInf, kSpinZ), StampOutcome::RejectedNonFinite);
  EXPECT_ROTATION_NEAR(propagator_.orientation(), before, 0.0);
  EXPECT_EQ(propagator_.addSample(0.6, kSpinZ), StampOutcome::Advanced);
  EXPECT_ROTATION_NEAR(propagator_.orientation(), spun(6 * turn(0.1)), kRoundOff);
}

// Finite rates whose magnitude overflows are rejected as well (beyond kMaxBodyRate).
TEST_P(KinematicPolicy, RejectsOverflowingRatesAndKeepsAFiniteUnitState) {
  feed(0.0, 0.5, 0.1);
  const Eigen::Quaterniond before = propagator_.orientation();
  EXPECT_EQ(propagator_.addSample(0.6, Eigen::Vector3d(1e300, -1e300, 1e300)),
            StampOutcome::RejectedOutOfRange);
  EXPECT_ROTATION_NEAR(propagator_.orientation(), before, 0.0);
  EXPECT_NEAR(propagator_.orientation().norm(), 1.0, 1e-15);
  EXPECT_EQ(propagator_.addSample(0.6, kSpinZ), StampOutcome::Advanced);
  EXPECT_ROTATION_NEAR(propagator_.orientation(), spun(6 * turn(0.1)), kRoundOff);
}

TEST_P(KinematicPolicy, ResetAndSetState) {
  feed(0.0, 1.0, 0.1);
  propagator_.reset();
  EXPECT_FALSE(propagator_.anchored());
  EXPECT_ROTATION_NEAR(propagator_.orientation(), initial_, 0.0);

  const Eigen::Quaterniond pinned = ap::expMap(Eigen::Vector3d(-1.0, 0.5, 2.0));
  propagator_.setState(3.0, pinned, kSpinZ);
  EXPECT_TRUE(propagator_.anchored());
  EXPECT_EQ(propagator_.time(), 3.0);
  propagator_.addSample(3.25, kSpinZ);
  const Eigen::Quaterniond expected =
      pinned * Eigen::Quaterniond(Eigen::AngleAxisd(turn(0.25), Eigen::Vector3d::UnitZ()));
  EXPECT_ROTATION_NEAR(propagator_.orientation(), expected, kRoundOff);
  EXPECT_THROW(propagator_.setState(4.0, Eigen::Quaterniond(0, 0, 0, 0), kSpinZ),
               std::invalid_argument);
  EXPECT_THROW(propagator_.setState(kNaN, pinned, kSpinZ), std::invalid_argument);
}

INSTANTIATE_TEST_SUITE_P(Kinematic, KinematicPolicy,
                         ::testing::ValuesIn(ap::integratorsFor(ap::Model::Kinematic)),
                         integrator_cases::MethodName());

TEST(KinematicConfig, RejectsBadConfiguration) {
  ap::KinematicConfig config;
  config.integrator = ap::Integrator::ImplicitMidpoint;
  EXPECT_THROW(ap::KinematicPropagator{config}, std::invalid_argument);
  config = {};
  config.time_policy.max_dt = -1.0;
  EXPECT_THROW(ap::KinematicPropagator{config}, std::invalid_argument);
  config = {};
  config.initial_q_WB = Eigen::Quaterniond(0, 0, 0, 0);
  EXPECT_THROW(ap::KinematicPropagator{config}, std::invalid_argument);
  config = {};
  config.initial_q_WB = Eigen::Quaterniond(2, 0, 0, 0);  // normalised, not rejected
  EXPECT_NO_THROW(ap::KinematicPropagator{config});
}

TEST(KinematicConfig, AutoIsCf4) {
  EXPECT_EQ(ap::KinematicPropagator(ap::KinematicConfig{}).integrator(), ap::Integrator::Cf4);
}

namespace {

// The integrator names as the parameter table of docs/parameters.md documents them, with the
// models each drives there, written out here rather than read from the core's table.
struct DocumentedIntegrator {
  ap::Integrator id;
  const char* name;
  bool kinematic;
  bool dynamic;
};

const DocumentedIntegrator kDocumentedIntegrators[] = {
    {ap::Integrator::Auto, "auto", true, true},
    {ap::Integrator::Euler, "euler", true, false},
    {ap::Integrator::Rk4, "rk4", true, true},
    {ap::Integrator::Exp, "exp", true, false},
    {ap::Integrator::Exp2, "exp2", true, false},
    {ap::Integrator::Cf4, "cf4", true, false},
    {ap::Integrator::ImplicitMidpoint, "implicit_midpoint", false, true},
    {ap::Integrator::Splitting, "splitting", false, true},
    {ap::Integrator::Splitting4, "splitting4", false, true},
    {ap::Integrator::Dopri5, "dopri5", false, true},
    {ap::Integrator::Exact, "exact", false, true},
};

}  // namespace

// Name to enumerator and enumerator to name, each against the documented pair rather than
// through the table both ways; and the table holds no name the documentation does not.
TEST(IntegratorNames, MatchTheDocumentedNamesBothWays) {
  std::vector<std::string> documented;
  for (const DocumentedIntegrator& entry : kDocumentedIntegrators) {
    SCOPED_TRACE(entry.name);
    EXPECT_EQ(ap::integratorFromName(entry.name), entry.id);
    EXPECT_EQ(ap::integratorName(entry.id), entry.name);
    EXPECT_EQ(ap::supportsKinematic(entry.id), entry.kinematic);
    EXPECT_EQ(ap::supportsDynamic(entry.id), entry.dynamic);
    documented.emplace_back(entry.name);
  }
  // Exact is the last enumerator: one documented name per enumerator, and no more in the table.
  EXPECT_EQ(static_cast<std::size_t>(ap::Integrator::Exact) + 1, documented.size());
  EXPECT_EQ(ap::integratorNames(), documented);
  EXPECT_EQ(ap::integratorNames(ap::integratorsFor(ap::Model::Kinematic)),
            (std::vector<std::string>{"euler", "rk4", "exp", "exp2", "cf4"}));
  EXPECT_EQ(ap::integratorNames(ap::integratorsFor(ap::Model::Dynamic)),
            (std::vector<std::string>{"rk4", "implicit_midpoint", "splitting", "splitting4",
                                      "dopri5", "exact"}));
  // What `auto` resolves to (docs/parameters.md): cf4 kinematic, exact torque-free, rk4 with
  // torque.
  EXPECT_EQ(ap::autoIntegrator(ap::Model::Kinematic, false), ap::Integrator::Cf4);
  EXPECT_EQ(ap::autoIntegrator(ap::Model::Dynamic, false), ap::Integrator::Exact);
  EXPECT_EQ(ap::autoIntegrator(ap::Model::Dynamic, true), ap::Integrator::Rk4);
}

// Near misses are refused (names are exact and lower case), and the message lists every
// accepted name.
TEST(IntegratorNames, RefuseUnknownNames) {
  for (const char* unknown : {"rk45", "", "CF4", "Euler", " cf4", "cf4 ", "exp3", "numerical_rk4",
                              "implicit-midpoint", "kinematic"}) {
    SCOPED_TRACE(std::string("'") + unknown + "'");
    try {
      ap::integratorFromName(unknown);
      ADD_FAILURE() << "accepted";
    } catch (const std::invalid_argument& e) {
      for (const DocumentedIntegrator& entry : kDocumentedIntegrators) {
        EXPECT_NE(std::string(e.what()).find(entry.name), std::string::npos) << e.what();
      }
    }
  }
}

// A one-model program (kinematic_demo) names only that model's methods: every kinematic one
// (integratorsFor, the table's rows that drive it), none of the dynamic-only ones.
TEST(IntegratorNames, OneModelsNamesListOnlyItsMethods) {
  EXPECT_EQ(ap::integratorFromName("cf4", ap::Model::Kinematic), ap::Integrator::Cf4);
  EXPECT_EQ(ap::integratorFromName("auto", ap::Model::Kinematic), ap::Integrator::Auto);
  for (const char* refused : {"bogus", "exact"}) {
    SCOPED_TRACE(refused);
    try {
      ap::integratorFromName(refused, ap::Model::Kinematic);
      ADD_FAILURE() << "accepted";
    } catch (const std::invalid_argument& e) {
      const std::string what = e.what();
      for (const ap::IntegratorInfo& row : ap::integratorTable()) {
        const bool kinematic = ap::supportsKinematic(row.id);  // auto too
        const std::string name = " " + std::string(row.name);
        const bool last = what.size() >= name.size() &&
                          what.compare(what.size() - name.size(), name.size(), name) == 0;
        const bool named = what.find(name + " ") != std::string::npos || last;
        EXPECT_EQ(named, kinematic) << row.name << ": " << what;
      }
    }
  }
}

TEST(ModelAndRateSampleNames, MatchTheDocumentedNamesBothWays) {
  const std::pair<ap::Model, const char*> models[] = {{ap::Model::Auto, "auto"},
                                                      {ap::Model::Kinematic, "kinematic"},
                                                      {ap::Model::Dynamic, "dynamic"}};
  for (const auto& [model, name] : models) {
    EXPECT_EQ(ap::modelFromName(name), model) << name;
    EXPECT_EQ(ap::modelName(model), name);
  }
  const std::pair<ap::RateSamples, const char*> kinds[] = {
      {ap::RateSamples::Instantaneous, "instantaneous"},
      {ap::RateSamples::IntervalAverage, "interval_average"}};
  for (const auto& [kind, name] : kinds) {
    EXPECT_EQ(ap::rateSamplesFromName(name), kind) << name;
    EXPECT_EQ(ap::rateSamplesName(kind), name);
  }
  for (const char* unknown : {"kinematics", "", "Dynamic", "auto "}) {
    EXPECT_THROW(ap::modelFromName(unknown), std::invalid_argument) << unknown;
  }
  for (const char* unknown : {"instant", "", "interval-average", "Instantaneous"}) {
    EXPECT_THROW(ap::rateSamplesFromName(unknown), std::invalid_argument) << unknown;
  }
}
