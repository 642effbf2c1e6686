// The parameter struct, its validator, and the places its defaults are written down (the
// table in docs/parameters.md, config/default.yaml): they must agree with the struct.
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "attitude_propagator/config/parameters.h"
#include "package_files.h"
#include "refused_parameters.h"

namespace ap = attitude_propagator;
namespace fs = std::filesystem;

namespace {

using package_files::packageRoot;
using package_files::readFile;

std::string trim(const std::string& s) {
  const auto begin = s.find_first_not_of(" \t");
  if (begin == std::string::npos) return "";
  return s.substr(begin, s.find_last_not_of(" \t\r") - begin + 1);
}

// Top-level "name: value" lines of a flat YAML file, comments stripped.
std::map<std::string, std::string> yamlEntries(const fs::path& path) {
  std::map<std::string, std::string> entries;
  std::istringstream lines(readFile(path));
  std::string line;
  while (std::getline(lines, line)) {
    line = line.substr(0, line.find('#'));
    if (trim(line).empty() || line[0] == ' ') continue;
    const auto colon = line.find(':');
    if (colon == std::string::npos) continue;
    std::string value = trim(line.substr(colon + 1));
    if (value.size() >= 2 && (value.front() == '"' || value.front() == '\'')) {
      value = value.substr(1, value.size() - 2);
    }
    entries[trim(line.substr(0, colon))] = value;
  }
  return entries;
}

}  // namespace

TEST(Parameters, DefaultsAreKinematicOnImu) {
  const ap::NodeConfig config = ap::validateParameters(ap::Parameters{});
  EXPECT_EQ(config.model, ap::Model::Kinematic);
  EXPECT_EQ(config.rate_input, ap::RateInput::Imu);
  EXPECT_FALSE(config.dynamic.has_value());
  EXPECT_EQ(config.kinematic.integrator, ap::Integrator::Auto);
}

TEST(Parameters, AutoModelIsDynamicWithInertia) {
  ap::Parameters p;
  p.inertia = {1.0, 2.0, 2.5};
  p.publish_rate = 50.0;
  const ap::NodeConfig config = ap::validateParameters(p);
  EXPECT_EQ(config.model, ap::Model::Dynamic);
  ASSERT_TRUE(config.dynamic.has_value());
  EXPECT_DOUBLE_EQ(config.dynamic->max_step, 1.0 / 50.0);  // max_step 0: 1/publish_rate
}

