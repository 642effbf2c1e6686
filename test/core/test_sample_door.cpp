// The rules with one owner each, against what their comments say: the sample door
// (models/sample_door.h) at n-1, n, n+1 ulps of its bounds and on every non-finite kind, and one
// state per stamp (time/one_state_per_stamp.h) at the last published stamp -1, 0, +1 ns.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <optional>

#include "attitude_propagator/limits.h"
#include "attitude_propagator/models/sample_door.h"
#include "attitude_propagator/time/one_state_per_stamp.h"

namespace ap = attitude_propagator;

namespace {

TEST(SampleDoor, EachKindHasItsOwnBound) {
  EXPECT_EQ(ap::doorBound(false), ap::kMaxBodyRate);
  EXPECT_EQ(ap::doorBound(true), ap::kMaxTorque);
}

// A value whose norm is exactly the bound enters; one ulp above is out of range. Along a
// generic direction the norm is rounded, so the bound is met along an axis, where it is exact.
TEST(SampleDoor, TheBoundItselfEntersAndTheNextDoubleDoesNot) {
  for (const bool torque : {false, true}) {
    const double bound = ap::doorBound(torque);
    const double below = std::nextafter(bound, 0.0);
    const double above = std::nextafter(bound, 2.0 * bound);
    EXPECT_EQ(ap::refusedValue(Eigen::Vector3d(0.0, -below, 0.0), bound), std::nullopt);
    EXPECT_EQ(ap::refusedValue(Eigen::Vector3d(0.0, -bound, 0.0), bound), std::nullopt);
    EXPECT_EQ(ap::refusedValue(Eigen::Vector3d(0.0, -above, 0.0), bound),
              ap::StampOutcome::RejectedOutOfRange);
  }
}

TEST(SampleDoor, EveryNonFiniteValueOrStampIsNonFiniteNotOutOfRange) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  const double bound = ap::kMaxBodyRate;
  for (int axis = 0; axis < 3; ++axis) {
    for (const double bad : {nan, inf, -inf}) {
      Eigen::Vector3d v(0.1, -0.2, 0.3);
      v[axis] = bad;
      EXPECT_EQ(ap::refusedValue(v, bound), ap::StampOutcome::RejectedNonFinite);
      EXPECT_EQ(ap::refusedSample(1.0, v, bound), ap::StampOutcome::RejectedNonFinite);
    }
  }
  const Eigen::Vector3d ok(0.1, -0.2, 0.3);
  for (const double bad : {nan, inf, -inf}) {
    EXPECT_EQ(ap::refusedSample(bad, ok, bound), ap::StampOutcome::RejectedNonFinite);
  }
  // A non-finite stamp with a value out of range is non-finite: the stamp is asked first.
  EXPECT_EQ(ap::refusedSample(nan, Eigen::Vector3d(2.0 * bound, 0.0, 0.0), bound),
            ap::StampOutcome::RejectedNonFinite);
  EXPECT_EQ(ap::refusedSample(-1e300, ok, bound), std::nullopt);  // any finite time
}

TEST(OneStatePerStamp, OnlyAStampAfterTheLastPublishedIsPublishable) {
  const ap::Stamp last = 1'700'000'000'123'456'789;
  EXPECT_FALSE(ap::publishable(last - 1, last));
  EXPECT_FALSE(ap::publishable(last, last));
  EXPECT_TRUE(ap::publishable(last + 1, last));
  EXPECT_TRUE(ap::publishable(std::numeric_limits<ap::Stamp>::min(), std::nullopt));
}

}  // namespace
