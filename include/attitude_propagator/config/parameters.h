// The node's parameters (docs/design.md §7.7): one struct holding every private parameter with
// its default, one list describing them (forEachParameter), and one validator turning them into
// the engine's configuration. They live in the config library (attitude_propagator_config), not
// in the numerics core: frames, tf and topic choices are the node's, and the node and the bag
// tools share them. No ROS here: the ROS loader (src/ros/parameter_loader.cpp) only reads values
// into this struct, and the table in docs/parameters.md and config/default.yaml are checked
// against it (test/core/test_parameters.cpp).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "attitude_propagator/engine.h"
#include "attitude_propagator/limits.h"
#include "attitude_propagator/models/dynamic_propagator.h"
#include "attitude_propagator/models/kinematic_propagator.h"
#include "attitude_propagator/numerics/integrator.h"
#include "attitude_propagator/numerics/world_convention.h"

namespace attitude_propagator {

/// Smallest `max_dt` (s) the validator accepts, and the minimum of its slider in
/// cfg/AttitudePropagator.cfg (test/ros/test_bad_params.py checks that the two agree). A
/// microsecond is below the period of any rate stream; a smaller max_dt would only make every
/// sample a gap.
constexpr double kMinMaxDt = 1e-6;

/// Smallest `time_jump_threshold` (s): a millisecond is above the arrival jitter of any
/// stream, so a step back below it is a straggler, never a new timeline. The largest is
/// kMaxFuture: a forward glitch is told from a jump by the same threshold (source_timeline.h).
constexpr double kMinTimeJumpThreshold = 1e-3;

/// Largest `input_queue_size` and `output_queue_size` (messages): a million IMU messages hold
/// about 0.4 GB per queue, the most a node should ever be allowed to keep.
constexpr int kMaxQueueSize = 1000000;

/// Every private parameter of the node with its default: the one place defaults live.
struct Parameters {
  std::string model = "auto";
  std::string integrator = "auto";
  std::string rate_input = "imu";
  bool torque_input = false;
  std::string torque_frame = "body";
  double torque_timeout = 0.0;
  std::vector<double> inertia;              // empty: no inertia given
  std::vector<double> initial_orientation;  // empty: none given (identity, or use_accel aligns)
  std::vector<double> initial_angular_velocity{0.0, 0.0, 0.0};
  std::string fixed_frame = "world";
  std::string body_frame = "base_link";
  std::string world_frame = "enu";
  bool publish_tf = true;
  bool reverse_tf = false;
  double publish_rate = 100.0;
  double max_step = 0.0;  // 0: 1 / publish_rate
  double max_dt = 1.0;
  double max_future = 1.0;
  double time_jump_threshold = 1.0;
  double rate_delay = 0.0;
  double tolerance = 1e-9;
  double angular_velocity_stddev = 0.01;
  double initial_orientation_stddev = 3.141592653589793;  // pi: unknown until pinned
  std::string tf_conflict = "warn";
  int input_queue_size = 10000;
  int output_queue_size = 5000;
  std::string rate_samples = "instantaneous";
  std::string average_stamp = "end";
  std::string stamp_filter = "none";
  int max_gap_fill = 4;
  std::vector<double> gyro_bias{0.0, 0.0, 0.0};
  std::string fix_mode = "fuse";
  double fix_history = 1.0;
  double fix_gate = 16.266;  // the 99.9 % point of chi-square(3)
  double fix_stddev = 0.01;
  std::string fix_frame;  // empty: body_frame
  bool estimate_gyro_bias = false;
  double gyro_bias_random_walk = 1e-5;
  double gyro_bias_stddev = 0.01;  // 0.57 deg/s: a MEMS gyro (docs/parameters.md)
  bool use_accel = false;
  double accel_stddev = 0.1;
  bool use_accel_covariance = true;
  bool use_mag = false;
  double mag_stddev = 1e-6;
  bool use_mag_covariance = true;
  double declination = 0.0;
  std::vector<double> mag_bias{0.0, 0.0, 0.0};
};

/// The `integrator` parameter's description, from the integrator table: the methods of each
/// model and what `auto` picks.
const char* integratorParameterDoc();

/// Calls f(name, field, unit, description) for every parameter, in the order of the table in
/// docs/parameters.md. Works on a const or a mutable Parameters: the loader reads into the
/// fields, the table and the YAML check format them. Adding a parameter = one member above,
/// one line here.
template <class P, class F>
void forEachParameter(P& p, F&& f) {
  f("model", p.model, "", "`auto` (dynamic when `inertia` is set), `kinematic` or `dynamic`");
  f("integrator", p.integrator, "", integratorParameterDoc());
  f("rate_input", p.rate_input, "",
    "`imu` (`imu/data_raw`), `twist` (`body_twist`) or `none` (dynamic only)");
  f("torque_input", p.torque_input, "", "subscribe to `torque` (dynamic model only)");
  f("torque_frame", p.torque_frame, "", "`body` or `fixed`: the frame of unstamped torque");
  f("torque_timeout", p.torque_timeout, "s",
    "a torque older than this counts as zero; 0: held until the next one; at most 3600");
  f("inertia", p.inertia, "kg m²",
    "3 principal moments, or 6 values Ixx Iyy Izz Ixy Ixz Iyz; moments in [1e-15, 1e15]; "
    "empty: none");
  f("initial_orientation", p.initial_orientation, "",
    "q_WB at the first stamp and after a reset, [x, y, z, w] in `world_frame`'s axes "
    "(normalised; any finite scale); empty: none given, the identity, or with `use_accel` the "
    "tilt from the first accelerometer sample");
  f("initial_angular_velocity", p.initial_angular_velocity, "rad/s",
    "body rate at the first stamp (dynamic model), [x, y, z] in `world_frame`'s body axes; "
    "magnitude at most 1e5");
  f("fixed_frame", p.fixed_frame, "", "parent frame of the published transform");
  f("body_frame", p.body_frame, "", "child frame; IMU rates in another frame are rotated");
  f("world_frame", p.world_frame, "",
    "axes of the attitudes given and published: `enu` (REP-103, body FLU), `nwu` (body FLU) or "
    "`ned` (body FRD); other than enu, messages name `<fixed_frame>_nwu`/`_ned` and "
    "`<body_frame>_frd`, joined to the REP-103 frames on /tf_static");
  f("publish_tf", p.publish_tf, "", "publish the transform on /tf");
  f("reverse_tf", p.reverse_tf, "",
    "publish `body_frame → fixed_frame` instead (for a tree rooted at the body)");
  f("tf_conflict", p.tf_conflict, "",
    "another node publishes a parent of our child frame: `warn` (once, counted), `stop` "
    "(also stop publishing tf until it is over) or `ignore` (no watch: it sees every transform "
    "we publish, which costs throughput above about 20 kHz)");
  f("input_queue_size", p.input_queue_size, "messages",
    "subscriber queue of each streamed input (rates, torques, field, /clock): a burst this long "
    "is queued, beyond it roscpp drops the oldest (counted from sequence gaps only for fixes); "
    "in [1, 1000000]; start-up only");
  f("output_queue_size", p.output_queue_size, "messages",
    "publisher queue of /tf, `imu/data` and `attitude_state` per subscriber connection: a "
    "subscriber this far behind loses the oldest (what the node keeps per output and slow "
    "subscriber); in [1, 1000000]; start-up only");
  f("publish_rate", p.publish_rate, "Hz",
    "dynamic model: publish at multiples of 1/rate; at most 1000");
  f("max_step", p.max_step, "s",
    "dynamic model: largest integration step, in [1e-5, 60] and at least max_dt / 1e5; "
    "0: 1/publish_rate");
  f("max_dt", p.max_dt, "s",
    "largest gap between stamps integrated across (kinematic: a silence of more than 5.5 mean "
    "periods of the rate stream is held even under it), in [1e-6, 60]");
  f("max_future", p.max_future, "s",
    "an input, bias sample, fix or `~set_state` stamped further ahead of ROS time is refused "
    "(counted); more than 0, at most 3600");
  f("time_jump_threshold", p.time_jump_threshold, "s",
    "stamps (or, under sim time, the clock) that go back by more than this and stay back (a "
    "looped bag, a restarted driver) start time again from the initial state; a smaller step "
    "back is a straggler, dropped (imu_filter_madgwick's name; a jump always resets here, so 0 "
    "is refused); in [1e-3, 3600]");
  f("rate_delay", p.rate_delay, "s",
    "how much older the rate is than its stamp (an on-chip filter's group delay, a fixed "
    "latency): stamps are moved back by it first; in [0, max_dt]");
  f("tolerance", p.tolerance, "", "relative and absolute tolerance of `dopri5`, in [1e-12, 1e-2]");
  f("angular_velocity_stddev", p.angular_velocity_stddev, "rad/s",
    "rate noise used when an input carries no covariance (drives the growth of the orientation "
    "covariance); at most 1000");
  f("initial_orientation_stddev", p.initial_orientation_stddev, "rad",
    "orientation uncertainty at the first stamp and after a reset (π: unknown, the default); "
    "0 when `fixed_frame` is defined by the start; `~set_state` pins it to 0");
  f("rate_samples", p.rate_samples, "",
    "`instantaneous` (rate at the stamp) or `interval_average` (mean over the interval the "
    "sample closes: delta-angle / dt)");
  f("average_stamp", p.average_stamp, "",
    "`interval_average` only: where in its interval a mean is stamped, `end`, `mid` or `start` "
    "(mid and start: each state one sample later, when the next stamp shows where the "
    "interval ends)");
  f("stamp_filter", p.stamp_filter, "",
    "`none` or `sensor_clock`: replace receipt stamps by a fitted sensor clock");
  f("max_gap_fill", p.max_gap_fill, "samples",
    "`interval_average`: lost samples in a row filled in from the neighbouring means when the "
    "stamps prove the loss (regular intervals, a whole number of periods); 0: never; in [0, 4] "
    "(a silence of more than 5.5 periods is a dropout, held)");
  f("gyro_bias", p.gyro_bias, "rad/s", "subtracted from every rate, [x, y, z] in the body frame");
  f("fix_mode", p.fix_mode, "",
    "what an absolute attitude fix does at its stamp: `fuse` (EKF update behind `fix_gate`) or "
    "`reset` (the attitude replaced); the rates since are integrated again");
  f("fix_history", p.fix_history, "s",
    "how late a fix may arrive: rate inputs kept (from the first fix on), in (0, 10], at most "
    "4096 inputs");
  f("fix_gate", p.fix_gate, "",
    "`fuse`: largest squared Mahalanobis distance of a fix's innovation accepted (99.9 % of "
    "chi-square(3)); > 0");
  f("fix_stddev", p.fix_stddev, "rad",
    "rotation error of a fix that carries no covariance, per axis; in (0, π]");
  f("fix_frame", p.fix_frame, "",
    "the frame whose orientation a pose or quaternion fix gives (its mount to `body_frame` "
    "from tf); empty: `body_frame`");
  f("estimate_gyro_bias", p.estimate_gyro_bias, "",
    "kinematic model: estimate the gyro bias from the fixes (subtracted on top of `gyro_bias`)");
  f("gyro_bias_random_walk", p.gyro_bias_random_walk, "rad/s/√s",
    "`estimate_gyro_bias`: random walk of the bias (a MEMS gyro's; 1e-6 or less for a tactical "
    "one); in [0, 1000]");
  f("gyro_bias_stddev", p.gyro_bias_stddev, "rad/s",
    "`estimate_gyro_bias`: prior standard deviation of the bias per axis (0.57 °/s, a MEMS "
    "gyro's; 2.4e-5 for a tactical one; the random walk grows it further while nothing "
    "measures the bias); in [0, 10]");
  f("use_accel", p.use_accel, "",
    "kinematic model, `rate_input: imu`: the IMU's `linear_acceleration` measures the gravity "
    "direction (roll and pitch); start-up only");
  f("accel_stddev", p.accel_stddev, "m/s²",
    "`use_accel`: accelerometer noise per axis for messages whose covariance is all zero; in "
    "(0, 100]");
  f("use_accel_covariance", p.use_accel_covariance, "",
    "`use_accel`: a message's `linear_acceleration_covariance` is used when it gives one; false: "
    "ignored, `accel_stddev` always (a driver whose covariance is wrong)");
  f("use_mag", p.use_mag, "",
    "kinematic model: `imu/mag` (sensor_msgs/MagneticField) measures the heading; start-up only");
  f("mag_stddev", p.mag_stddev, "T",
    "`use_mag`: magnetometer noise per axis for messages whose covariance is all zero; in "
    "(0, 1e-2]");
  f("use_mag_covariance", p.use_mag_covariance, "",
    "`use_mag`: a message's `magnetic_field_covariance` is used when it gives one; false: "
    "ignored, `mag_stddev` always (a driver whose covariance is wrong, e.g. in another unit)");
  f("declination", p.declination, "rad",
    "`use_mag`: magnetic north east of true north positive; in [-π, π]");
  f("mag_bias", p.mag_bias, "T",
    "`use_mag`: the magnetometer's own field (hard iron, from a calibration), subtracted from "
    "every field sample, [x, y, z] in the body frame; size at most 0.01");
}

/// All parameter names, for rejecting unknown ones.
std::vector<std::string> parameterNames();

/// A parameter's value as YAML flow text (`auto`, `true`, `0.5`, `[0, 0, 0, 1]`), the format
/// of config/default.yaml and of the table in docs/parameters.md.
std::string formatParameter(const std::string& value);
std::string formatParameter(bool value);
std::string formatParameter(int value);
std::string formatParameter(double value);
std::string formatParameter(const std::vector<double>& value);

/// The parameter table of docs/parameters.md (Markdown), generated from the defaults above.
std::string parameterTableMarkdown();

enum class RateInput { Imu, Twist, None };

/// The validated configuration the wrapper runs with.
struct NodeConfig {
  Model model = Model::Kinematic;  ///< resolved: Kinematic or Dynamic, never Auto
  RateInput rate_input = RateInput::Imu;
  bool torque_input = false;
  TorqueFrame torque_frame = TorqueFrame::Body;
  WorldConvention world = WorldConvention::Enu;  ///< the axes of the attitudes given and published
  KinematicConfig kinematic;                     ///< when model == Kinematic
  std::optional<DynamicConfig> dynamic;          ///< when model == Dynamic
  Parameters parameters;                         ///< the values as given (frames, rates, flags)
};

/// Checks every parameter and resolves `model` (auto: dynamic when inertia is given).
/// Throws std::invalid_argument whose message starts with the parameter's name and lists the
/// accepted values, e.g. "model: unknown value 'x'; accepted: auto kinematic dynamic".
NodeConfig validateParameters(const Parameters& parameters);

/// The engine's part of a validated node configuration (the node and the bag tools run the
/// same engine with the same parameters).
EngineConfig engineConfig(const NodeConfig& node);

}  // namespace attitude_propagator
