// The ~set_state request (src/messages/set_state_request.cpp) against srv/SetState.srv: the
// state given in world_frame's axes (a body facing east: identity in ENU/FLU, a heading of
// +90 deg about down in NED/FRD), an unstamped request at now, and no time at all refused.
#include <cmath>
#include <limits>

#include <gtest/gtest.h>

#include "../core/engine_fixtures.h"
#include "attitude_propagator/config/parameters.h"
#include "attitude_propagator/messages/set_state_request.h"

namespace ap = attitude_propagator;

namespace {

struct Node {
  ap::NodeConfig config = ap::validateParameters({});
  engine_fixtures::DiscardingSink sink;
  ap::AttitudeEngine engine{ap::engineConfig(config), sink};
};

ap::SetState::Request facingEast(double heading_about_z, double stamp_s) {
  ap::SetState::Request request;
  request.header.stamp = ros::Time(stamp_s);
  request.orientation.z = std::sin(heading_about_z / 2);
  request.orientation.w = std::cos(heading_about_z / 2);
  request.angular_velocity.x = 1.0;
  request.angular_velocity.y = 2.0;
  request.angular_velocity.z = 3.0;
  return request;
}

}  // namespace

TEST(SetStateRequest, TheStateIsGivenInWorldFramesAxes) {
  Node enu;
  ap::SetState::Response response;
  ap::applySetState(facingEast(0.0, 100.5), ros::Time(200), ap::WorldConvention::Enu, enu.engine,
                    response);
  EXPECT_TRUE(response.success);
  EXPECT_EQ(response.message, "state set at 100.500000 s");
  EXPECT_LT(enu.engine.state().q_WB.angularDistance(Eigen::Quaterniond::Identity()), 1e-12);
  EXPECT_LT((enu.engine.state().w_B - Eigen::Vector3d(1, 2, 3)).norm(), 1e-12);

  Node ned;
  ap::applySetState(facingEast(M_PI / 2, 100.5), ros::Time(200), ap::WorldConvention::Ned,
                    ned.engine, response);
  EXPECT_TRUE(response.success);
  // Facing east in ENU/FLU is the identity; FRD's (1, 2, 3) is FLU's (1, -2, -3).
  EXPECT_LT(ned.engine.state().q_WB.angularDistance(Eigen::Quaterniond::Identity()), 1e-12);
  EXPECT_LT((ned.engine.state().w_B - Eigen::Vector3d(1, -2, -3)).norm(), 1e-12);
}

TEST(SetStateRequest, AnUnstampedRequestHoldsNow) {
  Node node;
  ap::SetState::Response response;
  ap::applySetState(facingEast(0.0, 0.0), ros::Time(200.25), ap::WorldConvention::Enu, node.engine,
                    response);
  EXPECT_TRUE(response.success);
  EXPECT_EQ(response.message, "state set at 200.250000 s");
}

TEST(SetStateRequest, NoTimeAtAllAsksForAStamp) {
  Node node;
  ap::SetState::Response response;
  response.success = true;
  ap::applySetState(facingEast(0.0, 0.0), ros::Time(), ap::WorldConvention::Enu, node.engine,
                    response);
  EXPECT_FALSE(response.success);
  EXPECT_EQ(response.message, "no ROS time yet (use_sim_time without /clock): give header.stamp");
}

TEST(SetStateRequest, TheEnginesRefusalIsTheAnswer) {
  Node node;
  ap::SetState::Request request = facingEast(0.0, 100.0);
  request.orientation.w = std::numeric_limits<double>::quiet_NaN();
  ap::SetState::Response response;
  ap::applySetState(request, ros::Time(200), ap::WorldConvention::Enu, node.engine, response);
  EXPECT_FALSE(response.success);
  EXPECT_FALSE(response.message.empty());
  EXPECT_EQ(response.message.find("state set"), std::string::npos);
}
