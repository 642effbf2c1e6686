// propagate_bag: the node's propagation over a recorded bag, as fast as the machine allows.
// Reads the rate topic (sensor_msgs/Imu, geometry_msgs/Twist or TwistStamped), in the dynamic
// model the torque topic, and with --fixes the absolute attitude fixes (orientation_fix's types),
// with the node's parameters and YAML, through the same core engine; writes attitude_state,
// imu/data and /tf into an output bag at the input messages' record times (or the states into a
// CSV). Several bags (the parts of a split recording) are read as one stream merged by record time,
// so the state carries on across the parts. The bags are read chunk by chunk (rosbag::View), never
// whole.
//
// Time, as the node under sim time: a /clock topic in the bag drives the engine's clock. Without
// one, the input stamps do (each input is submitted, then the clock ticks to its stamp, so a
// grid stamp's state includes the inputs stamped up to it).
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <iostream>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <geometry_msgs/QuaternionStamped.h>
#include <geometry_msgs/Twist.h>
#include <geometry_msgs/TwistStamped.h>
#include <geometry_msgs/Vector3Stamped.h>
#include <geometry_msgs/Wrench.h>
#include <geometry_msgs/WrenchStamped.h>
#include <ros/names.h>
#include <rosgraph_msgs/Clock.h>
#include <sensor_msgs/Imu.h>
#include <sensor_msgs/MagneticField.h>
#include <tf2/buffer_core.h>
#include <tf2_msgs/TFMessage.h>
#include <boost/make_shared.hpp>

#include "aiding_summary.h"
#include "attitude_propagator/AttitudeState.h"
#include "attitude_propagator/engine.h"
#include "attitude_propagator/messages/conversions.h"
#include "attitude_propagator/messages/fix_decoder.h"
#include "attitude_propagator/messages/frame_source.h"
#include "attitude_propagator/messages/imu_input.h"
#include "attitude_propagator/messages/input_decoders.h"
#include "attitude_propagator/messages/input_roles.h"
#include "attitude_propagator/messages/outputs.h"
#include "attitude_propagator/messages/refusal_table.h"
#include "attitude_propagator/models/kinematic_propagator.h"
#include "attitude_propagator/quoted_text.h"
#include "bag_input.h"
#include "bag_writer.h"
#include "command_line.h"
#include "config_file.h"
#include "interrupts.h"
#include "output_files.h"
#include "progress.h"
#include "tool_error.h"