// Every engine-side value set away from its default arrives unchanged where the engine reads
// it: the validated configuration, then engineConfig(). The values are chosen unlike the
// defaults (checked first), so a field left at its default or filled from another parameter
// shows.
TEST(Parameters, DynamicValuesReachTheEngineUnchanged) {
  ap::Parameters p;
  p.inertia = {1.0, 2.0, 2.5};
  p.integrator = "dopri5";
  p.torque_input = true;
  p.torque_frame = "fixed";
  p.torque_timeout = 2.5;
  p.tolerance = 3e-7;
  p.initial_angular_velocity = {0.125, -0.25, 0.375};
  p.initial_orientation = {0.0, 0.0, 0.6, 0.8};
  p.max_step = 0.004;
  p.max_dt = 0.5;
  p.publish_rate = 40.0;
  p.angular_velocity_stddev = 0.02;
  p.initial_orientation_stddev = 0.1;
  p.gyro_bias = {0.001, -0.002, 0.003};
  const ap::Parameters defaults;
  ASSERT_NE(p.torque_frame, defaults.torque_frame);
  ASSERT_NE(p.torque_timeout, defaults.torque_timeout);
  ASSERT_NE(p.tolerance, defaults.tolerance);
  ASSERT_NE(p.initial_angular_velocity, defaults.initial_angular_velocity);
  ASSERT_NE(p.max_step, defaults.max_step);
  ASSERT_NE(p.max_step, 1.0 / p.publish_rate);  // not the automatic value either
  ASSERT_NE(p.max_dt, defaults.max_dt);

  const ap::NodeConfig node = ap::validateParameters(p);
  EXPECT_EQ(node.model, ap::Model::Dynamic);
  EXPECT_TRUE(node.torque_input);
  EXPECT_EQ(node.torque_frame, ap::TorqueFrame::Fixed);
  const ap::EngineConfig engine = ap::engineConfig(node);
  EXPECT_EQ(engine.model, ap::Model::Dynamic);
  ASSERT_TRUE(node.dynamic.has_value());
  ASSERT_TRUE(engine.dynamic.has_value());
  for (const ap::DynamicConfig& d : {*node.dynamic, *engine.dynamic}) {
    EXPECT_EQ(d.integrator, ap::Integrator::Dopri5);
    EXPECT_TRUE(d.torque_input);
    EXPECT_EQ(d.torque_timeout, 2.5);
    EXPECT_EQ(d.tolerance, 3e-7);
    EXPECT_EQ(d.initial.w_B, Eigen::Vector3d(0.125, -0.25, 0.375));
    EXPECT_EQ(d.initial.q_WB.coeffs(), Eigen::Vector4d(0.0, 0.0, 0.6, 0.8));  // x y z w
    EXPECT_EQ(d.max_step, 0.004);
    EXPECT_EQ(d.time_policy.max_dt, 0.5);
    EXPECT_EQ(d.body.principalMoments(), Eigen::Vector3d(1.0, 2.0, 2.5));
  }
  EXPECT_EQ(engine.publish_rate, 40.0);
  EXPECT_EQ(engine.rate_stddev, 0.02);
  EXPECT_EQ(engine.initial_orientation_stddev, 0.1);
  EXPECT_EQ(engine.gyro_bias_B, Eigen::Vector3d(0.001, -0.002, 0.003));
}

// The defaults reach the dynamic configuration as docs/parameters.md's table gives them: torque
// held (timeout 0), tolerance 1e-9, at rest, torques in the body frame, max_dt 1 s.
TEST(Parameters, DynamicDefaultsAreTheDocumentedOnes) {
  ap::Parameters p;
  p.inertia = {1.0, 2.0, 2.5};
  const ap::NodeConfig node = ap::validateParameters(p);
  ASSERT_TRUE(node.dynamic.has_value());
  EXPECT_FALSE(node.torque_input);
  EXPECT_EQ(node.torque_frame, ap::TorqueFrame::Body);
  EXPECT_EQ(node.dynamic->integrator, ap::Integrator::Auto);
  EXPECT_EQ(node.dynamic->torque_timeout, 0.0);
  EXPECT_EQ(node.dynamic->tolerance, 1e-9);
  EXPECT_EQ(node.dynamic->initial.w_B, Eigen::Vector3d::Zero());
  EXPECT_EQ(node.dynamic->time_policy.max_dt, 1.0);
  EXPECT_EQ(node.dynamic->max_step, 1.0 / 100.0);  // 1 / the default publish_rate
  const ap::EngineConfig engine = ap::engineConfig(node);
  EXPECT_EQ(engine.publish_rate, 100.0);
  EXPECT_EQ(engine.rate_stddev, 0.01);
  EXPECT_EQ(engine.initial_orientation_stddev, M_PI);
}

