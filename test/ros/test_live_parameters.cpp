// dynamic_reconfigure and the parameters (src/ros/live_parameters.cpp): the six live
// parameters go both ways, each change is told apart, and a refused change keeps the
// configuration in force (docs/parameters.md, the live ones).
#include <string>

#include <gtest/gtest.h>

#include "../core/engine_fixtures.h"
#include "attitude_propagator/ros/live_parameters.h"

namespace ap = attitude_propagator;

namespace {

/// Live values that differ from the defaults in every field.
ap::AttitudePropagatorConfig changedLive() {
  ap::AttitudePropagatorConfig live;
  live.angular_velocity_stddev = 0.0123;
  live.max_dt = 0.25;
  live.torque_timeout = 3.5;
  live.publish_tf = false;
  live.reverse_tf = true;
  live.integrator = "rk4";
  return live;
}

}  // namespace

TEST(LiveParameters, EveryLiveValueIsTakenAndTheRestKept) {
  ap::Parameters in_force;
  in_force.body_frame = "base_link";
  const ap::Parameters p = ap::liveParameters(in_force, changedLive());
  EXPECT_EQ(p.angular_velocity_stddev, 0.0123);
  EXPECT_EQ(p.max_dt, 0.25);
  EXPECT_EQ(p.torque_timeout, 3.5);
  EXPECT_FALSE(p.publish_tf);
  EXPECT_TRUE(p.reverse_tf);
  EXPECT_EQ(p.integrator, "rk4");
  EXPECT_EQ(p.body_frame, "base_link");
}

TEST(LiveParameters, TheValuesInForceAreShownBack) {
  const ap::Parameters in_force = ap::liveParameters({}, changedLive());
  ap::AttitudePropagatorConfig live;
  ap::showInForce(in_force, live);
  EXPECT_EQ(live.angular_velocity_stddev, 0.0123);
  EXPECT_EQ(live.max_dt, 0.25);
  EXPECT_EQ(live.torque_timeout, 3.5);
  EXPECT_FALSE(live.publish_tf);
  EXPECT_TRUE(live.reverse_tf);
  EXPECT_EQ(live.integrator, "rk4");
}

TEST(LiveParameters, EachChangeIsToldApart) {
  const ap::Parameters now;
  const auto change = [&](auto edit) {
    ap::Parameters next = now;
    edit(next);
    return ap::liveChange(now, next);
  };
  EXPECT_TRUE(change([](ap::Parameters& p) { p.angular_velocity_stddev += 0.01; }).engine_changes);
  EXPECT_TRUE(change([](ap::Parameters& p) { p.max_dt += 0.5; }).engine_changes);
  EXPECT_TRUE(change([](ap::Parameters& p) { p.torque_timeout += 1.0; }).engine_changes);
  EXPECT_TRUE(change([](ap::Parameters& p) { p.integrator = "rk4"; }).engine_changes);
  const ap::LiveChange tf = change([](ap::Parameters& p) { p.publish_tf = !p.publish_tf; });
  EXPECT_TRUE(tf.tf_toggled);
  EXPECT_FALSE(tf.child_changed);
  EXPECT_FALSE(tf.engine_changes);
  const ap::LiveChange child = change([](ap::Parameters& p) { p.reverse_tf = !p.reverse_tf; });
  EXPECT_TRUE(child.child_changed);
  EXPECT_FALSE(child.tf_toggled);
  EXPECT_FALSE(child.engine_changes);
  const ap::LiveChange none = ap::liveChange(now, now);
  EXPECT_FALSE(none.engine_changes || none.tf_toggled || none.child_changed);
}

TEST(LiveParameters, ARefusedChangeKeepsTheConfigurationInForce) {
  ap::NodeConfig config = ap::validateParameters({});
  engine_fixtures::DiscardingSink sink;
  ap::AttitudeEngine engine(ap::engineConfig(config), sink);
  ap::Parameters p = config.parameters;
  p.integrator = "no_such_method";
  const std::string error = ap::applyLive(p, ap::liveChange(config.parameters, p), engine, config);
  EXPECT_EQ(error.rfind("integrator", 0), 0u) << error;
  EXPECT_EQ(config.parameters.integrator, ap::Parameters{}.integrator);
  const auto line = ap::reconfigureText(error, true, config.parameters, engine.integrator());
  ASSERT_TRUE(line);
  EXPECT_EQ(line->level, ros::console::levels::Warn);
  EXPECT_EQ(line->text.rfind("reconfigure refused: integrator", 0), 0u);
}

TEST(LiveParameters, AChangeTheEngineRefusesKeepsTheConfigurationInForce) {
  // The engine runs the dynamic model; the parameters asked for validate to the kinematic one.
  ap::Parameters dynamic;
  dynamic.inertia = {1.0, 2.0, 3.0};
  engine_fixtures::DiscardingSink sink;
  ap::AttitudeEngine engine(ap::engineConfig(ap::validateParameters(dynamic)), sink);
  ap::NodeConfig config = ap::validateParameters({});
  ap::Parameters p = config.parameters;
  p.max_dt = 0.25;
  const std::string error = ap::applyLive(p, ap::liveChange(config.parameters, p), engine, config);
  EXPECT_EQ(error, "model: cannot change while running");
  EXPECT_EQ(config.parameters.max_dt, ap::Parameters{}.max_dt);
}

TEST(LiveParameters, AnAcceptedChangeIsInForce) {
  ap::NodeConfig config = ap::validateParameters({});
  engine_fixtures::DiscardingSink sink;
  ap::AttitudeEngine engine(ap::engineConfig(config), sink);
  ap::Parameters p = config.parameters;
  p.max_dt = 0.25;
  EXPECT_EQ(ap::applyLive(p, ap::liveChange(config.parameters, p), engine, config), "");
  EXPECT_EQ(config.parameters.max_dt, 0.25);
  const auto line = ap::reconfigureText("", true, config.parameters, engine.integrator());
  ASSERT_TRUE(line);
  EXPECT_EQ(line->level, ros::console::levels::Info);
  EXPECT_EQ(line->text, "reconfigured: integrator " + ap::integratorName(engine.integrator()) +
                            ", max_dt 0.25 s, torque_timeout " +
                            ap::formatted("%g", config.parameters.torque_timeout) +
                            " s, angular_velocity_stddev " +
                            ap::formatted("%g", config.parameters.angular_velocity_stddev) +
                            " rad/s (the propagator goes on from the current state)");
  EXPECT_FALSE(ap::reconfigureText("", false, config.parameters, engine.integrator()));
}
