#include "attitude_propagator/config/parameters.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <stdexcept>
#include <type_traits>
#include <utility>

#include "attitude_propagator/numerics/quaternion.h"
#include "attitude_propagator/quoted_text.h"

namespace attitude_propagator {

namespace {

[[noreturn]] void fail(const std::string& name, const std::string& problem) {
  throw std::invalid_argument(name + ": " + problem);
}

/// A finite value above min (or at it, if min_inclusive) and at most max.
void requireFinite(const std::string& name, double value, double min, bool min_inclusive,
                   double max, const std::string& accepted) {
  const bool ok =
      std::isfinite(value) && (min_inclusive ? value >= min : value > min) && value <= max;
  if (!ok) fail(name, "invalid value " + formatParameter(value) + "; accepted: " + accepted);
}

void requireVector(const std::string& name, const std::vector<double>& v, std::size_t size,
                   const std::string& accepted) {
  bool ok = v.size() == size;
  for (double x : v) ok = ok && std::isfinite(x);
  if (!ok) fail(name, "invalid value " + formatParameter(v) + "; accepted: " + accepted);
}

void requireOneOf(const std::string& name, const std::string& value,
                  const std::vector<std::string>& accepted) {
  std::string list;
  for (const auto& a : accepted) {
    if (value == a) return;
    list += (list.empty() ? "" : " ") + a;
  }
  fail(name, "unknown value '" + logText(value) + "'; accepted: " + list);
}

void requireCount(const std::string& name, int value, int max, const std::string& accepted) {
  if (value < 1 || value > max) {
    fail(name, "invalid value " + formatParameter(value) + "; accepted: " + accepted);
  }
}

void requireFrameName(const std::string& name, const std::string& frame) {
  // tf2 refuses frame ids with a leading slash (tf1 style) and empty ones.
  if (frame.empty() || frame.front() == '/') {
    fail(name, "invalid frame id '" + frame +
                   "'; accepted: a non-empty tf2 frame id without "
                   "a leading '/'");
  }
}

/// Names of the integrators that can drive the model (with torque: those that take one), for
/// error messages.
std::string acceptedIntegrators(Model model, bool torque = false) {
  std::vector<std::string> names{"auto"};
  for (Integrator m : integratorsFor(model)) {
    if (!torque || integratorInfo(m).takes_torque) names.push_back(integratorName(m));
  }
  return joinNames(names);
}

/// `a` `b` `c`: names in backticks, for the parameter documentation.
std::string quotedNames(const std::vector<Integrator>& methods) {
  std::string list;
  for (Integrator m : methods) list += (list.empty() ? "`" : " `") + integratorName(m) + "`";
  return list;
}

Model resolveModel(const Parameters& p) {
  const Model requested = modelFromName(p.model);  // throws "model: ..."
  if (requested != Model::Auto) return requested;
  return p.inertia.empty() ? Model::Kinematic : Model::Dynamic;
}

/// `auto` on the kinematic model, for the parameter documentation: the table's method, chosen
/// per stream by KinematicAutoRule (auto_integrator.h) where the measurements put another ahead.
std::string autoKinematicDoc() {
  return quotedNames({autoIntegrator(Model::Kinematic, false)}) +
         " (per stream: `exp2` on means with filled losses where the stream predicts it the "
         "smaller error, `rk4` or `exp2` under heavy stamp jitter; docs/real_streams.md)";
}

Integrator resolveIntegrator(const Parameters& p, Model model) {
  const Integrator integrator = integratorFromName(p.integrator);  // throws "integrator: ..."
  const bool ok =
      model == Model::Dynamic ? supportsDynamic(integrator) : supportsKinematic(integrator);
  if (!ok) {
    fail("integrator", "'" + logText(p.integrator) + "' does not drive the " + modelName(model) +
                           " model; accepted: " + acceptedIntegrators(model));
  }
  if (model == Model::Dynamic && p.torque_input && !integratorInfo(integrator).takes_torque) {
    fail("integrator", "'" + logText(p.integrator) +
                           "' takes no torque and torque_input is true; accepted: " +
                           acceptedIntegrators(model, true));
  }
  return integrator;
}

RigidBody makeBody(const std::vector<double>& inertia) {
  // The moments' range (limits.h, checked by RigidBody) keeps I |w|^2 and the closed forms'
  // squares of I w finite for every rate the door lets in.
  const std::string accepted =
      "3 positive principal moments [I1, I2, I3] in [1e-15, 1e15] with each at most the sum of "
      "the others, or 6 values [Ixx, Iyy, Izz, Ixy, Ixz, Iyz] of a positive definite tensor with "
      "such moments (kg m^2)";
  bool ok = inertia.size() == 3 || inertia.size() == 6;
  for (double x : inertia) ok = ok && std::isfinite(x);
  for (std::size_t i = 0; ok && i < 3; ++i) ok = inertia[i] > 0.0;
  if (!ok) fail("inertia", "invalid value " + formatParameter(inertia) + "; accepted: " + accepted);
  try {
    return RigidBody::fromParameter(inertia);
  } catch (const std::invalid_argument& e) {
    fail("inertia", std::string(e.what()) + "; accepted: " + accepted);
  }
}

Eigen::Quaterniond initialOrientation(const std::vector<double>& v) {
  const std::string accepted = "[] (none given) or [x, y, z, w], finite, not all zero (any scale)";
  if (v.empty()) return Eigen::Quaterniond::Identity();  // none given
  requireVector("initial_orientation", v, 4, accepted);
  const std::optional<Eigen::Quaterniond> q =
      safeNormalized(Eigen::Quaterniond(v[3], v[0], v[1], v[2]));
  if (!q) fail("initial_orientation", "zero quaternion; accepted: " + accepted);
  return *q;
}

// The bounds below (limits.h) make every accepted set run in bounded CPU and finite numbers:
// publish_rate bounds the timer's calls per second, max_step from below and max_dt / max_step
// the grid steps per call, tolerance from below the dopri5 sub-steps (below 1e-12 its error
// control is round-off and only shrinks the step), max_dt and torque_timeout keep stamps plus
// intervals exact sums, the initial rate the energy.
void checkScalars(const Parameters& p) {
  requireOneOf("rate_input", p.rate_input, {"imu", "twist", "none"});
  requireOneOf("torque_frame", p.torque_frame, {"body", "fixed"});
  requireFinite("torque_timeout", p.torque_timeout, 0.0, true, kMaxTorqueTimeout,
                "a finite number >= 0 and at most 3600 (s)");
  requireFinite("publish_rate", p.publish_rate, 0.0, false, kMaxPublishRate,
                "a finite number > 0 and at most 1000 (Hz)");
  const std::string step_range = "0 (1/publish_rate) or a number in [1e-5, 60] (s)";
  requireFinite("max_step", p.max_step, 0.0, true, kMaxMaxDt, step_range);
  if (p.max_step > 0.0 && p.max_step < kMinMaxStep) {
    fail("max_step", "invalid value " + formatParameter(p.max_step) + "; accepted: " + step_range);
  }
  requireFinite("max_dt", p.max_dt, kMinMaxDt, true, kMaxMaxDt, "a number in [1e-6, 60] (s)");
  requireFinite("max_future", p.max_future, 0.0, false, kMaxFuture,
                "a number > 0 and at most 3600 (s)");
  requireFinite("time_jump_threshold", p.time_jump_threshold, kMinTimeJumpThreshold, true,
                kMaxFuture, "a number in [1e-3, 3600] (s)");
  requireFinite("rate_delay", p.rate_delay, 0.0, true, p.max_dt,
                "a finite number >= 0 and at most max_dt (s)");
  requireFinite("tolerance", p.tolerance, kMinTolerance, true, kMaxTolerance,
                "a number in [1e-12, 1e-2]");
  requireFinite("angular_velocity_stddev", p.angular_velocity_stddev, 0.0, true, kMaxRateStddev,
                "a finite number >= 0 and at most 1000 (rad/s)");
  // Beyond pi the angle is no more unknown than at pi (the covariance is capped at pi^2).
  requireFinite("initial_orientation_stddev", p.initial_orientation_stddev, 0.0, true, M_PI,
                "a finite number in [0, pi] (rad)");
  requireOneOf("tf_conflict", p.tf_conflict, {"warn", "stop", "ignore"});
  if (p.max_gap_fill < 0 || p.max_gap_fill > kMaxGapFill) {
    fail("max_gap_fill",
         "invalid value " + formatParameter(p.max_gap_fill) + "; accepted: an integer in [0, 4]");
  }
  requireCount("input_queue_size", p.input_queue_size, kMaxQueueSize, "an integer in [1, 1000000]");
  requireCount("output_queue_size", p.output_queue_size, kMaxQueueSize,
               "an integer in [1, 1000000]");
  // Late fixes (docs/design.md §6.9): the history's memory bound is kMaxFixHistory seconds and
  // kMaxFixHistorySamples inputs (limits.h).
  requireOneOf("fix_mode", p.fix_mode, {"fuse", "reset"});
  requireFinite("fix_history", p.fix_history, 0.0, false, kMaxFixHistory,
                "a number > 0 and at most 10 (s)");
  requireFinite("fix_gate", p.fix_gate, 0.0, false, std::numeric_limits<double>::max(),
                "a finite number > 0");
  requireFinite("fix_stddev", p.fix_stddev, 0.0, false, M_PI, "a number > 0 and at most pi (rad)");
  requireFinite("gyro_bias_random_walk", p.gyro_bias_random_walk, 0.0, true, kMaxRateStddev,
                "a finite number >= 0 and at most 1000 (rad/s/sqrt(s))");
  requireFinite("gyro_bias_stddev", p.gyro_bias_stddev, 0.0, true, kMaxGyroBiasStddev,
                "a finite number >= 0 and at most 10 (rad/s)");
  // The engine's bounds (checkAidingConfig), refused here first in the parameters' words.
  requireFinite("accel_stddev", p.accel_stddev, 0.0, false, 100.0,
                "a number > 0 and at most 100 (m/s^2)");
  requireFinite("mag_stddev", p.mag_stddev, 0.0, false, 1e-2, "a number > 0 and at most 0.01 (T)");
  requireFinite("declination", p.declination, -M_PI, true, M_PI,
                "a number in [-pi, pi] (rad, east of true north positive)");
  const std::string field_range = "[x, y, z], finite, of size at most 0.01 (T, body frame)";
  requireVector("mag_bias", p.mag_bias, 3, field_range);
  if (!(Eigen::Vector3d(p.mag_bias[0], p.mag_bias[1], p.mag_bias[2]).norm() <= kMaxMagBias)) {
    fail("mag_bias", "invalid value " + formatParameter(p.mag_bias) + "; accepted: " + field_range);
  }
  const std::string rate_range = "[x, y, z], finite, |w| <= 1e5 (rad/s)";
  const auto& w = p.initial_angular_velocity;
  requireVector("initial_angular_velocity", w, 3, rate_range);
  if (!(Eigen::Vector3d(w[0], w[1], w[2]).norm() <= kMaxBodyRate)) {
    fail("initial_angular_velocity",
         "invalid value " + formatParameter(w) + "; accepted: " + rate_range);
  }
  requireFrameName("fixed_frame", p.fixed_frame);
  requireFrameName("body_frame", p.body_frame);
  requireOneOf("world_frame", p.world_frame, {"enu", "nwu", "ned"});
  if (p.fixed_frame == p.body_frame) {
    fail("body_frame", "equals fixed_frame '" + p.fixed_frame +
                           "'; accepted: a frame id different from fixed_frame");
  }
  // fix_frame: empty means body_frame; the fixed frame would measure nothing.
  if (!p.fix_frame.empty()) requireFrameName("fix_frame", p.fix_frame);
  if (p.fix_frame == p.fixed_frame) {
    fail("fix_frame", "equals fixed_frame '" + p.fixed_frame +
                          "'; accepted: empty (body_frame) or a frame joined to body_frame");
  }
}

// Real-stream settings of the kinematic model: what a rate sample means, the stamp filter and
// the gyro bias. Checked whatever the model, so a misspelt value always refuses start.
void applyStreamParameters(const Parameters& p, KinematicConfig& kinematic) {
  requireOneOf("rate_samples", p.rate_samples, {"instantaneous", "interval_average"});
  requireOneOf("average_stamp", p.average_stamp, {"end", "mid", "start"});
  if (p.average_stamp != "end" && p.rate_samples != "interval_average") {
    fail("average_stamp", "'" + p.average_stamp + "' with rate_samples '" + p.rate_samples +
                              "'; accepted: end, or mid and start with interval_average");
  }
  requireOneOf("stamp_filter", p.stamp_filter, {"none", "sensor_clock"});
  requireVector("gyro_bias", p.gyro_bias, 3, "[x, y, z], finite (rad/s, body frame)");
  kinematic.rate_samples = rateSamplesFromName(p.rate_samples);
  kinematic.average_stamp = averageStampFromName(p.average_stamp);
  kinematic.stamp_filter = stampFilterFromName(p.stamp_filter);
  kinematic.max_gap_fill = p.max_gap_fill;
}

// Gravity and the field are measurements of the kinematic model only (the dynamic model's
// attitude follows its torques); the accelerometer comes in the IMU's messages.
void checkAiding(const Parameters& p, Model model) {
  for (const auto& [name, on] : {std::pair<const char*, bool>{"use_accel", p.use_accel},
                                 std::pair<const char*, bool>{"use_mag", p.use_mag}}) {
    if (on && model != Model::Kinematic) {
      fail(name, "true needs the kinematic model; accepted with model dynamic: false");
    }
  }
  if (p.use_accel && p.rate_input != "imu") {
    fail("use_accel",
         "true needs rate_input imu (the accelerometer comes in the IMU's "
         "messages); accepted with rate_input " +
             logText(p.rate_input) + ": false");
  }
}

}  // namespace

const char* integratorParameterDoc() {
  static const std::string doc = "kinematic: " + quotedNames(integratorsFor(Model::Kinematic)) +
                                 "; dynamic: " + quotedNames(integratorsFor(Model::Dynamic)) +
                                 "; `auto`: " + autoKinematicDoc() + ", " +
                                 quotedNames({autoIntegrator(Model::Dynamic, false)}) +
                                 " torque-free, else " +
                                 quotedNames({autoIntegrator(Model::Dynamic, true)});
  return doc.c_str();
}

std::vector<std::string> parameterNames() {
  std::vector<std::string> names;
  const Parameters defaults;
  forEachParameter(defaults, [&names](const char* name, const auto&, const char*, const char*) {
    names.emplace_back(name);
  });
  return names;
}

std::string formatParameter(const std::string& value) { return value; }

std::string formatParameter(bool value) { return value ? "true" : "false"; }

std::string formatParameter(int value) { return std::to_string(value); }

std::string formatParameter(double value) {
  // Shortest text that reads back to the same double, with a dot so YAML reads a double.
  char text[32];
  if (std::isfinite(value) && value == std::round(value) && std::abs(value) < 1e15) {
    std::snprintf(text, sizeof(text), "%.1f", value);  // whole numbers: "100.0", not "1e+02"
    return text;
  }
  for (int precision = 1; precision <= 17; ++precision) {
    std::snprintf(text, sizeof(text), "%.*g", precision, value);
    if (std::strtod(text, nullptr) == value) break;
  }
  std::string s(text);
  // PyYAML (rosparam) reads "1e-09" as a string: the mantissa needs a dot ("1.0e-09").
  if (std::isfinite(value) && s.find('.') == std::string::npos) {
    const auto e = s.find('e');
    s.insert(e == std::string::npos ? s.size() : e, ".0");
  }
  return s;
}

std::string formatParameter(const std::vector<double>& value) {
  std::string s = "[";
  for (std::size_t i = 0; i < value.size(); ++i) {
    s += (i ? ", " : "") + formatParameter(value[i]);
  }
  return s + "]";
}

std::string parameterTableMarkdown() {
  std::string table =
      "| parameter | default | unit | meaning |\n"
      "|---|---|---|---|\n";
  const Parameters defaults;
  forEachParameter(
      defaults, [&table](const char* name, const auto& value, const char* unit, const char* doc) {
        table += std::string("| `") + name + "` | `" + formatParameter(value) + "` | " + unit +
                 " | " + doc + " |\n";
      });
  return table;
}

NodeConfig validateParameters(const Parameters& p) {
  NodeConfig config;
  config.parameters = p;
  checkScalars(p);
  applyStreamParameters(p, config.kinematic);
  config.model = resolveModel(p);
  const Integrator integrator = resolveIntegrator(p, config.model);
  config.rate_input = p.rate_input == "imu"     ? RateInput::Imu
                      : p.rate_input == "twist" ? RateInput::Twist
                                                : RateInput::None;
  config.torque_input = p.torque_input;
  config.torque_frame = p.torque_frame == "fixed" ? TorqueFrame::Fixed : TorqueFrame::Body;
  config.world = worldConventionFromName(p.world_frame);
  // The propagators work in REP-103's axes; the initial state is given in world_frame's.
  const Eigen::Quaterniond q0_WB =
      attitudeFromConvention(config.world, initialOrientation(p.initial_orientation));

  TimePolicy policy;
  policy.max_dt = p.max_dt;
  policy.backward_jump = p.time_jump_threshold;

  if (p.estimate_gyro_bias && config.model != Model::Kinematic) {
    fail("estimate_gyro_bias",
         "true needs the kinematic model; accepted with model dynamic: false");
  }
  checkAiding(p, config.model);

  if (config.model == Model::Kinematic) {
    if (p.torque_input) {
      fail("torque_input",
           "true needs the dynamic model, which needs `inertia`; accepted "
           "without inertia: false");
    }
    if (config.rate_input == RateInput::None) {
      fail("rate_input",
           "'none' leaves the kinematic model nothing to integrate; accepted "
           "with model kinematic: imu twist");
    }
    config.kinematic.integrator = integrator;
    config.kinematic.time_policy = policy;
    config.kinematic.initial_q_WB = q0_WB;
    return config;
  }

  if (p.inertia.empty()) {
    fail("inertia",
         "required by model dynamic; accepted: 3 principal moments [I1, I2, I3] or "
         "6 values [Ixx, Iyy, Izz, Ixy, Ixz, Iyz] (kg m^2)");
  }
  if (1.0 / p.publish_rate > p.max_dt) {
    // Each timer tick would be a gap longer than max_dt: the state would be held forever.
    fail("publish_rate", "invalid value " + formatParameter(p.publish_rate) + " with max_dt " +
                             formatParameter(p.max_dt) +
                             "; accepted: at least 1/max_dt (Hz) in the dynamic model");
  }
  DynamicConfig dynamic;
  dynamic.body = makeBody(p.inertia);
  dynamic.integrator = integrator;
  dynamic.torque_input = p.torque_input;
  dynamic.max_step = p.max_step > 0.0 ? p.max_step : 1.0 / p.publish_rate;
  if (p.max_dt / dynamic.max_step > kMaxGridStepsPerCall * (1.0 + 1e-12)) {
    // One call may have to cross max_dt in steps of max_step (the slack: 60 / 6e-4 rounds
    // above 1e5).
    fail("max_step", "invalid value " + formatParameter(dynamic.max_step) + " with max_dt " +
                         formatParameter(p.max_dt) + "; accepted: at least max_dt / 1e5 (s)");
  }
  dynamic.tolerance = p.tolerance;
  dynamic.torque_timeout = p.torque_timeout;
  dynamic.time_policy = policy;
  dynamic.initial.q_WB = q0_WB;
  const auto& w = p.initial_angular_velocity;
  dynamic.initial.w_B = bodyVectorFromConvention(config.world, Eigen::Vector3d(w[0], w[1], w[2]));
  try {
    // What the propagator refuses at construction (an initial state its exact motion cannot
    // be evaluated from) is refused here, before the node starts.
    DynamicPropagator probe(dynamic);
  } catch (const std::invalid_argument& e) {
    fail("initial_angular_velocity", std::string(e.what()) +
                                         "; accepted: [x, y, z], finite, "
                                         "|w| <= 1e5 (rad/s)");
  }
  config.dynamic = dynamic;
  return config;
}

EngineConfig engineConfig(const NodeConfig& node) {
  EngineConfig config;
  config.model = node.model;
  config.kinematic = node.kinematic;
  config.dynamic = node.dynamic;
  config.publish_rate = node.parameters.publish_rate;
  config.max_future = node.parameters.max_future;
  config.rate_delay = node.parameters.rate_delay;
  config.rate_stddev = node.parameters.angular_velocity_stddev;
  config.initial_orientation_stddev = node.parameters.initial_orientation_stddev;
  const Parameters& p = node.parameters;
  // The engine subtracts the bias (the parameter, then the bias topic) for both models.
  config.gyro_bias_B = Eigen::Vector3d(p.gyro_bias[0], p.gyro_bias[1], p.gyro_bias[2]);
  config.fixes.mode = p.fix_mode == "reset" ? FixMode::Reset : FixMode::Fuse;
  config.fixes.history = p.fix_history;
  config.fixes.gate = p.fix_gate;
  config.fixes.stddev = p.fix_stddev;
  config.fixes.estimate_gyro_bias = p.estimate_gyro_bias;
  config.fixes.gyro_bias_random_walk = p.gyro_bias_random_walk;
  config.fixes.gyro_bias_stddev = p.gyro_bias_stddev;
  config.aiding.use_accel = p.use_accel;
  config.aiding.accel_stddev = p.accel_stddev;
  config.aiding.use_accel_covariance = p.use_accel_covariance;
  config.aiding.use_mag = p.use_mag;
  config.aiding.mag_stddev = p.mag_stddev;
  config.aiding.use_mag_covariance = p.use_mag_covariance;
  config.aiding.declination = p.declination;
  config.aiding.mag_bias = Eigen::Vector3d(p.mag_bias[0], p.mag_bias[1], p.mag_bias[2]);
  // Without an initial attitude the tilt is the first gravity sample's (the heading unknown).
  config.aiding.align = p.use_accel && p.initial_orientation.empty();
  return config;
}

}  // namespace attitude_propagator
