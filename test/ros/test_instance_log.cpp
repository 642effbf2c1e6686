// InstanceLog (src/ros/instance_log.cpp) against its documented rules: a nodelet's lines name
// it, a node's do not; lines are throttled per kind and per instance, on wall time.
#include <gtest/gtest.h>

#include "attitude_propagator/ros/instance_log.h"

namespace ap = attitude_propagator;

TEST(InstanceLog, ANodeOfItsOwnHasNoPrefixANodeletItsName) {
  EXPECT_EQ(ap::instancePrefix("/attitude_propagator", "/attitude_propagator"), "");
  EXPECT_EQ(ap::instancePrefix("/imu_attitude", "/manager"), "/imu_attitude: ");
  // A hostile name is cut as every quoted text is.
  const std::string prefix = ap::instancePrefix("/" + std::string(1000, 'n'), "/manager");
  EXPECT_LT(prefix.size(), 600u);
}

TEST(InstanceLog, AKindIsDueOncePerPeriodAndAnotherKindIsNotHeldBack) {
  ap::InstanceLog log;
  EXPECT_TRUE(log.due("a", 100.0, 5.0));
  EXPECT_FALSE(log.due("a", 104.999, 5.0));
  EXPECT_TRUE(log.due("b", 104.999, 5.0));
  EXPECT_TRUE(log.due("a", 105.0, 5.0));
  EXPECT_FALSE(log.due("a", 109.0, 5.0));
}

TEST(InstanceLog, AWallClockThatWentBackLetsTheLineThrough) {
  ap::InstanceLog log;
  EXPECT_TRUE(log.due("a", 100.0, 5.0));
  EXPECT_TRUE(log.due("a", 50.0, 5.0));
  EXPECT_FALSE(log.due("a", 51.0, 5.0));
}

TEST(InstanceLog, TwoInstancesThrottleApart) {
  // Two nodelets in one manager: one's warning never silences the other's.
  ap::InstanceLog first("/a: ");
  ap::InstanceLog second("/b: ");
  EXPECT_TRUE(first.due("fix outcome", 10.0, 5.0));
  EXPECT_TRUE(second.due("fix outcome", 10.0, 5.0));
}
