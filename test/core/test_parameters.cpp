// The parameter struct, its validator, and the places its defaults are written down (the
// README table, config/default.yaml): they must agree with the struct.
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

#include "attitude_propagator/config/parameters.h"

namespace ap = attitude_propagator;
namespace fs = std::filesystem;

namespace {

// The package root, from this file's path (test/core/test_parameters.cpp).
fs::path packageRoot() { return fs::path(__FILE__).parent_path().parent_path().parent_path(); }

std::string readFile(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

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

// Expects validateParameters to throw a message starting with the parameter's name and
// listing the accepted values.
void expectRejected(const ap::Parameters& p, const std::string& name) {
  try {
    ap::validateParameters(p);
    ADD_FAILURE() << "accepted a bad " << name;
  } catch (const std::invalid_argument& e) {
    const std::string message = e.what();
    EXPECT_EQ(message.rfind(name + ": ", 0), 0u) << message;
    EXPECT_NE(message.find("accepted"), std::string::npos) << message;
  }
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
  expectRejected(with([](auto& p) { p.model = "magic"; }), "model");
  expectRejected(with([](auto& p) { p.integrator = "leapfrog"; }), "integrator");
  expectRejected(with([](auto& p) { p.integrator = "dopri5"; }), "integrator");  // not kinematic
  expectRejected(with([](auto& p) { p.rate_input = "gps"; }), "rate_input");
  expectRejected(with([](auto& p) { p.rate_input = "none"; }), "rate_input");  // kinematic
  expectRejected(with([](auto& p) { p.torque_frame = "imu"; }), "torque_frame");
  expectRejected(with([](auto& p) { p.torque_input = true; }), "torque_input");  // no inertia
  expectRejected(with([](auto& p) { p.model = "dynamic"; }), "inertia");
  expectRejected(with([](auto& p) { p.inertia = {1.0, 2.0}; }), "inertia");
  expectRejected(with([](auto& p) { p.inertia = {1.0, -2.0, 2.0}; }), "inertia");
  expectRejected(with([](auto& p) { p.inertia = {1.0, 1.0, 3.0}; }), "inertia");  // triangle
  expectRejected(with([](auto& p) { p.inertia = {1.0, NAN, 1.0}; }), "inertia");
  expectRejected(with([](auto& p) {
                   p.inertia = {1.0, 1.0, 1.0};
                   p.torque_input = true;
                   p.integrator = "exact";
                 }),
                 "integrator");
  expectRejected(with([](auto& p) {
                   p.initial_orientation = {0.0, 0.0, 0.0, 0.0};
                 }),
                 "initial_orientation");
  expectRejected(with([](auto& p) {
                   p.initial_orientation = {0.0, 0.0, 1.0};
                 }),
                 "initial_orientation");
  expectRejected(with([](auto& p) {
                   p.initial_angular_velocity = {0.0, INFINITY, 0.0};
                 }),
                 "initial_angular_velocity");
  expectRejected(with([](auto& p) { p.publish_rate = 0.0; }), "publish_rate");
  expectRejected(with([](auto& p) { p.max_step = -0.1; }), "max_step");
  expectRejected(with([](auto& p) {
                   p.inertia = {1.0, 1.0, 1.0};
                   p.publish_rate = 0.5;  // every 2 s tick a gap over max_dt = 1 s
                 }),
                 "publish_rate");
  expectRejected(with([](auto& p) { p.max_dt = NAN; }), "max_dt");
  expectRejected(with([](auto& p) { p.tolerance = 0.0; }), "tolerance");
  expectRejected(with([](auto& p) { p.torque_timeout = -1.0; }), "torque_timeout");
  expectRejected(with([](auto& p) { p.angular_velocity_stddev = -1.0; }),
                 "angular_velocity_stddev");
  expectRejected(with([](auto& p) { p.fixed_frame = ""; }), "fixed_frame");
  expectRejected(with([](auto& p) { p.body_frame = "/base_link"; }), "body_frame");
  expectRejected(with([](auto& p) { p.body_frame = "world"; }), "body_frame");
}

TEST(Parameters, FormatsAsYaml) {
  EXPECT_EQ(ap::formatParameter(100.0), "100.0");
  EXPECT_EQ(ap::formatParameter(1e-9), "1.0e-09");
  EXPECT_EQ(ap::formatParameter(0.1), "0.1");
  EXPECT_EQ(ap::formatParameter(std::vector<double>{0, 0, 0, 1}), "[0.0, 0.0, 0.0, 1.0]");
  EXPECT_EQ(ap::formatParameter(std::vector<double>{}), "[]");
  EXPECT_EQ(ap::formatParameter(true), "true");
}

// The README's table is generated from the struct; this fails when they drift apart and
// prints the table to paste.
TEST(Parameters, ReadmeTableMatchesTheStruct) {
  const std::string readme = readFile(packageRoot() / "README.md");
  const std::string table = ap::parameterTableMarkdown();
  EXPECT_NE(readme.find(table), std::string::npos)
      << "README.md's parameter table differs from the Parameters struct; expected:\n"
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
