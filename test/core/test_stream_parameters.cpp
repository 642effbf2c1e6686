// The real-stream parameters (rate_samples, stamp_filter, gyro_bias): defaults, the values
// they turn into, and refusal of bad values with the accepted list.
#include <cmath>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

#include "attitude_propagator/config/parameters.h"
#include "refused_parameters.h"

namespace ap = attitude_propagator;

TEST(StreamParameters, DefaultsArePointSamplesUnfilteredWithoutBias) {
  const ap::KinematicConfig k = ap::validateParameters(ap::Parameters{}).kinematic;
  EXPECT_EQ(k.rate_samples, ap::RateSamples::Instantaneous);
  EXPECT_EQ(k.stamp_filter, ap::StampFilter::None);
  EXPECT_EQ(ap::engineConfig(ap::validateParameters(ap::Parameters{})).gyro_bias_B,
            Eigen::Vector3d::Zero());
}

TEST(StreamParameters, ReachTheKinematicConfig) {
  ap::Parameters p;
  p.rate_samples = "interval_average";
  p.stamp_filter = "sensor_clock";
  const ap::KinematicConfig k = ap::validateParameters(p).kinematic;
  EXPECT_EQ(k.rate_samples, ap::RateSamples::IntervalAverage);
  EXPECT_EQ(k.stamp_filter, ap::StampFilter::SensorClock);
}

// The engine subtracts the gyro bias for both models (the kinematic propagator has none):
// engineConfig() gives it to the engine. The other two settings go to the kinematic
// propagator.
TEST(StreamParameters, ReachTheEngineOnce) {
  for (const bool dynamic : {false, true}) {
    SCOPED_TRACE(dynamic ? "dynamic" : "kinematic");
    ap::Parameters p;
    if (dynamic) p.inertia = {1.0, 2.0, 2.5};
    p.rate_samples = "interval_average";
    p.stamp_filter = "sensor_clock";
    p.gyro_bias = {0.01, -0.02, 0.03};
    const ap::EngineConfig engine = ap::engineConfig(ap::validateParameters(p));
    EXPECT_EQ(engine.gyro_bias_B, Eigen::Vector3d(0.01, -0.02, 0.03));
    EXPECT_EQ(engine.kinematic.rate_samples, ap::RateSamples::IntervalAverage);
    EXPECT_EQ(engine.kinematic.stamp_filter, ap::StampFilter::SensorClock);
  }
}

TEST(StreamParameters, RefuseUnknownValuesWithTheAcceptedList) {
  ap::Parameters p;
  p.rate_samples = "averaged";
  expectRefused(p, "rate_samples", "instantaneous interval_average");
  p = {};
  p.stamp_filter = "kalman";
  expectRefused(p, "stamp_filter", "none sensor_clock");
  p = {};
  p.gyro_bias = {0.0, 0.0};
  expectRefused(p, "gyro_bias", "[x, y, z]");
  p.gyro_bias = {0.0, NAN, 0.0};
  expectRefused(p, "gyro_bias", "[x, y, z]");
  p = {};
  p.model = "dynamic";  // refused whatever the model
  p.inertia = {1.0, 2.0, 3.0};
  p.rate_samples = "x";
  expectRefused(p, "rate_samples", "instantaneous interval_average");
}