// The kinematic model takes the integrator, max_dt and the initial orientation, and ignores
// the dynamic model's parameters (docs/parameters.md: publish_rate, max_step, tolerance,
// torque_*, initial_angular_velocity) without refusing them.
TEST(Parameters, KinematicValuesReachTheEngineUnchanged) {
  ap::Parameters p;
  p.integrator = "exp2";
  p.max_dt = 0.25;
  p.initial_orientation = {0.6, 0.0, 0.0, 0.8};
  p.angular_velocity_stddev = 0.5;
  p.max_step = 0.004;
  p.tolerance = 1e-4;
  p.torque_timeout = 7.0;
  p.torque_frame = "fixed";
  p.initial_angular_velocity = {1.0, 2.0, 3.0};
  const ap::NodeConfig node = ap::validateParameters(p);
  EXPECT_EQ(node.model, ap::Model::Kinematic);
  EXPECT_FALSE(node.dynamic.has_value());
  const ap::EngineConfig engine = ap::engineConfig(node);
  EXPECT_EQ(engine.model, ap::Model::Kinematic);
  EXPECT_FALSE(engine.dynamic.has_value());
  EXPECT_EQ(engine.kinematic.integrator, ap::Integrator::Exp2);
  EXPECT_EQ(engine.kinematic.time_policy.max_dt, 0.25);
  EXPECT_EQ(engine.kinematic.initial_q_WB.coeffs(), Eigen::Vector4d(0.6, 0.0, 0.0, 0.8));
  EXPECT_EQ(engine.rate_stddev, 0.5);
}

// max_step: 0 means 1/publish_rate; otherwise docs/parameters.md's range [1e-5, 60] s, and at least
// max_dt / 1e5 (one call crosses max_dt in at most 1e5 steps), the automatic value included.
TEST(Parameters, MaxStepFollowsTheDocumentedRules) {
  auto dynamic = [](double max_step, double max_dt, double publish_rate) {
    ap::Parameters p;
    p.inertia = {1.0, 2.0, 2.5};
    p.max_step = max_step;
    p.max_dt = max_dt;
    p.publish_rate = publish_rate;
    return p;
  };
  auto step = [](const ap::Parameters& p) { return ap::validateParameters(p).dynamic->max_step; };
  EXPECT_EQ(step(dynamic(0.0, 1.0, 50.0)), 1.0 / 50.0);
  EXPECT_EQ(step(dynamic(0.0, 60.0, 1000.0)), 1.0 / 1000.0);
  EXPECT_EQ(step(dynamic(1e-5, 1.0, 100.0)), 1e-5);   // the smallest
  EXPECT_EQ(step(dynamic(60.0, 60.0, 100.0)), 60.0);  // the largest
  EXPECT_EQ(step(dynamic(6e-4, 60.0, 100.0)), 6e-4);  // max_dt / 1e5 exactly
  expectRefused(dynamic(0.99e-5, 1.0, 100.0), "max_step");
  expectRefused(dynamic(60.001, 60.0, 100.0), "max_step");
  expectRefused(dynamic(5.9e-4, 60.0, 100.0), "max_step");  // below max_dt / 1e5
  expectRefused(dynamic(2e-5, 3.0, 100.0), "max_step");     // below max_dt / 1e5 = 3e-5
}

// The other documented ranges, at their ends and just past them: torque_timeout in
// [0, 3600] s, tolerance in [1e-12, 1e-2], |initial_angular_velocity| at most 1e5 rad/s.
TEST(Parameters, DocumentedRangesAreInclusive) {
  auto dynamic = [](auto change) {
    ap::Parameters p;
    p.inertia = {1.0, 2.0, 2.5};
    change(p);
    return p;
  };
  auto accepted = [](const ap::Parameters& p) { return ap::validateParameters(p).dynamic.value(); };
  EXPECT_EQ(accepted(dynamic([](auto& p) { p.torque_timeout = 3600.0; })).torque_timeout, 3600.0);
  expectRefused(dynamic([](auto& p) { p.torque_timeout = 3600.5; }), "torque_timeout");
  // time_jump_threshold: [1e-3, 3600] s, kMinTimeJumpThreshold the documented smallest.
  EXPECT_EQ(ap::kMinTimeJumpThreshold, 1e-3);
  EXPECT_EQ(ap::validateParameters(dynamic([](auto& p) {
              p.time_jump_threshold = ap::kMinTimeJumpThreshold;
            })).parameters.time_jump_threshold,
            ap::kMinTimeJumpThreshold);
  expectRefused(dynamic([](auto& p) { p.time_jump_threshold = 0.999e-3; }), "time_jump_threshold");
  EXPECT_EQ(accepted(dynamic([](auto& p) { p.tolerance = 1e-12; })).tolerance, 1e-12);
  EXPECT_EQ(accepted(dynamic([](auto& p) { p.tolerance = 1e-2; })).tolerance, 1e-2);
  expectRefused(dynamic([](auto& p) { p.tolerance = 0.9e-12; }), "tolerance");
  expectRefused(dynamic([](auto& p) { p.tolerance = 0.011; }), "tolerance");
  EXPECT_EQ(accepted(dynamic([](auto& p) {
              p.initial_angular_velocity = {0.0, 6e4, 8e4};
            })).initial.w_B,
            Eigen::Vector3d(0.0, 6e4, 8e4));  // |w| = 1e5
  expectRefused(dynamic([](auto& p) {
                  p.initial_angular_velocity = {0.0, 6e4, 8.001e4};
                }),
                "initial_angular_velocity");
}

