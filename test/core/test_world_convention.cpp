// world_frame: the axes of the attitudes given and published. Each convention against the
// axes written out by hand (east, north, up; forward, left/right, up/down), and the whole path
// (parameters → engine → published axes) against a closed form.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "attitude_propagator/config/parameters.h"
#include "attitude_propagator/numerics/world_convention.h"
#include "engine_fixtures.h"
#include "refused_parameters.h"
#include "rotation_matchers.h"

namespace ap = attitude_propagator;
using namespace engine_fixtures;

namespace {

const Eigen::Vector3d kEast(1, 0, 0), kNorth(0, 1, 0), kUp(0, 0, 1);  // ENU coordinates

void expectVectorNear(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double tol = 1e-15) {
  EXPECT_LT((a - b).norm(), tol) << a.transpose() << " vs " << b.transpose();
}

}  // namespace

TEST(WorldConvention, NamesAndSuffixesAsDocumented) {
  for (const char* name : {"enu", "nwu", "ned"}) {
    EXPECT_EQ(ap::worldConventionName(ap::worldConventionFromName(name)), name);
  }
  EXPECT_THROW(ap::worldConventionFromName("NED"), std::invalid_argument);
  EXPECT_THROW(ap::worldConventionFromName("enu "), std::invalid_argument);
  EXPECT_EQ(ap::fixedFrameSuffix(ap::WorldConvention::Enu), "");
  EXPECT_EQ(ap::fixedFrameSuffix(ap::WorldConvention::Nwu), "_nwu");
  EXPECT_EQ(ap::fixedFrameSuffix(ap::WorldConvention::Ned), "_ned");
  EXPECT_EQ(ap::bodyFrameSuffix(ap::WorldConvention::Enu), "");
  EXPECT_EQ(ap::bodyFrameSuffix(ap::WorldConvention::Nwu), "");
  EXPECT_EQ(ap::bodyFrameSuffix(ap::WorldConvention::Ned), "_frd");
}

// East, north and up in each convention's fixed coordinates, written out.
TEST(WorldConvention, FixedAxesAreEastNorthUpWrittenOut) {
  const auto ned = ap::fixedFromEnu(ap::WorldConvention::Ned);
  expectVectorNear(ned * kEast, Eigen::Vector3d(0, 1, 0));   // east is NED's y
  expectVectorNear(ned * kNorth, Eigen::Vector3d(1, 0, 0));  // north is NED's x
  expectVectorNear(ned * kUp, Eigen::Vector3d(0, 0, -1));    // up is -down
  const auto nwu = ap::fixedFromEnu(ap::WorldConvention::Nwu);
  expectVectorNear(nwu * kEast, Eigen::Vector3d(0, -1, 0));  // east is -west
  expectVectorNear(nwu * kNorth, Eigen::Vector3d(1, 0, 0));
  expectVectorNear(nwu * kUp, Eigen::Vector3d(0, 0, 1));
  const auto enu = ap::fixedFromEnu(ap::WorldConvention::Enu);
  expectVectorNear(enu * kNorth, kNorth);
}

// FRD's forward, right and down in FLU coordinates; FLU bodies are FLU.
TEST(WorldConvention, BodyAxesAreForwardRightDownForNed) {
  const auto frd = ap::fluFromBody(ap::WorldConvention::Ned);
  expectVectorNear(frd * Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(1, 0, 0));   // forward
  expectVectorNear(frd * Eigen::Vector3d(0, 1, 0), Eigen::Vector3d(0, -1, 0));  // right = -left
  expectVectorNear(frd * Eigen::Vector3d(0, 0, 1), Eigen::Vector3d(0, 0, -1));  // down = -up
  for (auto c : {ap::WorldConvention::Enu, ap::WorldConvention::Nwu}) {
    EXPECT_TRUE(ap::fluFromBody(c).coeffs().isApprox(Eigen::Quaterniond::Identity().coeffs()));
  }
}

// A level body facing north: FLU's forward along ENU's north; as published it is the identity
// in NED and NWU (x north, body level), and a quarter turn about up in ENU.
TEST(WorldConvention, ALevelBodyFacingNorthReadsAsEachConventionSaysIt) {
  const Eigen::Quaterniond q_EF = aboutAxis(kUp, M_PI / 2);  // forward → north
  EXPECT_ROTATION_NEAR(ap::attitudeInConvention(ap::WorldConvention::Ned, q_EF),
                       Eigen::Quaterniond::Identity(), 1e-15);
  EXPECT_ROTATION_NEAR(ap::attitudeInConvention(ap::WorldConvention::Nwu, q_EF),
                       Eigen::Quaterniond::Identity(), 1e-15);
  EXPECT_ROTATION_NEAR(ap::attitudeInConvention(ap::WorldConvention::Enu, q_EF), q_EF, 0.0);
}

