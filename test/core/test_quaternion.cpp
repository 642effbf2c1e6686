#include <gtest/gtest.h>

#include "attitude_propagator/quaternion.h"
#include "rotation_matchers.h"

namespace ap = attitude_propagator;

TEST(ExpMap, Placeholder) { EXPECT_ROTATION_NEAR(ap::expMap(Eigen::Vector3d::Zero()), Eigen::Quaterniond::Identity(), 0.0); }