// A parameter's value in its error is capped as a message's text is (quoted_text.h): a 1 MB
// integrator name gives a line of its first 64 bytes and its length, not a 1 MB one.
TEST(Parameters, AHugeValueIsCappedInItsError) {
  for (const std::string name : {"integrator", "model", "rate_input"}) {
    ap::Parameters p;
    const std::string huge(1000 * 1000, 'x');
    if (name == "integrator") p.integrator = huge;
    if (name == "model") p.model = huge;
    if (name == "rate_input") p.rate_input = huge;
    try {
      ap::validateParameters(p);
      ADD_FAILURE() << name;
    } catch (const std::invalid_argument& e) {
      const std::string what = e.what();
      EXPECT_EQ(what.rfind(name + ": ", 0), 0u) << what.substr(0, 100);
      EXPECT_NE(what.find("...(1000000 bytes)"), std::string::npos) << what.size();
      EXPECT_LT(what.size(), 1000u);
    }
  }
}

TEST(Parameters, InitialOrientationIsNormalised) {
  ap::Parameters p;
  p.initial_orientation = {0.0, 0.0, 2.0, 2.0};
  const Eigen::Quaterniond q = ap::validateParameters(p).kinematic.initial_q_WB;
  EXPECT_NEAR(q.norm(), 1.0, 1e-15);
  EXPECT_NEAR(q.z(), std::sqrt(0.5), 1e-15);
}

TEST(Parameters, RejectsEachBadValueNamingTheParameter) {
  auto with = [](auto change) {
    ap::Parameters p;
    change(p);
    return p;
  };
  expectRefused(with([](auto& p) { p.model = "magic"; }), "model");
  expectRefused(with([](auto& p) { p.integrator = "leapfrog"; }), "integrator");
  expectRefused(with([](auto& p) { p.integrator = "dopri5"; }), "integrator");  // not kinematic
  expectRefused(with([](auto& p) { p.rate_input = "gps"; }), "rate_input");
  expectRefused(with([](auto& p) { p.rate_input = "none"; }), "rate_input");  // kinematic
  expectRefused(with([](auto& p) { p.torque_frame = "imu"; }), "torque_frame");
  expectRefused(with([](auto& p) { p.torque_input = true; }), "torque_input");  // no inertia
  expectRefused(with([](auto& p) { p.model = "dynamic"; }), "inertia");
  expectRefused(with([](auto& p) { p.inertia = {1.0, 2.0}; }), "inertia");
  expectRefused(with([](auto& p) { p.inertia = {1.0, -2.0, 2.0}; }), "inertia");
  expectRefused(with([](auto& p) { p.inertia = {1.0, 1.0, 3.0}; }), "inertia");  // triangle
  expectRefused(with([](auto& p) { p.inertia = {1.0, NAN, 1.0}; }), "inertia");
  expectRefused(with([](auto& p) {
                  p.inertia = {1.0, 1.0, 1.0};
                  p.torque_input = true;
                  p.integrator = "exact";
                }),
                "integrator");
  expectRefused(with([](auto& p) {
                  p.initial_orientation = {0.0, 0.0, 0.0, 0.0};
                }),
                "initial_orientation");
  expectRefused(with([](auto& p) {
                  p.initial_orientation = {0.0, 0.0, 1.0};
                }),
                "initial_orientation");
  expectRefused(with([](auto& p) {
                  p.initial_angular_velocity = {0.0, INFINITY, 0.0};
                }),
                "initial_angular_velocity");
  expectRefused(with([](auto& p) { p.publish_rate = 0.0; }), "publish_rate");
  expectRefused(with([](auto& p) { p.max_step = -0.1; }), "max_step");
  expectRefused(with([](auto& p) {
                  p.inertia = {1.0, 1.0, 1.0};
                  p.publish_rate = 0.5;  // every 2 s tick a gap over max_dt = 1 s
                }),
                "publish_rate");
  expectRefused(with([](auto& p) { p.max_dt = NAN; }), "max_dt");
  expectRefused(with([](auto& p) { p.tolerance = 0.0; }), "tolerance");
  expectRefused(with([](auto& p) { p.torque_timeout = -1.0; }), "torque_timeout");
  expectRefused(with([](auto& p) { p.angular_velocity_stddev = -1.0; }), "angular_velocity_stddev");
  expectRefused(with([](auto& p) { p.fixed_frame = ""; }), "fixed_frame");
  expectRefused(with([](auto& p) { p.body_frame = "/base_link"; }), "body_frame");
  expectRefused(with([](auto& p) { p.body_frame = "world"; }), "body_frame");
}