namespace attitude_propagator {
namespace tools {
namespace {

struct Options {
  std::vector<std::string> inputs;
  std::string output;
  bool csv = false;
  BagOutput::Compression compression = BagOutput::Compression::None;
  std::string rates_topic;
  std::string torque_topic = "/torque";
  std::string clock_topic = "/clock";
  std::string bias_topic = "/gyro_bias";
  std::string fixes_topic;  // empty: no fixes read
  std::string mag_topic;    // empty: /imu/mag with use_mag
  std::string static_tf_topic = "/tf_static";
  std::string tf_topic = "/tf";  // input transforms, heard in record order as the node hears them
  bool use_clock = true;
  bool io_floor = false;
  bool progress = true;
  bool dry_run = false;
  // Output topics, resolved (absolute).
  std::string state_out = "attitude_state";
  std::string imu_out = "imu/data";
  std::string tf_out = "/tf";
  std::string tf_static_out = "/tf_static";
  Parameters parameters;
};

/// A ROS graph name resolved as a node in namespace `ns` resolves it: absolute names stay,
/// relative ones are put under `ns`. A private name (~) has no node to belong to here.
std::string resolveTopic(const std::string& option, const std::string& ns,
                         const std::string& name) {
  std::string error;
  if (name.empty() || name[0] == '~' || !ros::names::validate(name, error)) {
    throw UsageError(option + " " + name + ": not a topic name" +
                     (error.empty() ? std::string(" (no private ~names)") : " (" + error + ")"));
  }
  if (name[0] == '/') return name;
  return (ns.back() == '/' ? ns : ns + "/") + name;
}

BagOutput::Compression parseCompression(const std::string& name) {
  if (name == "none") return BagOutput::Compression::None;
  if (name == "lz4") return BagOutput::Compression::Lz4;
  throw UsageError("--compression " + name + ": none or lz4");
}

/// The command line as given, before it is checked and combined (parseOptions).
struct Given {
  Options o;
  std::vector<std::string> configs, sets;
  std::string ns = "/";
};

CommandLine commandLine(Given& g) {
  Options& o = g.o;
  auto to = [](std::string& field) { return [&field](const std::string& v) { field = v; }; };
  return {
      std::string("propagate_bag (attitude_propagator) ") + AP_VERSION,
      22,
      {helpParagraph(R"(usage: propagate_bag IN.bag [IN2.bag ...] [options]

Propagates the attitude over recorded bags with the node's engine and parameters, as fast as
the machine allows, and writes attitude_state, imu/data and /tf into a bag (or a CSV).
Several bags (the parts of `rosbag record --split`, e.g. rec_*.bag) are read as one stream
merged by record time, in whatever order they are given: the state carries on from one part to
the next, as over the unsplit recording.

)"),
       valueOption("-o, --output", "OUT.bag",
                   "output bag (default: IN.propagated.bag, after the first input)", to(o.output)),
       valueOption("--csv", "OUT.csv", "write the states as CSV instead of a bag",
                   [&o](const std::string& v) {
                     o.output = v;
                     o.csv = true;
                   }),
       valueOption("--compression", "none|lz4",
                   "output bag chunks stored as they are (default) or LZ4-compressed:\n"
                   "about 5x smaller for about 20 % more CPU; faster in wall time only\n"
                   "where the disk, not the CPU, limits the run (docs/bag_tools.md)",
                   [&o](const std::string& v) { o.compression = parseCompression(v); }),
       valueOption("--config", "FILE.yaml", "node parameters (the keys of config/default.yaml)",
                   [&g](const std::string& v) { g.configs.push_back(v); }),
       valueOption("--set", "name=value",
                   "one node parameter (YAML value), after --config; repeatable",
                   [&g](const std::string& v) { g.sets.push_back(v); }),
       valueOption("--rates", "TOPIC",
                   "rate topic (default /imu/data_raw, or /body_twist for rate_input twist)",
                   to(o.rates_topic)),
       valueOption("--torque", "TOPIC",
                   "torque topic, dynamic model with torque_input (default /torque)",
                   to(o.torque_topic)),
       valueOption("--clock", "TOPIC",
                   "clock topic driving the engine when present (default /clock)",
                   to(o.clock_topic)),
       flagOption("--no-clock", "ignore the clock topic: input stamps drive the engine",
                  [&o] { o.use_clock = false; }),
       valueOption("--fixes", "TOPIC",
                   "absolute attitude fixes, as the node's orientation_fix takes them\n"
                   "(PoseWithCovarianceStamped, PoseStamped, QuaternionStamped, or Imu with\n"
                   "an orientation), each submitted at its record time as the node does at\n"
                   "receipt (fix_mode, fix_frame, estimate_gyro_bias, ...); default: none",
                   to(o.fixes_topic)),
       valueOption("--mag", "TOPIC",
                   "magnetometer (sensor_msgs/MagneticField), as the node's imu/mag: read\n"
                   "with use_mag (default /imu/mag); the accelerometer comes in the rate\n"
                   "topic's Imu messages with use_accel",
                   to(o.mag_topic)),
       helpParagraph(R"(
Output topics, named as the node's would be (relative names resolved in --ns, as ROS does):
)"),
       valueOption("--ns", "NS",
                   "namespace of the relative output topics (default /): with --ns r1,\n"
                   "/r1/attitude_state and /r1/imu/data; /tf and /tf_static stay, as\n"
                   "tf2 listeners only hear those (give robots their own frame names)",
                   to(g.ns)),
       valueOption("--state-topic", "NAME", "default attitude_state", to(o.state_out)),
       valueOption("--imu-topic", "NAME", "default imu/data", to(o.imu_out)),
       valueOption("--tf-topic", "NAME", "default /tf", to(o.tf_out)),
       valueOption("--tf-static-topic", "NAME",
                   "default /tf_static: the mounts used (body frame to the IMU's, twist's\n"
                   "or torque's frame, the transforms read from the input's /tf_static),\n"
                   "latched as rosbag records a latched topic",
                   to(o.tf_static_out)),
       helpParagraph(R"(
Frames follow the node's rules: the input's /tf_static holds at every time, its /tf is heard
as it was recorded; a mount (rates) is looked up once, a torque's frame at each message.

)"),
       flagOption("--dry-run",
                  "open and check the bags, print their topics, types and message\n"
                  "counts, the settings that would run and the output's topics and\n"
                  "estimated size; write nothing",
                  [&o] { o.dry_run = true; }),
       flagOption("--io-floor",
                  "read, decode and write the same outputs without propagating (one\n"
                  "identity state per input): the I/O cost alone, for benchmarks",
                  [&o] { o.io_floor = true; }),
       flagOption("--no-progress", "no progress line (it is shown only on a terminal anyway)",
                  [&o] { o.progress = false; }),
       versionOption("the package version"),
       helpOption("this text"),
       helpParagraph(R"(
The output never replaces an input (a bag or a --config file, under any name: refused), is
written under a temporary name in its directory and appears under its own name only when
complete; the run is refused at the start when the file system has less free space than the
output's estimated size. Every input bag is checked before any is read.

The summary accounts for every rate and torque message: accepted, dropped for a named reason
(stale, future, no-tf, ...) or still pending at the end (dynamic model: stamped after the
last clock tick); with --fixes, for every fix: accepted, rejected for a named reason (gate,
too old, ...), waiting at the end, or refused before the engine (frames, type, ...); with
use_accel and use_mag, the accel_* and mag_* counters under the names of the node's diagnostics.

Exit codes:
  0    the output is complete and holds the states of the accepted inputs
  1    an input could not be read (missing, truncated, damaged) or the output not written
       (full disk, no permission); nothing is left under the output name
  2    usage: bad options or parameters, an output that is an input, an input given twice
  3    the bags were read to the end but no input was accepted (or no state published); the
       summary counts why (e.g. "no-tf 4001"), and no output is written
  128+N  stopped by signal N (130: Ctrl-C, 143: SIGTERM, 129: SIGHUP); no output is written
)")}};
}

Options parseOptions(int argc, char** argv) {
  Given g;
  Options& o = g.o;
  o.inputs = parseCommandLine(commandLine(g), argc, argv);
  std::vector<std::string>& configs = g.configs;
  std::vector<std::string>& sets = g.sets;
  std::string& ns = g.ns;
  if (o.inputs.empty()) throw UsageError("no input bag (see --help)");
  if (ns.find('~') != std::string::npos) {
    throw UsageError("--ns " + ns + ": not a namespace (no private ~names)");
  }
  std::string error;
  if (!ros::names::validate(ns[0] == '/' ? ns : "/" + ns, error)) {
    throw UsageError("--ns " + ns + ": not a namespace (" + error + ")");
  }
  if (ns[0] != '/') ns = "/" + ns;
  o.state_out = resolveTopic("--state-topic", ns, o.state_out);
  o.imu_out = resolveTopic("--imu-topic", ns, o.imu_out);
  o.tf_out = resolveTopic("--tf-topic", ns, o.tf_out);
  o.tf_static_out = resolveTopic("--tf-static-topic", ns, o.tf_static_out);
  // One topic, one type: a bag connection carries one.
  const std::vector<std::string> outs = {o.state_out, o.imu_out, o.tf_out, o.tf_static_out};
  for (std::size_t i = 0; i < outs.size(); ++i) {
    for (std::size_t j = 0; j < i; ++j) {
      if (outs[i] == outs[j]) {
        throw UsageError(outs[i] + ": two outputs on one topic; give each its own");
      }
    }
  }
  for (const auto& c : configs) loadConfigFile(c, o.parameters);
  for (const auto& s : sets) applySetting(s, o.parameters);
  // tf1's leading '/' in a frame parameter is read without it (frame_ids.h), with a warning.
  for (const auto& w : tf2FrameParameters(o.parameters)) {
    // The frame as given is the user's text: capped by the one text rule, as the node's line.
    std::fprintf(stderr, "warning: %s\n", logText(w, 4 * kLogTextBytes).c_str());
  }
  validateParameters(o.parameters);  // std::invalid_argument: a usage error, before any reading
  if (o.output.empty()) {
    const std::string& first = o.inputs.front();
    const bool bag = first.size() > 4 && first.compare(first.size() - 4, 4, ".bag") == 0;
    o.output = (bag ? first.substr(0, first.size() - 4) : first) + ".propagated.bag";
  }
  std::vector<std::string> inputs = configs;
  inputs.insert(inputs.end(), o.inputs.begin(), o.inputs.end());
  refuseOutputOverInput(o.output, inputs);
  if (o.rates_topic.empty()) {
    o.rates_topic = o.parameters.rate_input == "twist" ? "/body_twist" : "/imu/data_raw";
  }
  for (const std::string* input : {&o.rates_topic, &o.torque_topic, &o.clock_topic}) {
    if (!o.fixes_topic.empty() && sameTopic(o.fixes_topic, *input)) {
      throw UsageError("--fixes " + o.fixes_topic + ": the topic of another input");
    }
  }
  if (o.mag_topic.empty()) o.mag_topic = "/imu/mag";
  for (const std::string* input :
       {&o.rates_topic, &o.torque_topic, &o.clock_topic, &o.fixes_topic}) {
    if (o.parameters.use_mag && sameTopic(o.mag_topic, *input)) {
      throw UsageError("--mag " + o.mag_topic + ": the topic of another input");
    }
  }
  return std::move(o);
}

// ---------------------------------------------------------------------------------------------
// Outputs
// ---------------------------------------------------------------------------------------------

/// Where states (and the republished IMU messages) go.
class Writer {
 public:
  virtual ~Writer() = default;
  virtual void state(const EngineState& s, const ros::Time& record) = 0;
  virtual void imu(const sensor_msgs::Imu& input, const EngineState& s,
                   const Eigen::Quaterniond& q_BI, const ros::Time& record) = 0;
  /// The static transforms used so far (all of them: a latched topic keeps its last message).
  virtual void mounts(const tf2_msgs::TFMessage& transforms, const ros::Time& record) = 0;
  virtual void close() = 0;
};

/// The node's output encoding for this run's configuration and integrator.
OutputEncoder outputEncoder(const NodeConfig& config, const AttitudeEngine& engine) {
  return OutputEncoder(config, engine);
}

/// Bytes the output takes per state and per republished IMU message (an estimate for the
/// free-space check: the messages as they will be written, with their frame names).
struct RecordSizes {
  double per_state = 0.0;
  double per_imu = 0.0;
};

// A record is its header (op, conn and time fields: 38 bytes), two lengths and the message,
// plus a 12-byte index entry. LZ4 stores these streams about 5x smaller (docs/bag_tools.md); a
// quarter is assumed.
template <class M>
double recordBytes(const M& msg) {
  return 4 + 38 + 4 + ros::serialization::serializationLength(msg) + 12;
}

RecordSizes bagRecordSizes(const Options& o, const NodeConfig& config,
                           const AttitudeEngine& engine) {
  const OutputEncoder encoder = outputEncoder(config, engine);
  AttitudeState state;
  encoder.state(EngineState{}, state);
  tf2_msgs::TFMessage tf;
  tf.transforms.resize(1);
  encoder.transform(EngineState{}, tf.transforms[0]);
  sensor_msgs::Imu imu;
  imu.header.frame_id = "imu_link";
  const double shrink = o.compression == BagOutput::Compression::Lz4 ? 0.25 : 1.0;
  return {shrink * (recordBytes(state) + (config.parameters.publish_tf ? recordBytes(tf) : 0.0)),
          shrink * recordBytes(imu)};
}

/// attitude_state, imu/data and /tf as the node publishes them, into a bag.
class BagWriter : public Writer {
 public:
  BagWriter(const std::string& path, const Options& o, const NodeConfig& config,
            const AttitudeEngine& engine)
      : bag_(path, o.output, o.compression),
        encoder_(outputEncoder(config, engine)),
        publish_tf_(config.parameters.publish_tf),
        state_topic_(o.state_out),
        imu_topic_(o.imu_out),
        tf_topic_(o.tf_out),
        tf_static_topic_(o.tf_static_out) {
    bag_.latch(tf_static_topic_);
    tf_.transforms.resize(1);
  }

  void state(const EngineState& s, const ros::Time& record) override {
    if (!static_written_ && !encoder_.conventionFrames(record).empty()) {
      mounts(tf2_msgs::TFMessage(), record);
    }
    if (publish_tf_) {
      encoder_.transform(s, tf_.transforms[0]);
      bag_.write(tf_topic_, record, tf_);
    }
    encoder_.state(s, state_);
    bag_.write(state_topic_, record, state_);
  }

  void imu(const sensor_msgs::Imu& input, const EngineState& s, const Eigen::Quaterniond& q_BI,
           const ros::Time& record) override {
    encoder_.imu(input, s, q_BI, imu_);
    bag_.write(imu_topic_, record, imu_);
  }

  /// The mounts, with world_frame's named axes: a latched topic keeps only its last message.
  void mounts(const tf2_msgs::TFMessage& transforms, const ros::Time& record) override {
    tf2_msgs::TFMessage all = transforms;
    for (const auto& t : encoder_.conventionFrames(record)) all.transforms.push_back(t);
    bag_.write(tf_static_topic_, record, all);
    static_written_ = true;
  }

  void close() override { bag_.close(); }

 private:
  BagOutput bag_;
  OutputEncoder encoder_;
  bool publish_tf_;
  bool static_written_ = false;
  std::string state_topic_, imu_topic_, tf_topic_, tf_static_topic_;
  AttitudeState state_;
  tf2_msgs::TFMessage tf_;
  sensor_msgs::Imu imu_;
};

/// One line per state.
class CsvWriter : public Writer {
 public:
  CsvWriter(const std::string& path, const std::string& name, OutputEncoder encoder)
      : file_(path, name), encoder_(std::move(encoder)) {
    std::fputs(
        "stamp,qx,qy,qz,qw,wx,wy,wz,P_xx,P_xy,P_xz,P_yx,P_yy,P_yz,P_zx,P_zy,P_zz,norm_error,"
        "steps,Mx,My,Mz,kinetic_energy\n",
        file_.get());
  }

  void state(const EngineState& s, const ros::Time&) override {
    const int n = format(encoder_.inWorldAxes(s), row_, sizeof row_);
    std::fwrite(row_, 1, static_cast<std::size_t>(std::min<int>(n, sizeof row_ - 1)), file_.get());
    file_.check();
  }
  void imu(const sensor_msgs::Imu&, const EngineState&, const Eigen::Quaterniond&,
           const ros::Time&) override {}
  void mounts(const tf2_msgs::TFMessage&, const ros::Time&) override {}
  void close() override { file_.close(); }

  /// A row of numbers as long as they print (negative, 17 digits, 3-digit exponents).
  static double rowBytes() {
    EngineState s;
    const double x = -0.12345678901234567e-100;
    s.stamp = std::numeric_limits<Stamp>::max();
    s.q_WB.coeffs().setConstant(x);
    s.w_B.setConstant(x);
    s.P_B.setConstant(x);
    s.M_B.setConstant(x);
    s.norm_error = s.kinetic_energy = x;
    s.steps = std::numeric_limits<decltype(s.steps)>::max();
    char row[kRowSize];
    return format(s, row, sizeof row);
  }

 private:
  static int format(const EngineState& s, char* row, std::size_t size) {
    const auto& q = s.q_WB;
    const auto& P = s.P_B;
    return std::snprintf(row, size,
                         "%s,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.9g,%.9g,%.9g,%.9g,%.9g,"
                         "%.9g,%.9g,%.9g,%.9g,%.3g,%llu,%.17g,%.17g,%.17g,%.17g\n",
                         formatStamp(s.stamp).c_str(), q.x(), q.y(), q.z(), q.w(), s.w_B.x(),
                         s.w_B.y(), s.w_B.z(), P(0, 0), P(0, 1), P(0, 2), P(1, 0), P(1, 1), P(1, 2),
                         P(2, 0), P(2, 1), P(2, 2), s.norm_error,
                         static_cast<unsigned long long>(s.steps), s.M_B.x(), s.M_B.y(), s.M_B.z(),
                         s.kinetic_energy);
  }

  CsvFile file_;
  OutputEncoder encoder_;
  static constexpr std::size_t kRowSize = 1024;
  char row_[kRowSize];
};

// ---------------------------------------------------------------------------------------------
// The run
// ---------------------------------------------------------------------------------------------

class BagPropagator : public EngineSink {
 public:
  BagPropagator(const Options& o, BagSet& bags)
      : o_(o), bags_(bags), config_(validateParameters(o.parameters)) {
    engine_ = std::make_unique<AttitudeEngine>(engineConfig(config_), *this);
  }

  /// Checks the topics and the free space, then runs; writes into `path` (a temporary name).
  void run(const std::string& path);
  /// Checks the topics and prints what run() would read, with which settings, and write; the
  /// exit code the run would give (kExitNothingUsable: the rates reach no body).
  int dryRun(std::FILE* out);
  /// Why the output holds nothing usable (nothing accepted, no state), or nothing.
  std::optional<std::string> nothingUsable() const;
  void summary(std::FILE* out, bool written) const;

  // EngineSink
  void publishState(const EngineState& state) override {
    ++states_;
    writer_->state(state, record_);
  }
  void inputApplied(const Input& input, const EngineState& state) override {
    if (!input.payload) return;
    const auto& imu = *static_cast<const ImuPayload*>(input.payload.get());
    writer_->imu(*imu.msg, state, imu.q_BS, record_);
  }
  void note(const EngineNote& note) override {
    // Counted by the engine, summarised at the end; the clock's second timeline is named there
    // by the publishers the bag recorded (the latest tick's, the one before from another).
    if (note.kind == EngineNote::ClockTwoTimelines && clock_sources_.empty()) {
      clock_sources_ = clockPublishersText(clock_publisher_, previous_clock_publisher_);
      clock_apart_ = static_cast<double>(*engine_->clockNow() - note.stamp) * 1e-9;
    }
  }

 private:
  std::vector<std::string> checkTopics();
  /// The output's estimated size in bytes (for the free-space check).
  double estimatedBytes();
  void dispatch(const rosbag::MessageInstance& m);
  void onImu(const rosbag::MessageInstance& m);
  void onBias(const rosbag::MessageInstance& m);
  /// use_mag: a field, decoded by the node's rules and submitted as the node does at receipt.
  void onMag(const rosbag::MessageInstance& m);
  /// A fix: decoded by the node's rules (FixDecoder, the bag's frames), submitted at once as the
  /// node submits it at receipt; the corrected state goes out with the next output.
  void onFix(const rosbag::MessageInstance& m);
  /// The account of the fixes read (the engine's fixes_* counters and the decoder's refusals).
  void fixSummary(std::FILE* out) const;
  void stampSummary(std::FILE* out, const KinematicPropagator& k) const;
  /// Prints the decoders' warnings of frame ids with a leading '/', once per frame.
  void warnFrames();
  /// Keeps the first frame whose rates had no transform to the body (the advice at the end).
  void noteNoMount(const DecodedInput& in);
  /// The first rate message's frame id as tf2 reads it (empty: none, or no stamped rates).
  std::string firstRateFrame();
  /// --dry-run: whether the rates' frame reaches body_frame in the bag; prints the finding.
  bool mountReachable(std::FILE* out);
  /// Counts a refused input once, or hands a decoded one to submit().
  void take(DecodedInput& in);
  void submit(Input& input);
  void tickTo(Stamp now);
  void readStaticTransforms();
  void recordMount(const std::string& target, const std::string& source);

  /// The bag's transforms for the decoders: its /tf_static (read first: static transforms hold
  /// at every time) and its /tf as recorded up to the message at hand. Each static transform a
  /// lookup goes through is written to the output's /tf_static; a lookup that fails is reported
  /// once per frame.
  class BagFrames : public FrameSource {
   public:
    explicit BagFrames(BagPropagator& run) : run_(run) {}
    std::optional<Eigen::Quaterniond> rotation(const std::string& target, const std::string& source,
                                               const ros::Time& stamp, std::string* error) override;

   private:
    BagPropagator& run_;
    std::map<std::string, bool> reported_;  // frames whose failed lookup was reported
  };

  const Options& o_;
  BagSet& bags_;
  NodeConfig config_;
  std::unique_ptr<AttitudeEngine> engine_;
  std::unique_ptr<Writer> writer_;
  std::string rates_, torque_, clock_, bias_, tf_, fixes_, mag_;  // as recorded; empty: not read
  bool clock_driven_ = false;
  ros::Time record_;  // record time of the message being handled
  std::optional<Stamp> last_tick_;
  InputDecoders decoders_{DecoderFrames::of(config_)};
  BagFrames frames_{*this};
  FixDecoder fix_decoder_{FixFrames::of(config_)};
  // Each Imu message is decoded into imu_msg_, which imu_ carries to the engine (imu_input.h).
  boost::shared_ptr<sensor_msgs::Imu> imu_msg_ = boost::make_shared<sensor_msgs::Imu>();
  ImuPayload imu_{imu_msg_};
  geometry_msgs::Vector3Stamped bias_msg_;
  sensor_msgs::MagneticField mag_msg_;
  std::uint64_t accel_read_ = 0;  // Imu messages whose acceleration was submitted
  tf2_msgs::TFMessage tf_msg_;
  std::uint64_t tf_read_ = 0;  // /tf messages heard (not inputs: not in the summary's count)
  rosgraph_msgs::Clock clock_msg_;
  std::string clock_publisher_, previous_clock_publisher_;  // of the latest ticks (callerid)
  std::string clock_sources_;  // the first two timelines recognised: their publishers
  double clock_apart_ = 0.0;   // and how far apart (s)
  std::vector<std::uint8_t> buffer_;
  std::unique_ptr<tf2::BufferCore> tf_buffer_;  // the bag's /tf_static, then its /tf
  std::map<std::string, geometry_msgs::TransformStamped> static_edges_;  // by child frame
  std::map<std::string, geometry_msgs::TransformStamped> mounts_used_;   // by child frame
  std::map<std::string, std::uint64_t> read_;                            // messages read per role
  std::string no_mount_frame_;  // the first rates' frame refused for want of a transform
  std::uint64_t messages_ = 0;
  std::uint64_t states_ = 0;
  std::uint64_t floor_accepted_ = 0;  // --io-floor: inputs passed straight to the outputs
  std::uint64_t messages_total_ = 0;  // in the view, before reading
  double wall_ = 0.0;
  double bag_seconds_ = 0.0;
};

std::vector<std::string> BagPropagator::checkTopics() {
  std::vector<std::string> topics;
  const bool dynamic = config_.model == Model::Dynamic;
  if (config_.rate_input != RateInput::None) {
    const Source source = config_.rate_input == RateInput::Imu ? Source::Imu : Source::Twist;
    requireTopic(bags_, o_.rates_topic, "rate", inputRoleOf(source).types);
  }
  if (config_.rate_input != RateInput::None) {
    rates_ = o_.rates_topic;
    topics.push_back(rates_);
  }
  if (dynamic && config_.torque_input) {
    requireTopic(bags_, o_.torque_topic, "torque", inputRoleOf(Source::Torque).types);
    torque_ = o_.torque_topic;
    topics.push_back(torque_);
  }
  if (topics.empty()) {
    throw ToolError("nothing to read: rate_input is none and torque_input is off");
  }
  if (o_.use_clock && topicType(bags_, o_.clock_topic)) {
    requireTopic(bags_, o_.clock_topic, "clock", {typeOf<rosgraph_msgs::Clock>()});
    clock_ = o_.clock_topic;
    topics.push_back(clock_);
    clock_driven_ = true;
  }
  if (!o_.fixes_topic.empty()) {
    // Every type the node takes; a second type on the topic is the decoder's to refuse.
    requireTopic(bags_, o_.fixes_topic, "fix", inputRoleOf(InputRole::Fix).types);
    fixes_ = o_.fixes_topic;
    topics.push_back(fixes_);
  }
  if (config_.parameters.use_mag) {
    requireTopic(bags_, o_.mag_topic, "magnetometer", inputRoleOf(InputRole::Field).types);
    mag_ = o_.mag_topic;
    topics.push_back(mag_);
  }
  if (config_.rate_input != RateInput::None && topicType(bags_, o_.bias_topic)) {
    requireTopic(bags_, o_.bias_topic, "gyro bias", inputRoleOf(InputRole::Bias).types);
    bias_ = o_.bias_topic;
    topics.push_back(bias_);
  }
  // The input's /tf, heard as the node's listener hears it (not an input: read with them).
  try {
    if (topicType(bags_, o_.tf_topic) == typeOf<tf2_msgs::TFMessage>().first) tf_ = o_.tf_topic;
  } catch (const ToolError&) {
    // A /tf of several types is no tf tree: not heard, as a tf listener would not.
  }
  return topics;
}

double BagPropagator::estimatedBytes() {
  const RecordSizes sizes =
      o_.csv ? RecordSizes{CsvWriter::rowBytes(), 0.0} : bagRecordSizes(o_, config_, *engine_);
  // The output's size: a state per rate input (kinematic) or per grid stamp (dynamic), and
  // each IMU input republished; the bag's header and index besides.
  const std::uint64_t rates = rates_.empty() ? 0 : messageCount(bags_, {rates_});
  const double states = config_.model == Model::Dynamic && !o_.io_floor
                            ? config_.parameters.publish_rate * bag_seconds_ + 1.0
                            : double(o_.io_floor ? messages_total_ : rates);
  const double imu = config_.rate_input == RateInput::Imu && !o_.csv ? double(rates) : 0.0;
  constexpr double kBagOverhead = 64 * 1024;
  return std::min(states * sizes.per_state + imu * sizes.per_imu + kBagOverhead, 1e18);
}

void BagPropagator::run(const std::string& path) {
  const std::vector<std::string> topics = checkTopics();
  for (const std::string& overlap : bags_.overlaps(topics)) {
    std::fprintf(stderr,
                 "propagate_bag: %s of record time: their messages are interleaved by record "
                 "time (one recording given twice would send each input twice: dropped as "
                 "stale)\n",
                 overlap.c_str());
  }
  if (o_.csv) {
    writer_ = std::make_unique<CsvWriter>(path, o_.output, outputEncoder(config_, *engine_));
  } else {
    writer_ = std::make_unique<BagWriter>(path, o_, config_, *engine_);
  }
  {
    rosbag::View inputs;
    bags_.addQuery(inputs, topics);
    bag_seconds_ = inputs.size() > 0 ? (inputs.getEndTime() - inputs.getBeginTime()).toSec() : 0.0;
    messages_total_ = inputs.size();
  }
  requireFreeSpace(o_.output, static_cast<std::uint64_t>(estimatedBytes()));
  std::vector<std::string> read = topics;
  if (!tf_.empty()) read.push_back(tf_);
  rosbag::View view;
  bags_.addQuery(view, read);
  Progress progress(view.size(), o_.progress);
  visitMessages(view, bags_.name(), progress, messages_, [this](const rosbag::MessageInstance& m) {
    record_ = m.getTime();
    dispatch(m);
  });
  messages_ -= tf_read_;
  writer_->close();
  progress.finish();
  wall_ = progress.elapsed();
}

void BagPropagator::dispatch(const rosbag::MessageInstance& m) {
  const std::string& topic = m.getTopic();
  if (!tf_.empty() && sameTopic(topic, tf_)) {
    ++tf_read_;
    if (!isType<tf2_msgs::TFMessage>(m)) return;
    if (!tf_buffer_) readStaticTransforms();
    deserializeInto(m, buffer_, tf_msg_);
    for (const auto& t : tf_msg_.transforms) tf_buffer_->setTransform(t, "bag", false);
    return;
  }
  ++read_[topic];
  if (!rates_.empty() && sameTopic(topic, rates_)) {
    if (config_.rate_input == RateInput::Imu) {
      onImu(m);
    } else {
      DecodedInput in = decoders_.twistTopic(m, record_, &frames_);
      noteNoMount(in);
      take(in);
    }
  } else if (!torque_.empty() && sameTopic(topic, torque_)) {
    DecodedInput in = decoders_.torqueTopic(m, record_, &frames_);
    take(in);
  } else if (!clock_.empty() && sameTopic(topic, clock_)) {
    deserializeInto(m, buffer_, clock_msg_);
    if (m.getCallerId() != clock_publisher_) {
      previous_clock_publisher_ = clock_publisher_;
      clock_publisher_ = m.getCallerId();
    }
    if (!o_.io_floor) engine_->clockTick(toStamp(clock_msg_.clock));
  } else if (!bias_.empty() && sameTopic(topic, bias_)) {
    onBias(m);
  } else if (!fixes_.empty() && sameTopic(topic, fixes_)) {
    onFix(m);
  } else if (!mag_.empty() && sameTopic(topic, mag_)) {
    onMag(m);
  }
}

void BagPropagator::onImu(const rosbag::MessageInstance& m) {
  deserializeInto(m, buffer_, *imu_msg_);
  DecodedInput in = decoders_.imu(*imu_msg_, record_, &frames_);
  noteNoMount(in);
  if (!in) return take(in);
  imu_.q_BS = in.q_BS;
  if (engine_->dynamicModel()) {
    // May wait for the clock, while later messages are decoded into imu_msg_: a copy.
    in.value->payload = std::make_shared<ImuPayload>(
        ImuPayload{boost::make_shared<const sensor_msgs::Imu>(*imu_msg_), imu_.q_BS});
  } else {
    // Applied before submit() returns: point at the reused message, no allocation.
    in.value->payload = std::shared_ptr<const void>(std::shared_ptr<const void>(), &imu_);
  }
  take(in);
  // The accelerometer after its message's rate, at the same stamp, as the node submits it.
  if (config_.parameters.use_accel && in.acceleration && !o_.io_floor) {
    ++accel_read_;
    engine_->submitAcceleration(in.acceleration->stamp, in.acceleration->value_B,
                                in.acceleration->covariance_B);  // counted in accel_*
  }
}

void BagPropagator::onMag(const rosbag::MessageInstance& m) {
  deserializeInto(m, buffer_, mag_msg_);
  const DecodedField field = decoders_.magneticField(mag_msg_, record_, &frames_);
  warnFrames();
  if (!field) return countRefusal(*engine_, field.refusal->why);
  if (o_.io_floor) return;
  engine_->submitMagneticField(field->stamp, field->value_B, field->covariance_B);
}

void BagPropagator::onBias(const rosbag::MessageInstance& m) {
  deserializeInto(m, buffer_, bias_msg_);
  const Decoded<BiasSample> bias = decoders_.bias(bias_msg_, record_);
  warnFrames();
  if (!bias) return countRefusal(*engine_, bias.refusal->why);
  if (!o_.io_floor) engine_->submitBias(bias->stamp, bias->b_B);  // counted by the engine
}

void BagPropagator::onFix(const rosbag::MessageInstance& m) {
  const Decoded<Fix> fix = fix_decoder_.topic(m, record_, &frames_);  // refusals counted there
  warnFrames();
  if (!fix || o_.io_floor) return;
  engine_->submitFix(fix->stamp, fix->q_WB, fix->R_B);  // counted in the engine's fixes_*
}

void BagPropagator::warnFrames() {
  // Once per frame with tf1's leading '/' (frame_ids.h); nothing to do otherwise.
  // A message's frame id is the sender's text: capped by the one text rule, as the node's line.
  for (const auto& w : decoders_.takeFrameWarnings()) {
    std::fprintf(stderr, "warning: %s\n", logText(w, 4 * kLogTextBytes).c_str());
  }
  for (const auto& w : fix_decoder_.takeFrameWarnings()) {
    std::fprintf(stderr, "warning: %s\n", logText(w, 4 * kLogTextBytes).c_str());
  }
}

void BagPropagator::noteNoMount(const DecodedInput& in) {
  if (in.refusal && in.refusal->why == Refused::NoTransform && no_mount_frame_.empty() &&
      in.refusal->detail != kFrameIdRule) {
    no_mount_frame_ = tf2FrameId(in.refusal->frame);
  }
}

void BagPropagator::take(DecodedInput& in) {
  warnFrames();
  if (!in) return countRefusal(*engine_, in.refusal->why);
  submit(*in.value);
}

void BagPropagator::submit(Input& input) {
  if (o_.io_floor) {
    // The same outputs without propagating: one identity state per input.
    ++floor_accepted_;
    EngineState s;
    s.stamp = input.stamp;
    s.w_B = input.value;
    publishState(s);
    inputApplied(input, s);
    return;
  }
  engine_->submit(input);
  if (!clock_driven_ && engine_->dynamicModel()) tickTo(input.stamp);
}

void BagPropagator::tickTo(Stamp now) {
  // The engine's rule (clockTicksTo): no grid stamp deferred by its budget, a gap one tick.
  for (Stamp t : engine_->clockTicksTo(last_tick_, now)) engine_->clockTick(t);
  last_tick_ = last_tick_ ? std::max(*last_tick_, now) : now;
}

void BagPropagator::readStaticTransforms() {
  // The bags' static transforms, read once (a handful of messages); a later one for the same
  // child frame replaces an earlier one, as in tf2.
  tf_buffer_ = std::make_unique<tf2::BufferCore>();
  if (!topicType(bags_, o_.static_tf_topic)) return;
  rosbag::View view;
  bags_.addQuery(view, {o_.static_tf_topic});
  for (const rosbag::MessageInstance& m : view) {
    if (!isType<tf2_msgs::TFMessage>(m)) continue;
    tf2_msgs::TFMessage tf;
    deserializeInto(m, buffer_, tf);
    for (const auto& t : tf.transforms) {
      tf_buffer_->setTransform(t, "bag", true);
      static_edges_[t.child_frame_id] = t;
    }
  }
}

std::optional<Eigen::Quaterniond> BagPropagator::BagFrames::rotation(const std::string& target,
                                                                     const std::string& source,
                                                                     const ros::Time& stamp,
                                                                     std::string* error) {
  if (!run_.tf_buffer_) run_.readStaticTransforms();
  const auto q = BufferCoreFrames(*run_.tf_buffer_).rotation(target, source, stamp, error);
  if (!q) {
    if (!reported_[source]) {
      reported_[source] = true;
      const bool body = target == run_.config_.parameters.body_frame;
      std::fprintf(stderr,
                   "propagate_bag: no transform %s -> %s in %s (/tf_static, or /tf so far): its "
                   "messages are dropped until there is one%s%s\n",
                   logText(target).c_str(), logText(source).c_str(), run_.bags_.name().c_str(),
                   body ? "; to take it as the body: --set body_frame=" : "",
                   body ? logText(source).c_str() : "");
    }
    return std::nullopt;
  }
  run_.recordMount(target, source);
  return q;
}

void BagPropagator::recordMount(const std::string& target, const std::string& source) {
  // The transforms as recorded, each edge of the tree between the two frames, rather than the
  // one rotation composed of them: played next to the input, the output's /tf_static then
  // agrees with the input's, where a shortcut would give a frame a second parent.
  auto chain = [this](std::string frame) {
    std::vector<std::string> frames{frame};
    for (auto it = static_edges_.find(frame);
         it != static_edges_.end() && frames.size() <= static_edges_.size();
         it = static_edges_.find(frame)) {
      frame = it->second.header.frame_id;
      frames.push_back(frame);
    }
    return frames;
  };
  const std::vector<std::string> up_source = chain(source), up_target = chain(target);
  bool added = false;
  auto take = [&](const std::vector<std::string>& frames, const std::vector<std::string>& other) {
    for (const std::string& frame : frames) {
      if (std::find(other.begin(), other.end(), frame) != other.end()) break;  // common ancestor
      const auto edge = static_edges_.find(frame);
      if (edge == static_edges_.end()) break;
      added = mounts_used_.emplace(frame, edge->second).second || added;
    }
  };
  take(up_source, up_target);
  take(up_target, up_source);
  if (!added || !writer_) return;
  tf2_msgs::TFMessage message;
  for (const auto& [child, t] : mounts_used_) message.transforms.push_back(t);
  writer_->mounts(message, record_);
}

std::optional<std::string> BagPropagator::nothingUsable() const {
  const std::uint64_t accepted = o_.io_floor ? floor_accepted_ : engine_->counters().accepted;
  if (accepted == 0 && !no_mount_frame_.empty()) {
    return "no input accepted (" +
           noMountText(no_mount_frame_, config_.parameters.body_frame, "--set body_frame=") + ")";
  }
  if (accepted == 0) return "no input accepted";
  if (states_ == 0) return "no state published (the clock never reached a grid stamp)";
  return std::nullopt;
}

/// "name value, name value": the counters under the diagnostics' names (the core's table).
std::string countersText(const EngineCounters& c,
                         std::initializer_list<std::uint64_t EngineCounters::*> fields) {
  std::string text;
  for (std::uint64_t EngineCounters::*field : fields) {
    text += (text.empty() ? "" : ", ") + std::string(counterName(field)) + " " +
            std::to_string(c.*field);
  }
  return text;
}

void BagPropagator::summary(std::FILE* out, bool written) const {
  const EngineCounters& c = engine_->counters();
  std::string by_topic;
  for (const auto& [topic, n] : read_) {
    by_topic += (by_topic.empty() ? "" : ", ") + topic + " " + std::to_string(n);
  }
  std::string dropped;
  std::uint64_t dropped_total = 0;
  // Every way an input leaves the engine unused, under the diagnostics' names (the core's
  // counter table): with `accepted` and pending() these add up to `received` (each rate or
  // torque message read is submitted or rejected exactly once).
  forEachEngineCounter(c, [&](const CounterInfo& info, std::uint64_t n) {
    if (!countsUnusedInput(info)) return;
    dropped_total += n;
    if (n > 0) dropped += (dropped.empty() ? "" : ", ") + info.name + " " + std::to_string(n);
  });
  const std::uint64_t accepted = o_.io_floor ? floor_accepted_ : c.accepted;
  std::fprintf(
      out,
      "propagate_bag: %llu messages (%s), %llu accepted, dropped: %s; %s; %llu states -> %s; "
      "%.3f s wall, %.0f msg/s, %.0fx real time%s\n",
      static_cast<unsigned long long>(messages_), by_topic.c_str(),
      static_cast<unsigned long long>(accepted), dropped.empty() ? "none" : dropped.c_str(),
      countersText(c, {&EngineCounters::resets, &EngineCounters::jumps_back, &EngineCounters::gaps,
                       &EngineCounters::late})
          .c_str(),
      static_cast<unsigned long long>(states_), written ? o_.output.c_str() : "nothing written",
      wall_, wall_ > 0 ? double(messages_) / wall_ : 0.0, wall_ > 0 ? bag_seconds_ / wall_ : 0.0,
      o_.io_floor ? " (I/O floor: no propagation)" : "");
  if (c.clock_conflicts > 0) {
    std::fprintf(out,
                 "  clock: two timelines took turns on %s, %.3f s apart (%s): %llu times "
                 "recognised, the later followed, the other's ticks ignored, no reset for them\n",
                 logText(clock_).c_str(), clock_apart_, clock_sources_.c_str(),
                 static_cast<unsigned long long>(c.clock_conflicts));
  }
  if (o_.io_floor) return;
  const auto pending = static_cast<std::uint64_t>(engine_->pending());
  const std::uint64_t accounted = accepted + dropped_total + pending;
  std::fprintf(
      out, "  inputs: %llu = %llu accepted + %llu dropped + %llu pending at the end",
      static_cast<unsigned long long>(c.received), static_cast<unsigned long long>(accepted),
      static_cast<unsigned long long>(dropped_total), static_cast<unsigned long long>(pending));
  if (accounted != c.received) {
    std::fprintf(out, " (%lld not accounted for)",
                 static_cast<long long>(c.received) - static_cast<long long>(accounted));
  }
  std::fputc('\n', out);
  if (engine_->dynamicModel()) {
    std::fprintf(out,
                 "  dynamic: %s, pending %llu (inputs stamped after the last clock tick), %s\n",
                 countersText(c, {&EngineCounters::failed_steps}).c_str(),
                 static_cast<unsigned long long>(pending),
                 countersText(c, {&EngineCounters::deferred_ticks}).c_str());
  }
  if (const KinematicPropagator* k = engine_->kinematic()) stampSummary(out, *k);
  if (!bias_.empty()) {
    std::fprintf(out,
                 "  gyro bias: %s (refused: non-finite, too large, another frame, beyond "
                 "max_future; queue full: 64 waiting, the furthest ahead dropped)\n",
                 countersText(c, {&EngineCounters::bias_applied, &EngineCounters::rejected_bias,
                                  &EngineCounters::bias_queue_full})
                     .c_str());
  }
  if (!fixes_.empty()) fixSummary(out);
  std::uint64_t mag_read = 0;
  for (const auto& [topic, count] : read_) mag_read += sameTopic(topic, mag_) ? count : 0;
  printAidingSummary(out, c, config_.parameters.use_accel, config_.parameters.use_mag, accel_read_,
                     mag_read);
  if (config_.parameters.use_mag) printFieldFit(out, engine_->fieldFit());
}

// What the kinematic model did to the rates' stamps: the stamp filter's moves and fallbacks,
// the means filled in for lost samples (the gaps held are on the first line).
void BagPropagator::stampSummary(std::FILE* out, const KinematicPropagator& k) const {
  auto u = [](std::uint64_t x) { return static_cast<unsigned long long>(x); };
  if (const SensorClockFilter* f = k.stampFilter()) {
    std::fprintf(out,
                 "  stamp filter: %llu stamps moved (at most %.3f ms later and %.3f ms earlier "
                 "than received), %llu fallbacks to the receipt stamps (%s; jitter %.3g ms, "
                 "period %.3g ms), %llu rejected, %llu restarts\n",
                 u(f->moved()), f->largestLater() * 1e3, f->largestEarlier() * 1e3,
                 u(f->fallbacks()), f->misfit() ? "in one at the end" : "fitting at the end",
                 f->jitter() * 1e3, f->period() * 1e3, u(f->rejected()), u(f->restarts()));
  }
  if (k.rateSamples() == RateSamples::IntervalAverage) {
    std::fprintf(out,
                 "  interval averages: %llu means filled in for lost samples (max_gap_fill %d)\n",
                 u(k.filledSamples()), config_.parameters.max_gap_fill);
  }
}

void BagPropagator::fixSummary(std::FILE* out) const {
  // Every fix read is refused by the decoder, or submitted: then counted by the engine once
  // it is applied or rejected, or still waiting for the rates at the end.
  const EngineCounters& c = engine_->counters();
  const FixRefusals& r = fix_decoder_.refusals();
  std::uint64_t n = 0;
  for (const auto& [topic, count] : read_) n += sameTopic(topic, fixes_) ? count : 0;
  const std::uint64_t pending = engine_->pendingFixes();
  const std::uint64_t accounted = c.fixes_accepted + fixesNotApplied(c) + pending + r.total();
  auto u = [](std::uint64_t x) { return static_cast<unsigned long long>(x); };
  // The engine's counters in forEachFixCounter's order, the resets among the accepted.
  std::string engine_terms;
  forEachFixCounter(c, [&](const char* name, std::uint64_t value) {
    const std::string counter(name);
    if (counter == "reset") return;
    engine_terms += (engine_terms.empty() ? "" : " + ") + std::to_string(value) + " " + counter;
    if (counter == "accepted") engine_terms += " (" + std::to_string(c.fixes_reset) + " as resets)";
  });
  std::fprintf(out, "  fixes: %llu = %s + %llu pending at the end + %llu refused (%s)", u(n),
               engine_terms.c_str(), u(pending), u(r.total()), fixRefusalCounts(r).c_str());
  if (accounted != n) {
    std::fprintf(out, " (%lld not accounted for)",
                 static_cast<long long>(n) - static_cast<long long>(accounted));
  }
  if (config_.parameters.estimate_gyro_bias) {
    // With its standard deviation, so that an estimate stuck at its prior shows as one.
    const Eigen::Vector3d& b = engine_->gyroBiasEstimate();
    const Eigen::Vector3d s = engine_->gyroBiasStddev();
    std::fprintf(out,
                 "; gyro bias estimate [%g, %g, %g] rad/s, standard deviation [%g, %g, %g] rad/s "
                 "(prior %g)",
                 b.x(), b.y(), b.z(), s.x(), s.y(), s.z(), config_.parameters.gyro_bias_stddev);
  }
  std::fputc('\n', out);
}

/// A parameter's value as --dry-run prints it: the node's text for it (formatParameter), but a
/// text value capped by the one text rule (it is the user's) and shown as '' when empty.
std::string parameterText(const std::string& v) { return v.empty() ? "''" : logText(v); }
template <class T>
std::string parameterText(const T& v) {
  return formatParameter(v);
}

std::string BagPropagator::firstRateFrame() {
  rosbag::View view;
  bags_.addQuery(view, {rates_});
  for (const rosbag::MessageInstance& m : view) {
    if (isType<sensor_msgs::Imu>(m)) {
      deserializeInto(m, buffer_, *imu_msg_);
      return tf2FrameId(imu_msg_->header.frame_id);
    }
    // Any other rate type through a decoder of its own, whose type rule the run's does not
    // share: the frame its reading names (none for a plain Twist: in the body).
    InputDecoders probe(DecoderFrames::of(config_));
    const Decoded<Reading> reading = probe.readTwistTopic(m, m.getTime());
    return reading ? tf2FrameId(reading->frame_id) : std::string();
  }
  return {};
}

bool BagPropagator::mountReachable(std::FILE* out) {
  const std::string frame = firstRateFrame();
  const std::string& body = config_.parameters.body_frame;
  if (frame.empty() || frame == body || frameIdRefused(frame)) return true;
  readStaticTransforms();
  if (tf_buffer_->canTransform(body, frame, ros::Time())) {
    std::fprintf(out, "  mount: rates in '%s', joined to body_frame '%s' by /tf_static\n",
                 logText(frame).c_str(), logText(body).c_str());
    return true;
  }
  if (!tf_.empty()) {
    std::fprintf(out,
                 "  mount: rates in '%s': no static transform to body_frame '%s'; looked up "
                 "on %s as recorded\n",
                 logText(frame).c_str(), logText(body).c_str(), tf_.c_str());
    return true;
  }
  std::fprintf(out, "  mount: %s\n", noMountText(frame, body, "--set body_frame=").c_str());
  return false;
}

int BagPropagator::dryRun(std::FILE* out) {
  const std::vector<std::string> topics = checkTopics();
  std::fprintf(out, "propagate_bag: dry run, nothing written\n");
  std::map<std::string, std::string> roles{{rates_, "rates"},
                                           {torque_, "torque"},
                                           {clock_, "clock: drives the engine"},
                                           {bias_, "gyro bias"},
                                           {fixes_, "fixes"},
                                           {mag_, "magnetometer"},
                                           {o_.static_tf_topic, "static transforms (mounts)"},
                                           {tf_, "transforms (mounts, torque frames)"}};
  for (std::size_t i = 0; i < bags_.size(); ++i) {
    rosbag::View all(bags_.bag(i));
    std::fprintf(out, "  %s: %u messages, %.3f s of record time\n", bags_.paths()[i].c_str(),
                 all.size(),
                 all.size() > 0 ? (all.getEndTime() - all.getBeginTime()).toSec() : 0.0);
    std::map<std::string, std::pair<std::string, std::uint64_t>> by_topic;
    for (const rosbag::ConnectionInfo* c : all.getConnections()) {
      by_topic[c->topic].first = c->datatype;
    }
    for (auto& [topic, entry] : by_topic) {
      entry.second = rosbag::View(bags_.bag(i), rosbag::TopicQuery(topic)).size();
      std::string role = "not read";
      for (const auto& [name, what] : roles) {
        if (!name.empty() && sameTopic(topic, name)) role = what;
      }
      std::fprintf(out, "    %-24s %-32s %8llu  %s\n", topic.c_str(), entry.first.c_str(),
                   static_cast<unsigned long long>(entry.second), role.c_str());
    }
  }
  for (const std::string& overlap : bags_.overlaps(topics)) {
    std::fprintf(out, "  warning: %s of record time: messages interleaved\n", overlap.c_str());
  }
  const auto& p = config_.parameters;
  const std::string grid =
      engine_->dynamicModel() ? ", publish_rate " + parameterText(p.publish_rate) + " Hz" : "";
  const std::string integrator = integratorName(engine_->integrator());
  std::fprintf(out,
               "  settings: model %s, integrator %s, rate_input %s, fixed_frame %s, body_frame "
               "%s, max_dt %g s%s; time from %s\n",
               engine_->modelName().c_str(), integrator.c_str(), p.rate_input.c_str(),
               logText(p.fixed_frame).c_str(), logText(p.body_frame).c_str(), p.max_dt,
               grid.c_str(), clock_driven_ ? clock_.c_str() : "the input stamps");
  std::string all;
  forEachParameter(p, [&all](const char* name, const auto& value, const char*, const char*) {
    all += (all.empty() ? "" : ", ") + std::string(name) + "=" + parameterText(value);
  });
  std::fprintf(out, "  parameters: %s\n", all.c_str());
  rosbag::View view;
  bags_.addQuery(view, topics);
  bag_seconds_ = view.size() > 0 ? (view.getEndTime() - view.getBeginTime()).toSec() : 0.0;
  messages_total_ = view.size();
  std::string outputs;
  if (o_.csv) {
    outputs = "CSV";
  } else {
    outputs = "bag (" +
              std::string(o_.compression == BagOutput::Compression::Lz4 ? "lz4" : "uncompressed") +
              "): " + o_.state_out;
    if (config_.rate_input == RateInput::Imu) outputs += ", " + o_.imu_out;
    if (p.publish_tf) outputs += ", " + o_.tf_out;
    outputs += ", " + o_.tf_static_out + " (mounts used, latched)";
  }
  const double bytes = estimatedBytes();
  std::fprintf(out, "  output: %s, %s; about %.1f MB from %llu messages\n", o_.output.c_str(),
               outputs.c_str(), bytes / 1e6, static_cast<unsigned long long>(messages_total_));
  return mountReachable(out) ? kExitOk : kExitNothingUsable;
}

int run(int argc, char** argv) {
  catchInterrupts();
  const Options o = parseOptions(argc, argv);
  BagSet bags(o.inputs);
  if (o.dry_run) {
    return BagPropagator(o, bags).dryRun(stdout);
  }
  PendingFile output(o.output);  // destroyed last: the writer closes before it is removed
  if (output.leftovers() > 0) {
    std::fprintf(stderr, "propagate_bag: removed %d partial output(s) of %s left by killed runs\n",
                 output.leftovers(), o.output.c_str());
  }
  BagPropagator propagator(o, bags);
  propagator.run(output.temporary());
  throwIfInterrupted();  // a signal after the last message: still no output
  if (const auto why = propagator.nothingUsable()) {
    propagator.summary(stdout, false);
    throw ToolError(bags.name() + ": " + *why + "; no output written", kExitNothingUsable);
  }
  output.commit();
  propagator.summary(stdout, true);
  return kExitOk;
}

}  // namespace
}  // namespace tools
}  // namespace attitude_propagator

int main(int argc, char** argv) {
  return attitude_propagator::tools::runTool("propagate_bag", attitude_propagator::tools::run, argc,
                                             argv);
}
