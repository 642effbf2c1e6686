// HandOverBound (hand_over_bound.h) against its documented rule: between two rounds of roscpp's
// I/O thread at most `limit` messages of an output are handed over; past it the newest are
// dropped and counted; a round lets the next `limit` through.
#include <gtest/gtest.h>

#include "attitude_propagator/ros/hand_over_bound.h"

namespace ap = attitude_propagator;

TEST(HandOverBound, AtMostTheLimitBetweenTwoRoundsAndTheRestDroppedAndCounted) {
  ap::IoRounds rounds;
  ap::HandOverBound bound(rounds, 3);
  EXPECT_TRUE(bound.admit());
  EXPECT_TRUE(bound.admit());
  EXPECT_TRUE(bound.admit());   // n = limit
  EXPECT_FALSE(bound.admit());  // n + 1
  EXPECT_FALSE(bound.admit());
  EXPECT_EQ(bound.dropped(), 2u);
  rounds.ranOnce();  // the I/O thread came round: the queue was emptied
  EXPECT_TRUE(bound.admit());
  EXPECT_TRUE(bound.admit());
  EXPECT_TRUE(bound.admit());
  EXPECT_FALSE(bound.admit());
  EXPECT_EQ(bound.dropped(), 3u);
}

TEST(HandOverBound, OutputsAreBoundedApartOnTheSameRounds) {
  ap::IoRounds rounds;
  ap::HandOverBound tf(rounds, 1);
  ap::HandOverBound imu(rounds, 1);
  EXPECT_TRUE(tf.admit());
  EXPECT_TRUE(imu.admit());  // another output's count is its own
  EXPECT_FALSE(tf.admit());
  rounds.ranOnce();
  rounds.ranOnce();  // several rounds: the same as one
  EXPECT_TRUE(tf.admit());
  EXPECT_TRUE(imu.admit());
  EXPECT_FALSE(imu.admit());
  EXPECT_EQ(tf.dropped(), 1u);
  EXPECT_EQ(imu.dropped(), 1u);
}