// Gravity and the field: the values reach EngineConfig::aiding unchanged; the start-up
// alignment is on exactly when use_accel is set and no initial_orientation is given.
TEST(Parameters, AidingValuesReachTheEngineUnchanged) {
  ap::Parameters p;
  p.use_accel = true;
  p.accel_stddev = 0.25;
  p.use_mag = true;
  p.mag_stddev = 3e-7;
  p.declination = -0.125;
  p.use_accel_covariance = false;
  p.use_mag_covariance = false;
  p.mag_bias = {2e-6, -3e-6, 5e-7};
  const ap::Parameters defaults;
  ASSERT_TRUE(defaults.initial_orientation.empty());  // none given by default
  ASSERT_NE(p.accel_stddev, defaults.accel_stddev);
  ASSERT_NE(p.mag_stddev, defaults.mag_stddev);
  const ap::AidingConfig a = ap::engineConfig(ap::validateParameters(p)).aiding;
  EXPECT_TRUE(a.use_accel);
  EXPECT_EQ(a.accel_stddev, 0.25);
  EXPECT_TRUE(a.use_mag);
  EXPECT_EQ(a.mag_stddev, 3e-7);
  EXPECT_EQ(a.declination, -0.125);
  EXPECT_FALSE(a.use_accel_covariance);
  EXPECT_FALSE(a.use_mag_covariance);
  EXPECT_EQ(a.mag_bias, Eigen::Vector3d(2e-6, -3e-6, 5e-7));  // x, y, z in that order
  EXPECT_TRUE(a.align);
  p.initial_orientation = {0.0, 0.0, 0.0, 1.0};  // given: the attitude starts there
  EXPECT_FALSE(ap::engineConfig(ap::validateParameters(p)).aiding.align);
  p.initial_orientation.clear();
  p.use_accel = false;  // no gravity: nothing to align to
  EXPECT_FALSE(ap::engineConfig(ap::validateParameters(p)).aiding.align);
  const ap::AidingConfig off = ap::engineConfig(ap::validateParameters(defaults)).aiding;
  EXPECT_FALSE(off.any());
  EXPECT_FALSE(off.align);
  EXPECT_EQ(off.accel_stddev, 0.1);
  EXPECT_EQ(off.mag_stddev, 1e-6);
  EXPECT_EQ(off.declination, 0.0);
  EXPECT_TRUE(off.use_accel_covariance);  // a message's covariance is taken at its word
  EXPECT_TRUE(off.use_mag_covariance);
  EXPECT_EQ(off.mag_bias, Eigen::Vector3d::Zero());
}

