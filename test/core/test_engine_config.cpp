// models/engine_config.h: the settings the engine checks itself. Truths: the documented bounds,
// and one rule in one place: a setting refused at start is refused on reconfigure with the same
// words, and one taken at start is taken there too.
#include <gtest/gtest.h>

#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include "attitude_propagator/engine.h"
#include "attitude_propagator/limits.h"
#include "attitude_propagator/models/engine_config.h"
#include "engine_fixtures.h"

namespace ap = attitude_propagator;

namespace {

using NullSink = engine_fixtures::DiscardingSink;

std::string refusal(const std::function<void()>& check) {
  try {
    check();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return {};
}

struct Setting {
  const char* name;
  std::function<void(ap::EngineConfig&)> spoil;
};

}  // namespace

TEST(EngineConfig, EachSettingRefusedAtStartIsRefusedOnReconfigureWithTheSameWords) {
  const double max_dt = ap::timePolicyOf(engine_fixtures::kinematicConfig()).max_dt;
  const std::vector<Setting> settings = {
      {"max_future", [](ap::EngineConfig& c) { c.max_future = 0.0; }},
      {"max_future", [](ap::EngineConfig& c) { c.max_future = ap::kMaxFuture * 1.001; }},
      {"rate_delay", [](ap::EngineConfig& c) { c.rate_delay = -1e-9; }},
      {"rate_delay", [max_dt](ap::EngineConfig& c) { c.rate_delay = max_dt * (1.0 + 1e-9); }},
      {"fix_history", [](ap::EngineConfig& c) { c.fixes.history = 0.0; }},
      {"fix_gate", [](ap::EngineConfig& c) { c.fixes.gate = -1.0; }},
      {"gyro_bias_stddev", [](ap::EngineConfig& c) { c.fixes.gyro_bias_stddev = 11.0; }},
      {"accel_stddev", [](ap::EngineConfig& c) { c.aiding.accel_stddev = 0.0; }},
      {"declination", [](ap::EngineConfig& c) { c.aiding.declination = 4.0; }},
      {"mag_bias", [](ap::EngineConfig& c) { c.aiding.mag_bias << 0.0, 0.0, 0.0101; }},
      {"mag_bias", [](ap::EngineConfig& c) { c.aiding.mag_bias << NAN, 0.0, 0.0; }},
  };
  for (const Setting& s : settings) {
    ap::EngineConfig bad = engine_fixtures::kinematicConfig();
    s.spoil(bad);
    const std::string words = refusal([&bad] { ap::checkEngineSettings(bad); });
    EXPECT_EQ(words.rfind(s.name, 0), 0u) << s.name << ": " << words;
    EXPECT_NE(words.find("accepted"), std::string::npos) << words;
    NullSink sink;
    EXPECT_EQ(refusal([&bad, &sink] { ap::AttitudeEngine engine(bad, sink); }), words);
    ap::AttitudeEngine engine(engine_fixtures::kinematicConfig(), sink);
    EXPECT_EQ(engine.reconfigure(bad), words);
  }
  // At the bounds, taken by both.
  ap::EngineConfig edge = engine_fixtures::kinematicConfig();
  edge.rate_delay = max_dt;
  edge.max_future = ap::kMaxFuture;
  edge.aiding.mag_bias << 0.0, 0.0, -ap::kMaxMagBias;
  EXPECT_EQ(refusal([&edge] { ap::checkEngineConfig(edge); }), "");
  NullSink sink;
  ap::AttitudeEngine engine(engine_fixtures::kinematicConfig(), sink);
  EXPECT_EQ(engine.reconfigure(edge), "");
}

TEST(EngineConfig, TheBiasEstimateIsTheKinematicModelsAtStartAndOnReconfigure) {
  ap::EngineConfig dynamic = engine_fixtures::torqueConfig();
  dynamic.fixes.estimate_gyro_bias = true;
  const std::string words = refusal([&dynamic] { ap::checkEngineSettings(dynamic); });
  EXPECT_EQ(words, "estimate_gyro_bias: accepted: true with the kinematic model only");
  NullSink sink;
  EXPECT_EQ(refusal([&dynamic, &sink] { ap::AttitudeEngine engine(dynamic, sink); }), words);
  ap::AttitudeEngine engine(engine_fixtures::torqueConfig(), sink);
  EXPECT_EQ(engine.reconfigure(dynamic), words);
}

TEST(EngineConfig, PublishRateAndGyroBiasAreCheckedAtStart) {
  ap::EngineConfig c = engine_fixtures::kinematicConfig();
  c.publish_rate = 0.0;
  EXPECT_EQ(refusal([&c] { ap::checkEngineConfig(c); }).rfind("publish_rate", 0), 0u);
  c = engine_fixtures::kinematicConfig();
  c.gyro_bias_B = Eigen::Vector3d(0.0, 0.0, ap::kMaxBodyRate * 1.001);
  EXPECT_EQ(refusal([&c] { ap::checkEngineConfig(c); }).rfind("gyro_bias", 0), 0u);
  c.gyro_bias_B = Eigen::Vector3d(0.0, 0.0, ap::kMaxBodyRate);
  EXPECT_EQ(refusal([&c] { ap::checkEngineConfig(c); }), "");
}

TEST(EngineConfig, TheRateDelayInNanosecondsAndTheDefaultRateNoise) {
  ap::EngineConfig c = engine_fixtures::kinematicConfig();
  c.rate_delay = 0.0123456789;
  EXPECT_EQ(ap::rateDelayNs(c), 12345679);  // rounded to the nearest nanosecond
  c.rate_stddev = 0.002;
  EXPECT_EQ(ap::defaultRateCovariance(c), 4e-6 * Eigen::Matrix3d::Identity());
  c.rate_stddev = 0.0;
  EXPECT_EQ(ap::defaultRateCovariance(c), Eigen::Matrix3d::Zero());
  c.aiding.use_accel = true;  // measurements need the covariance to grow between them
  EXPECT_EQ(ap::defaultRateCovariance(c),
            ap::kAidedRateStddev * ap::kAidedRateStddev * Eigen::Matrix3d::Identity());
}
