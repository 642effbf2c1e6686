// The time and bad-input policy of docs/design.md §6–§7 in the kinematic propagator.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "attitude_propagator/kinematic_propagator.h"
#include "attitude_propagator/quaternion.h"
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
  // exp, exp2 and cf4 integrate a constant rate exactly (their rows say so); euler and rk4
  // only approximately (euler's renormalised step turns by 2 atan(|w| h / 2) instead of |w| h).
  double tolerance() const {
    return (ap::integratorInfo(GetParam()).keeps & ap::keeps::kConstantRate) ? 1e-12 : 2e-2;
  }
  // Angle about z after t seconds at kSpinZ from the initial orientation.
  Eigen::Quaterniond spun(double t) const {
    return initial_ * Eigen::Quaterniond(Eigen::AngleAxisd(t, Eigen::Vector3d::UnitZ()));
  }
  void feed(double t0, double t1, double dt) {
    for (double t = t0; t <= t1 + 1e-9; t += dt) propagator_.addSample(t, kSpinZ);
  }
  const Eigen::Quaterniond initial_ = ap::expMap(Eigen::Vector3d(0.1, 0.2, 0.3));
  ap::KinematicPropagator propagator_;
};

}  // namespace

TEST_P(KinematicPolicy, FirstSampleAnchorsTheInitialState) {
  EXPECT_FALSE(propagator_.anchored());
  EXPECT_EQ(propagator_.addSample(100.0, kSpinZ), StampOutcome::Anchored);
  EXPECT_TRUE(propagator_.anchored());
  EXPECT_EQ(propagator_.time(), 100.0);
  EXPECT_ROTATION_NEAR(propagator_.orientation(), initial_, 0.0);
  EXPECT_EQ(propagator_.addSample(100.1, kSpinZ), StampOutcome::Advanced);
  EXPECT_ROTATION_NEAR(propagator_.orientation(), spun(0.1), tolerance());
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
  EXPECT_ROTATION_NEAR(propagator_.orientation(), spun(t + 0.1), tolerance());
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
  EXPECT_ROTATION_NEAR(propagator_.orientation(), spun(1.0 + 0.5), tolerance());
}

TEST_P(KinematicPolicy, ResetsOnABackwardJumpOfMoreThanASecond) {
  feed(10.0, 12.0, 0.1);
  EXPECT_EQ(propagator_.addSample(5.0, kSpinZ), StampOutcome::ResetBackwardJump);
  EXPECT_ROTATION_NEAR(propagator_.orientation(), initial_, 0.0);
  EXPECT_EQ(propagator_.time(), 5.0);
  feed(5.1, 5.5, 0.1);
  EXPECT_ROTATION_NEAR(propagator_.orientation(), spun(0.5), tolerance());
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
  EXPECT_ROTATION_NEAR(propagator_.orientation(), spun(0.6), tolerance());
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
  EXPECT_ROTATION_NEAR(propagator_.orientation(), spun(0.6), tolerance());
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
      pinned * Eigen::Quaterniond(Eigen::AngleAxisd(0.25, Eigen::Vector3d::UnitZ()));
  EXPECT_ROTATION_NEAR(propagator_.orientation(), expected, tolerance());
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

TEST(IntegratorNames, RoundTripAndRejectUnknown) {
  for (const char* name : {"auto", "euler", "rk4", "exp", "exp2", "cf4", "implicit_midpoint",
                           "splitting", "splitting4", "dopri5", "exact"}) {
    EXPECT_EQ(ap::integratorName(ap::integratorFromName(name)), name);
  }
  try {
    ap::integratorFromName("rk45");
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("cf4"), std::string::npos) << e.what();
  }
  EXPECT_THROW(ap::modelFromName("kinematics"), std::invalid_argument);
}