// No initial_orientation: the identity, in every world_frame (its axes' own identity).
TEST(Parameters, InitialOrientationNotGivenIsTheIdentity) {
  const ap::NodeConfig node = ap::validateParameters(ap::Parameters{});
  EXPECT_EQ(node.kinematic.initial_q_WB.coeffs(), Eigen::Vector4d(0.0, 0.0, 0.0, 1.0));
}

// use_accel and use_mag are the kinematic model's; the accelerometer comes in Imu messages.
// Each refusal names the setting and what is accepted, before the engine would throw.
TEST(Parameters, AidingRefusedWhereItCannotWork) {
  auto with = [](auto change) {
    ap::Parameters p;
    change(p);
    return p;
  };
  expectRefused(with([](auto& p) {
                  p.inertia = {1.0, 2.0, 2.5};
                  p.use_accel = true;
                }),
                "use_accel");
  expectRefused(with([](auto& p) {
                  p.inertia = {1.0, 2.0, 2.5};
                  p.use_mag = true;
                }),
                "use_mag");
  expectRefused(with([](auto& p) {
                  p.rate_input = "twist";
                  p.use_accel = true;
                }),
                "use_accel");
  expectRefused(with([](auto& p) { p.accel_stddev = 0.0; }), "accel_stddev");
  expectRefused(with([](auto& p) { p.accel_stddev = 100.5; }), "accel_stddev");
  expectRefused(with([](auto& p) { p.mag_stddev = NAN; }), "mag_stddev");
  expectRefused(with([](auto& p) { p.mag_stddev = 0.02; }), "mag_stddev");
  expectRefused(with([](auto& p) { p.declination = 3.2; }), "declination");
  expectRefused(with([](auto& p) { p.mag_bias = {0.0, 1e-6}; }), "mag_bias");
  expectRefused(with([](auto& p) { p.mag_bias = {0.0, NAN, 0.0}; }), "mag_bias");
  // Its size bounded, not each axis: 0.006 on two axes is 8.5 mT, 0.008 on two 11.3 mT.
  expectRefused(with([](auto& p) { p.mag_bias = {0.008, -0.008, 0.0}; }), "mag_bias");
  EXPECT_NO_THROW(ap::validateParameters(with([](auto& p) {
    p.rate_input = "twist";
    p.use_mag = true;  // a field needs no accelerometer message
    p.accel_stddev = 100.0;
    p.mag_stddev = 1e-2;
    p.declination = -M_PI;
    p.mag_bias = {0.006, -0.006, 0.0};
  })));
}

// docs/node.md's table of the accel_*/mag_* counters names AidingCounters::forEach's counters,
// in its order: the diagnostics and the bag tools' summaries take the names from there.
TEST(Parameters, AidingCounterTableFollowsTheCore) {
  const std::string text = readFile(packageRoot() / "docs" / "node.md");
  const auto start = text.find("## Gravity and north");
  ASSERT_NE(start, std::string::npos) << "docs/node.md: no section Gravity and north";
  std::istringstream lines(text.substr(start, text.find("\n## ", start + 1) - start));
  std::vector<std::string> documented;
  std::string line;
  while (std::getline(lines, line)) {
    if (line.rfind("| `", 0) == 0) documented.push_back(line.substr(3, line.find('`', 3) - 3));
  }
  std::vector<std::string> names;
  ap::AidingCounters{}.forEach(
      [&names](const char* name, std::uint64_t) { names.push_back(name); });
  EXPECT_EQ(documented, names);
}

TEST(Parameters, FormatsAsYaml) {
  EXPECT_EQ(ap::formatParameter(100.0), "100.0");
  EXPECT_EQ(ap::formatParameter(1e-9), "1.0e-09");
  EXPECT_EQ(ap::formatParameter(0.1), "0.1");
  EXPECT_EQ(ap::formatParameter(std::vector<double>{0, 0, 0, 1}), "[0.0, 0.0, 0.0, 1.0]");
  EXPECT_EQ(ap::formatParameter(std::vector<double>{}), "[]");
  EXPECT_EQ(ap::formatParameter(true), "true");
  EXPECT_EQ(ap::formatParameter(10000), "10000");  // an int stays an int for rosparam
}