TEST(WorldConvention, AttitudesRoundTripAndStayUnit) {
  const Eigen::Quaterniond q = aboutAxis(Eigen::Vector3d(0.3, -0.7, 0.2), 2.1);
  for (auto c : {ap::WorldConvention::Enu, ap::WorldConvention::Nwu, ap::WorldConvention::Ned}) {
    const Eigen::Quaterniond out = ap::attitudeInConvention(c, q);
    EXPECT_NEAR(out.norm(), 1.0, 1e-15);
    EXPECT_ROTATION_NEAR(ap::attitudeFromConvention(c, out), q, 1e-15);
    const Eigen::Vector3d v(0.4, -0.1, 0.9);
    expectVectorNear(ap::bodyVectorFromConvention(c, ap::bodyVectorInConvention(c, v)), v);
  }
}

// The orientation error covariance in FRD: the xy and xz terms change sign, yz does not
// (C = diag(1, -1, -1)); a transpose or a missing side would show in the cross terms.
TEST(WorldConvention, CovarianceInFrdFlipsTheTermsThatMixForwardWithRightOrDown) {
  Eigen::Matrix3d P;
  P << 4, 1, 2,  //
      1, 5, 3,   //
      2, 3, 6;
  Eigen::Matrix3d expected;
  expected << 4, -1, -2,  //
      -1, 5, 3,           //
      -2, 3, 6;
  EXPECT_TRUE(ap::bodyCovarianceInConvention(ap::WorldConvention::Ned, P).isApprox(expected));
  EXPECT_TRUE(ap::bodyCovarianceInConvention(ap::WorldConvention::Nwu, P).isApprox(P));
}

TEST(WorldConvention, UnknownWorldFrameRefusesStartNamingTheValues) {
  ap::Parameters p;
  p.world_frame = "ecef";
  expectRefused(p, "world_frame", "enu nwu ned");
  for (const char* ok : {"enu", "nwu", "ned"}) {
    p.world_frame = ok;
    EXPECT_NO_THROW(ap::validateParameters(p)) << ok;
  }
}

// The whole path: the initial attitude given in the convention's axes, a constant rate measured
// in a REP-103 (FLU) frame, the result read back in the convention's axes. The closed form:
// q(T) = q0 · Exp(T ω_B) with ω_B the FLU rate written in the body's axes by hand (FRD:
// (x, -y, -z)). A yaw rate to the left turns an NED heading down (clockwise positive) and an
// ENU or NWU heading up.
class ConventionPath : public ::testing::TestWithParam<const char*> {};

TEST_P(ConventionPath, KinematicRunMatchesTheClosedFormInTheConventionsAxes) {
  const std::string name = GetParam();
  const ap::WorldConvention c = ap::worldConventionFromName(name);
  ap::Parameters p;
  p.world_frame = name;
  const Eigen::Quaterniond q0 = aboutAxis(Eigen::Vector3d(0.2, 0.1, 1.0), 0.6);  // mostly yaw
  p.initial_orientation = {q0.x(), q0.y(), q0.z(), q0.w()};
  const ap::NodeConfig config = ap::validateParameters(p);
  EXPECT_EQ(config.world, c);
  Recorder sink;
  ap::AttitudeEngine engine(ap::engineConfig(config), sink);
  const Eigen::Vector3d w_F(0.3, -0.2, 0.5);
  const double T = 2.0;
  for (int k = 0; k <= 200; ++k) engine.submit(rate(at(T * k / 200), w_F));
  ASSERT_EQ(sink.states.size(), 201u);
  const Eigen::Vector3d w_B = c == ap::WorldConvention::Ned ? Eigen::Vector3d(0.3, 0.2, -0.5) : w_F;
  const Eigen::Quaterniond expected = q0 * aboutAxis(w_B, w_B.norm() * T);
  EXPECT_ROTATION_NEAR(ap::attitudeInConvention(c, sink.states.back().q_WB), expected, 1e-12);
  EXPECT_ROTATION_NEAR(ap::attitudeInConvention(c, sink.states.front().q_WB), q0, 1e-15);
}

INSTANTIATE_TEST_SUITE_P(Conventions, ConventionPath, ::testing::Values("enu", "nwu", "ned"));

// The dynamic model's initial rate is given in the body's axes too: in FRD, (x, -y, -z) in FLU.
TEST(WorldConvention, InitialAngularVelocityIsInTheConventionsBodyAxes) {
  ap::Parameters p;
  p.inertia = {1.0, 2.0, 3.0};
  p.initial_angular_velocity = {0.1, 0.2, 0.3};
  p.world_frame = "ned";
  const ap::NodeConfig ned = ap::validateParameters(p);
  ASSERT_TRUE(ned.dynamic);
  expectVectorNear(ned.dynamic->initial.w_B, Eigen::Vector3d(0.1, -0.2, -0.3));
  p.world_frame = "nwu";
  expectVectorNear(ap::validateParameters(p).dynamic->initial.w_B, Eigen::Vector3d(0.1, 0.2, 0.3));
}