// The queue sizes are whole counts of messages in [1, 1e6] (docs/parameters.md).
TEST(Parameters, QueueSizesAreCountsWithinTheirDocumentedRange) {
  EXPECT_EQ(ap::kMaxQueueSize, 1000000);  // the documented largest
  for (const int v : {1, ap::kMaxQueueSize - 1, ap::kMaxQueueSize}) {
    ap::Parameters p;
    p.input_queue_size = v;
    p.output_queue_size = v;
    EXPECT_EQ(ap::validateParameters(p).parameters.input_queue_size, v);
  }
  for (const int v : {0, -1, ap::kMaxQueueSize + 1}) {
    ap::Parameters in;
    in.input_queue_size = v;
    expectRefused(in, "input_queue_size");
    ap::Parameters out;
    out.output_queue_size = v;
    expectRefused(out, "output_queue_size");
  }
}

// max_gap_fill: lost samples in a row filled, [0, 4] (docs/parameters.md), reaching the kinematic
// model as given; -1 and 5 are refused naming the range.
TEST(Parameters, MaxGapFillIsACountWithinItsDocumentedRange) {
  EXPECT_EQ(ap::kMaxGapFill, 4);  // the documented largest
  for (const int v : {0, ap::kMaxGapFill - 1, ap::kMaxGapFill}) {
    ap::Parameters p;
    p.max_gap_fill = v;
    EXPECT_EQ(ap::engineConfig(ap::validateParameters(p)).kinematic.max_gap_fill, v);
  }
  for (const int v : {-1, ap::kMaxGapFill + 1}) {
    ap::Parameters p;
    p.max_gap_fill = v;
    expectRefused(p, "max_gap_fill");
    try {
      ap::validateParameters(p);
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("an integer in [0, 4]"), std::string::npos) << e.what();
    }
  }
}

// The table in docs/parameters.md is generated from the struct; this fails when they drift
// apart and prints the table to paste.
TEST(Parameters, DocsTableMatchesTheStruct) {
  const fs::path page = packageRoot() / "docs" / "parameters.md";
  ASSERT_TRUE(fs::is_regular_file(page)) << page << " is missing";
  const std::string text = readFile(page);
  const std::string table = ap::parameterTableMarkdown();
  EXPECT_NE(text.find(table), std::string::npos)
      << "docs/parameters.md's parameter table differs from the Parameters struct; expected:\n"
      << table;
}

// config/default.yaml lists every parameter once with the struct's default.
TEST(Parameters, DefaultYamlMatchesTheStruct) {
  const auto yaml = yamlEntries(packageRoot() / "config" / "default.yaml");
  const ap::Parameters defaults;
  std::size_t count = 0;
  ap::forEachParameter(defaults,
                       [&](const char* name, const auto& value, const char*, const char*) {
                         ++count;
                         const auto it = yaml.find(name);
                         if (it == yaml.end()) {
                           ADD_FAILURE() << "config/default.yaml lacks " << name;
                           return;
                         }
                         EXPECT_EQ(it->second, ap::formatParameter(value)) << "default of " << name;
                       });
  EXPECT_EQ(yaml.size(), count) << "config/default.yaml has names the struct does not";
}

// Every YAML in config/ uses known names only (the node would refuse an unknown one).
TEST(Parameters, ConfigFilesUseKnownNames) {
  const auto names = ap::parameterNames();
  for (const auto& file : fs::directory_iterator(packageRoot() / "config")) {
    if (file.path().extension() != ".yaml") continue;
    for (const auto& [name, value] : yamlEntries(file.path())) {
      EXPECT_NE(std::find(names.begin(), names.end(), name), names.end())
          << file.path().filename() << ": unknown parameter " << name;
    }
  }
}
