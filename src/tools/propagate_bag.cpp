// propagate_bag: the node's propagation over a recorded bag, as fast as the machine allows.
// Reads the rate topic (sensor_msgs/Imu, geometry_msgs/Twist or TwistStamped) and, in the
// dynamic model, the torque topic, with the node's parameters and YAML, through the same core
// engine; writes attitude_state, imu/data and /tf into an output bag at the input messages'
// record times (or the states into a CSV). The bag is read chunk by chunk (rosbag::View),
// never whole.
//
// Time, as the node under sim time: a /clock topic in the bag drives the engine's clock. Without
// one, the input stamps do (each input is submitted, then the clock ticks to its stamp, so a
// grid stamp's state includes the inputs stamped up to it).
#include <algorithm>
#include <cstdio>
#include <cstring>
#include <iostream>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <geometry_msgs/Twist.h>
#include <geometry_msgs/TwistStamped.h>
#include <geometry_msgs/Vector3Stamped.h>
#include <geometry_msgs/Wrench.h>
#include <geometry_msgs/WrenchStamped.h>
#include <rosgraph_msgs/Clock.h>
#include <sensor_msgs/Imu.h>
#include <tf2/buffer_core.h>
#include <tf2/exceptions.h>
#include <tf2_msgs/TFMessage.h>

#include "attitude_propagator/AttitudeState.h"
#include "attitude_propagator/engine.h"
#include "attitude_propagator/orientation_covariance.h"
#include "attitude_propagator/ros/conversions.h"
#include "attitude_propagator/ros/imu_input.h"
#include "tool_support.h"

namespace attitude_propagator {
namespace tools {
namespace {

const char* const kUsage = R"(usage: propagate_bag IN.bag [options]

Propagates the attitude over a recorded bag with the node's engine and parameters, as fast as
the machine allows, and writes attitude_state, imu/data and /tf into a bag (or a CSV).

  -o, --output OUT.bag   output bag (default: IN.propagated.bag)
  --csv OUT.csv          write the states as CSV instead of a bag
  --compression none|lz4 output bag chunks stored as they are (default) or LZ4-compressed
                         (about 5x smaller, slower)
  --config FILE.yaml     node parameters (the keys of config/default.yaml)
  --set name=value       one node parameter (YAML value), after --config; repeatable
  --rates TOPIC          rate topic (default /imu/data_raw, or /body_twist for rate_input twist)
  --torque TOPIC         torque topic, dynamic model with torque_input (default /torque)
  --clock TOPIC          clock topic driving the engine when present (default /clock)
  --no-clock             ignore the clock topic: input stamps drive the engine
  --io-floor             read, decode and write the same outputs without propagating (one
                         identity state per input): the I/O cost alone, for benchmarks
  --no-progress          no progress line (it is shown only on a terminal anyway)
  -h, --help             this text

The output never replaces an input (the bag or a --config file, under any name: refused), is
written under a temporary name in its directory and appears under its own name only when
complete; the run is refused at the start when the file system has less free space than the
output's estimated size.

Exit codes:
  0    the output is complete and holds the states of the accepted inputs
  1    an input could not be read (missing, truncated, damaged) or the output not written
       (full disk, no permission); nothing is left under the output name
  2    usage: bad options or parameters, or an output that is an input
  3    the bag was read to the end but no input was accepted (or no state published); the
       summary counts why (e.g. "no-tf 4001"), and no output is written
  128+N  stopped by signal N (130: Ctrl-C, 143: SIGTERM, 129: SIGHUP); no output is written
)";

struct Options {
  std::string input;
  std::string output;
  bool csv = false;
  BagOutput::Compression compression = BagOutput::Compression::None;
  std::string rates_topic;
  std::string torque_topic = "/torque";
  std::string clock_topic = "/clock";
  std::string bias_topic = "/gyro_bias";
  std::string static_tf_topic = "/tf_static";
  bool use_clock = true;
  bool io_floor = false;
  bool progress = true;
  Parameters parameters;
};

BagOutput::Compression parseCompression(const std::string& name) {
  if (name == "none") return BagOutput::Compression::None;
  if (name == "lz4") return BagOutput::Compression::Lz4;
  throw UsageError("--compression " + name + ": none or lz4");
}

Options parseOptions(int argc, char** argv) {
  Options o;
  std::vector<std::string> configs, sets;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "-h" || a == "--help") {
      std::cout << kUsage;
      std::exit(0);
    } else if (a == "-o" || a == "--output") {
      o.output = optionValue(argc, argv, i);
    } else if (a == "--csv") {
      o.output = optionValue(argc, argv, i);
      o.csv = true;
    } else if (a == "--compression") {
      o.compression = parseCompression(optionValue(argc, argv, i));
    } else if (a == "--config") {
      configs.push_back(optionValue(argc, argv, i));
    } else if (a == "--set") {
      sets.push_back(optionValue(argc, argv, i));
    } else if (a == "--rates") {
      o.rates_topic = optionValue(argc, argv, i);
    } else if (a == "--torque") {
      o.torque_topic = optionValue(argc, argv, i);
    } else if (a == "--clock") {
      o.clock_topic = optionValue(argc, argv, i);
    } else if (a == "--no-clock") {
      o.use_clock = false;
    } else if (a == "--io-floor") {
      o.io_floor = true;
    } else if (a == "--no-progress") {
      o.progress = false;
    } else if (!a.empty() && a[0] == '-') {
      throw UsageError(a + ": unknown option (see --help)");
    } else if (o.input.empty()) {
      o.input = a;
    } else {
      throw UsageError(a + ": one input bag only (see --help)");
    }
  }
  if (o.input.empty()) throw UsageError("no input bag (see --help)");
  for (const auto& c : configs) loadConfigFile(c, o.parameters);
  for (const auto& s : sets) applySetting(s, o.parameters);
  validateParameters(o.parameters);  // std::invalid_argument: a usage error, before any reading
  if (o.output.empty()) {
    const bool bag = o.input.size() > 4 && o.input.compare(o.input.size() - 4, 4, ".bag") == 0;
    o.output = (bag ? o.input.substr(0, o.input.size() - 4) : o.input) + ".propagated.bag";
  }
  std::vector<std::string> inputs = configs;
  inputs.push_back(o.input);
  refuseOutputOverInput(o.output, inputs);
  if (o.rates_topic.empty()) {
    o.rates_topic = o.parameters.rate_input == "twist" ? "/body_twist" : "/imu/data_raw";
  }
  return o;
}

// ---------------------------------------------------------------------------------------------
// Outputs
// ---------------------------------------------------------------------------------------------

/// Where states (and the republished IMU messages) go.
class Writer {
 public:
  virtual ~Writer() = default;
  /// Bytes the output takes per state and per republished IMU message (an estimate for the
  /// free-space check: the messages as they will be written, with their frame names).
  virtual double bytesPerState() const = 0;
  virtual double bytesPerImu() const = 0;
  virtual void state(const EngineState& s, const ros::Time& record) = 0;
  virtual void imu(const sensor_msgs::Imu& input, const EngineState& s,
                   const Eigen::Quaterniond& q_BI, const ros::Time& record) = 0;
  virtual void close() = 0;
};

/// attitude_state, imu/data and /tf as the node publishes them, into a bag.
class BagWriter : public Writer {
 public:
  BagWriter(const std::string& path, const Options& o, const Parameters& p,
            const AttitudeEngine& engine)
      : bag_(path, o.output, o.compression),
        lz4_(o.compression == BagOutput::Compression::Lz4),
        publish_tf_(p.publish_tf),
        reverse_tf_(p.reverse_tf) {
    state_.header.frame_id = p.fixed_frame;
    state_.child_frame_id = p.body_frame;
    state_.model = engine.modelName();
    state_.integrator = integratorName(engine.integrator());
    tf_.transforms.resize(1);
    auto& t = tf_.transforms[0];
    t.header.frame_id = p.reverse_tf ? p.body_frame : p.fixed_frame;
    t.child_frame_id = p.reverse_tf ? p.fixed_frame : p.body_frame;
  }

  void state(const EngineState& s, const ros::Time& record) override {
    const ros::Time stamp = toRosTime(s.stamp);
    if (publish_tf_) {
      auto& t = tf_.transforms[0];
      t.header.stamp = stamp;
      toMsg(reverse_tf_ ? s.q_WB.conjugate() : s.q_WB, t.transform.rotation);
      bag_.write("/tf", record, tf_);
    }
    state_.header.stamp = stamp;
    toMsg(s.q_WB, state_.orientation);
    covarianceToMsg(s.P_B, state_.orientation_covariance);
    toMsg(s.w_B, state_.angular_velocity);
    toMsg(s.M_B, state_.angular_momentum);
    state_.kinetic_energy = s.kinetic_energy;
    state_.norm_error = s.norm_error;
    state_.steps = s.steps;
    bag_.write("/attitude_state", record, state_);
  }

  void imu(const sensor_msgs::Imu& input, const EngineState& s, const Eigen::Quaterniond& q_BI,
           const ros::Time& record) override {
    // As the node: the input with the orientation of the IMU's own frame and its covariance.
    imu_ = input;
    imu_.header.stamp = toRosTime(s.stamp);
    toMsg(s.q_WB * q_BI, imu_.orientation);
    covarianceToMsg(rotateCovariance(s.P_B, q_BI.conjugate().toRotationMatrix()),
                    imu_.orientation_covariance);
    bag_.write("/imu/data", record, imu_);
  }

  void close() override { bag_.close(); }

  // A record is its header (op, conn and time fields: 38 bytes), two lengths and the message,
  // plus a 12-byte index entry. LZ4 stores these streams about 5x smaller (README); a quarter
  // is assumed.
  double bytesPerState() const override {
    const double bytes = record(state_) + (publish_tf_ ? record(tf_) : 0.0);
    return lz4_ ? bytes / 4 : bytes;
  }
  double bytesPerImu() const override {
    sensor_msgs::Imu imu;
    imu.header.frame_id = "imu_link";
    return lz4_ ? record(imu) / 4 : record(imu);
  }

 private:
  template <class M>
  static double record(const M& msg) {
    return 4 + 38 + 4 + ros::serialization::serializationLength(msg) + 12;
  }

  BagOutput bag_;
  bool lz4_;
  bool publish_tf_;
  bool reverse_tf_;
  AttitudeState state_;
  tf2_msgs::TFMessage tf_;
  sensor_msgs::Imu imu_;
};

/// One line per state.
class CsvWriter : public Writer {
 public:
  CsvWriter(const std::string& path, const std::string& name) : file_(path, name) {
    std::fputs(
        "stamp,qx,qy,qz,qw,wx,wy,wz,P_xx,P_xy,P_xz,P_yx,P_yy,P_yz,P_zx,P_zy,P_zz,norm_error,"
        "steps,Mx,My,Mz,kinetic_energy\n",
        file_.get());
  }

  void state(const EngineState& s, const ros::Time&) override {
    const int n = format(s, row_, sizeof row_);
    std::fwrite(row_, 1, static_cast<std::size_t>(std::min<int>(n, sizeof row_ - 1)), file_.get());
    file_.check();
  }
  void imu(const sensor_msgs::Imu&, const EngineState&, const Eigen::Quaterniond&,
           const ros::Time&) override {}
  void close() override { file_.close(); }

  /// A row of numbers as long as they print (negative, 17 digits, 3-digit exponents).
  double bytesPerState() const override {
    EngineState s;
    const double x = -0.12345678901234567e-100;
    s.stamp = std::numeric_limits<Stamp>::max();
    s.q_WB.coeffs().setConstant(x);
    s.w_B.setConstant(x);
    s.P_B.setConstant(x);
    s.M_B.setConstant(x);
    s.norm_error = s.kinetic_energy = x;
    s.steps = std::numeric_limits<decltype(s.steps)>::max();
    char row[sizeof row_];
    return format(s, row, sizeof row);
  }
  double bytesPerImu() const override { return 0.0; }

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
  char row_[1024];
};

// ---------------------------------------------------------------------------------------------
// The run
// ---------------------------------------------------------------------------------------------

/// An IMU message kept with its input until the engine applies it, with its sensor mount.
struct ImuPayload {
  sensor_msgs::Imu msg;
  Eigen::Quaterniond q_BI = Eigen::Quaterniond::Identity();
};

class BagPropagator : public EngineSink {
 public:
  BagPropagator(const Options& o, rosbag::Bag& bag)
      : o_(o), bag_(bag), config_(validateParameters(o.parameters)) {
    engine_ = std::make_unique<AttitudeEngine>(engineConfig(config_), *this);
  }

  /// Checks the topics and the free space, then runs; writes into `path` (a temporary name).
  void run(const std::string& path);
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
    writer_->imu(imu.msg, state, imu.q_BI, record_);
  }
  void note(const EngineNote&) override {}  // counted by the engine, summarised at the end

 private:
  std::vector<std::string> checkTopics();
  void dispatch(const rosbag::MessageInstance& m);
  void onImu(const rosbag::MessageInstance& m);
  void onTwist(const rosbag::MessageInstance& m);
  void onTorque(const rosbag::MessageInstance& m);
  void onBias(const rosbag::MessageInstance& m);
  void submit(Input& input);
  void tickTo(Stamp now);
  const Eigen::Quaterniond* mountRotation(const std::string& frame_id);
  std::optional<Eigen::Quaterniond> staticRotation(const std::string& target,
                                                   const std::string& source);

  const Options& o_;
  rosbag::Bag& bag_;
  NodeConfig config_;
  std::unique_ptr<AttitudeEngine> engine_;
  std::unique_ptr<Writer> writer_;
  std::string rates_, torque_, clock_, bias_;  // as recorded; empty: not read
  bool clock_driven_ = false;
  ros::Time record_;  // record time of the message being handled
  std::optional<Stamp> last_tick_;
  std::optional<std::string> twist_type_, wrench_type_;
  ImuPayload imu_;
  geometry_msgs::TwistStamped twist_stamped_;
  geometry_msgs::Twist twist_;
  geometry_msgs::WrenchStamped wrench_stamped_;
  geometry_msgs::Wrench wrench_;
  geometry_msgs::Vector3Stamped bias_msg_;
  rosgraph_msgs::Clock clock_msg_;
  std::vector<std::uint8_t> buffer_;
  std::unique_ptr<tf2::BufferCore> static_tf_;
  std::map<std::string, std::optional<Eigen::Quaterniond>> mounts_;
  std::map<std::string, std::uint64_t> read_;  // messages read per role
  std::uint64_t messages_ = 0;
  std::uint64_t states_ = 0;
  std::uint64_t floor_accepted_ = 0;  // --io-floor: inputs passed straight to the outputs
  double wall_ = 0.0;
  double bag_seconds_ = 0.0;
};

std::vector<std::string> BagPropagator::checkTopics() {
  std::vector<std::string> topics;
  const bool dynamic = config_.model == Model::Dynamic;
  if (config_.rate_input == RateInput::Imu) {
    requireTopic(bag_, o_.rates_topic, "rate", {typeOf<sensor_msgs::Imu>()});
  } else if (config_.rate_input == RateInput::Twist) {
    requireTopic(bag_, o_.rates_topic, "rate",
                 {typeOf<geometry_msgs::Twist>(), typeOf<geometry_msgs::TwistStamped>()});
  }
  if (config_.rate_input != RateInput::None) {
    rates_ = recordedName(bag_, o_.rates_topic);
    topics.push_back(rates_);
  }
  if (dynamic && config_.torque_input) {
    requireTopic(bag_, o_.torque_topic, "torque",
                 {typeOf<geometry_msgs::Wrench>(), typeOf<geometry_msgs::WrenchStamped>()});
    torque_ = recordedName(bag_, o_.torque_topic);
    topics.push_back(torque_);
  }
  if (topics.empty()) {
    throw ToolError("nothing to read: rate_input is none and torque_input is off");
  }
  if (o_.use_clock && topicType(bag_, o_.clock_topic)) {
    requireTopic(bag_, o_.clock_topic, "clock", {typeOf<rosgraph_msgs::Clock>()});
    clock_ = recordedName(bag_, o_.clock_topic);
    topics.push_back(clock_);
    clock_driven_ = true;
  }
  if (config_.rate_input != RateInput::None && topicType(bag_, o_.bias_topic)) {
    requireTopic(bag_, o_.bias_topic, "gyro bias", {typeOf<geometry_msgs::Vector3Stamped>()});
    bias_ = recordedName(bag_, o_.bias_topic);
    topics.push_back(bias_);
  }
  return topics;
}

void BagPropagator::run(const std::string& path) {
  const std::vector<std::string> topics = checkTopics();
  if (o_.csv) {
    writer_ = std::make_unique<CsvWriter>(path, o_.output);
  } else {
    writer_ = std::make_unique<BagWriter>(path, o_, config_.parameters, *engine_);
  }
  rosbag::View view(bag_, rosbag::TopicQuery(topics));
  bag_seconds_ = (view.getEndTime() - view.getBeginTime()).toSec();
  // The output's size: a state per rate input (kinematic) or per grid stamp (dynamic), and
  // each IMU input republished; the bag's header and index besides.
  const std::uint64_t rates =
      rates_.empty() ? 0 : rosbag::View(bag_, rosbag::TopicQuery(rates_)).size();
  const double states = config_.model == Model::Dynamic && !o_.io_floor
                            ? config_.parameters.publish_rate * bag_seconds_ + 1.0
                            : double(o_.io_floor ? view.size() : rates);
  const double imu = config_.rate_input == RateInput::Imu && !o_.csv ? double(rates) : 0.0;
  constexpr double kBagOverhead = 64 * 1024;
  requireFreeSpace(
      o_.output,
      static_cast<std::uint64_t>(std::min(
          states * writer_->bytesPerState() + imu * writer_->bytesPerImu() + kBagOverhead, 1e18)));
  Progress progress(view.size(), o_.progress);
  visitMessages(view, o_.input, progress, messages_, [this](const rosbag::MessageInstance& m) {
    record_ = m.getTime();
    dispatch(m);
  });
  writer_->close();
  progress.finish();
  wall_ = progress.elapsed();
}

void BagPropagator::dispatch(const rosbag::MessageInstance& m) {
  const std::string& topic = m.getTopic();
  ++read_[topic];
  if (topic == rates_) {
    if (config_.rate_input == RateInput::Imu) {
      onImu(m);
    } else {
      onTwist(m);
    }
  } else if (topic == torque_) {
    onTorque(m);
  } else if (topic == clock_) {
    decodeInto(m, buffer_, clock_msg_);
    if (!o_.io_floor) engine_->clockTick(toStamp(clock_msg_.clock));
  } else if (topic == bias_) {
    onBias(m);
  }
}

void BagPropagator::onImu(const rosbag::MessageInstance& m) {
  decodeInto(m, buffer_, imu_.msg);
  const sensor_msgs::Imu& msg = imu_.msg;
  if (const auto refusal = refuseImuRate(msg)) {
    engine_->reject(refusal->why);
    return;
  }
  const Eigen::Quaterniond* q_BS = mountRotation(msg.header.frame_id);
  if (!q_BS) return;
  imu_.q_BI = *q_BS;
  Input input = imuRateInput(msg, *q_BS, stampOr(msg.header.stamp, record_));
  if (engine_->dynamicModel()) {
    input.payload = std::make_shared<ImuPayload>(imu_);  // may wait for the clock
  } else {
    // Applied before submit() returns: point at the reused message, no allocation.
    input.payload = std::shared_ptr<const void>(std::shared_ptr<const void>(), &imu_);
  }
  submit(input);
}

void BagPropagator::onTwist(const rosbag::MessageInstance& m) {
  // As the node: the first message fixes the topic's type.
  if (!twist_type_) twist_type_ = m.getDataType();
  if (m.getDataType() != *twist_type_) {
    engine_->reject(Rejection::WrongType);
    return;
  }
  Input input;
  input.source = Source::Twist;
  std::string frame_id;
  if (isType<geometry_msgs::TwistStamped>(m)) {
    decodeInto(m, buffer_, twist_stamped_);
    input.stamp = stampOr(twist_stamped_.header.stamp, record_);
    input.value = toEigen(twist_stamped_.twist.angular);
    frame_id = twist_stamped_.header.frame_id;
  } else {
    decodeInto(m, buffer_, twist_);
    input.stamp = toStamp(record_);
    input.value = toEigen(twist_.angular);
  }
  const Eigen::Quaterniond* q_BS = mountRotation(frame_id);
  if (!q_BS) return;
  input.value = *q_BS * input.value;
  submit(input);
}

void BagPropagator::onTorque(const rosbag::MessageInstance& m) {
  if (!wrench_type_) wrench_type_ = m.getDataType();
  if (m.getDataType() != *wrench_type_) {
    engine_->reject(Rejection::WrongType);
    return;
  }
  Input input;
  input.source = Source::Torque;
  input.frame = config_.torque_frame;
  std::string frame_id;
  if (isType<geometry_msgs::WrenchStamped>(m)) {
    decodeInto(m, buffer_, wrench_stamped_);
    input.stamp = stampOr(wrench_stamped_.header.stamp, record_);
    input.value = toEigen(wrench_stamped_.wrench.torque);
    frame_id = wrench_stamped_.header.frame_id;
  } else {
    decodeInto(m, buffer_, wrench_);
    input.stamp = toStamp(record_);
    input.value = toEigen(wrench_.torque);
  }
  const auto& p = config_.parameters;
  if (frame_id == p.body_frame || frame_id == p.fixed_frame) {
    input.frame = frame_id == p.body_frame ? TorqueFrame::Body : TorqueFrame::Fixed;
  } else if (!frame_id.empty() && input.value.allFinite()) {
    // A third frame: rotated into the body through the bag's static transforms.
    const auto q_B_frame = staticRotation(p.body_frame, frame_id);
    if (!q_B_frame) {
      engine_->reject(Rejection::NoTransform);
      return;
    }
    input.value = *q_B_frame * input.value;
    input.frame = TorqueFrame::Body;
  }
  submit(input);
}

void BagPropagator::onBias(const rosbag::MessageInstance& m) {
  decodeInto(m, buffer_, bias_msg_);
  const std::string& frame = bias_msg_.header.frame_id;
  const Eigen::Quaterniond* q_B = mountRotation(frame);
  if (!q_B) {
    engine_->rejectBias();
    return;
  }
  const Stamp stamp = stampOr(bias_msg_.header.stamp, record_);
  if (!o_.io_floor) engine_->submitBias(stamp, *q_B * toEigen(bias_msg_.vector));
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
  // Steps of at most half the engine's grid budget, so no grid stamp is ever deferred; a jump
  // longer than max_dt stays one tick (a gap, as the node treats a clock that jumps ahead).
  const auto& p = config_.parameters;
  const double budget = static_cast<double>(engine_->config().grid_budget);
  const auto step = static_cast<Stamp>(0.5 * budget / p.publish_rate * 1e9);
  if (last_tick_ && now > *last_tick_ && double(now - *last_tick_) * 1e-9 <= p.max_dt) {
    for (Stamp t = *last_tick_ + step; t < now; t += step) engine_->clockTick(t);
  }
  engine_->clockTick(now);
  last_tick_ = last_tick_ ? std::max(*last_tick_, now) : now;
}

const Eigen::Quaterniond* BagPropagator::mountRotation(const std::string& frame_id) {
  static const Eigen::Quaterniond kIdentity = Eigen::Quaterniond::Identity();
  if (frame_id.empty() || frame_id == config_.parameters.body_frame) return &kIdentity;
  auto it = mounts_.find(frame_id);
  if (it == mounts_.end()) {
    it = mounts_.emplace(frame_id, staticRotation(config_.parameters.body_frame, frame_id)).first;
  }
  if (!it->second) {
    engine_->reject(Rejection::NoTransform);
    return nullptr;
  }
  return &*it->second;
}

std::optional<Eigen::Quaterniond> BagPropagator::staticRotation(const std::string& target,
                                                                const std::string& source) {
  if (!static_tf_) {
    // The bag's static transforms, read once (a handful of messages).
    static_tf_ = std::make_unique<tf2::BufferCore>();
    if (topicType(bag_, o_.static_tf_topic)) {
      rosbag::View view(
          bag_,
          rosbag::TopicQuery(std::vector<std::string>{recordedName(bag_, o_.static_tf_topic)}));
      for (const rosbag::MessageInstance& m : view) {
        if (!isType<tf2_msgs::TFMessage>(m)) continue;
        tf2_msgs::TFMessage tf;
        decodeInto(m, buffer_, tf);
        for (const auto& t : tf.transforms) static_tf_->setTransform(t, "bag", true);
      }
    }
  }
  try {
    return rotationOf(static_tf_->lookupTransform(target, source, ros::Time(0))).normalized();
  } catch (const tf2::TransformException&) {
    std::fprintf(stderr,
                 "propagate_bag: no static transform %s -> %s in %s: its messages are "
                 "dropped\n",
                 target.c_str(), source.c_str(), o_.input.c_str());
    return std::nullopt;
  }
}

std::optional<std::string> BagPropagator::nothingUsable() const {
  const std::uint64_t accepted = o_.io_floor ? floor_accepted_ : engine_->counters().accepted;
  if (accepted == 0) return "no input accepted";
  if (states_ == 0) return "no state published (the clock never reached a grid stamp)";
  return std::nullopt;
}

void BagPropagator::summary(std::FILE* out, bool written) const {
  const EngineCounters& c = engine_->counters();
  std::string by_topic;
  for (const auto& [topic, n] : read_) {
    by_topic += (by_topic.empty() ? "" : ", ") + topic + " " + std::to_string(n);
  }
  std::string dropped;
  auto add = [&dropped](const char* name, std::uint64_t n) {
    if (n > 0)
      dropped += (dropped.empty() ? "" : ", ") + std::string(name) + " " + std::to_string(n);
  };
  add("stale", c.dropped_stale);
  add("future", c.rejected_future);
  add("reset", c.dropped_on_reset);
  add("non-finite", c.rejected_non_finite);
  add("out-of-range", c.rejected_out_of_range);
  add("no-rate", c.rejected_no_rate);
  add("type", c.rejected_type);
  add("covariance", c.rejected_covariance);
  add("no-tf", c.dropped_no_tf);
  add("no-time", c.dropped_no_time);
  add("bias", c.rejected_bias);
  const std::uint64_t accepted = o_.io_floor ? floor_accepted_ : c.accepted;
  std::fprintf(
      out,
      "propagate_bag: %llu messages (%s), %llu accepted, dropped: %s; %llu resets, "
      "%llu jumps back, %llu gaps, %llu late; %llu states -> %s; %.3f s wall, %.0f "
      "msg/s, %.0fx real time%s\n",
      static_cast<unsigned long long>(messages_), by_topic.c_str(),
      static_cast<unsigned long long>(accepted), dropped.empty() ? "none" : dropped.c_str(),
      static_cast<unsigned long long>(c.resets), static_cast<unsigned long long>(c.jumps_back),
      static_cast<unsigned long long>(c.gaps), static_cast<unsigned long long>(c.late),
      static_cast<unsigned long long>(states_), written ? o_.output.c_str() : "nothing written",
      wall_, wall_ > 0 ? double(messages_) / wall_ : 0.0, wall_ > 0 ? bag_seconds_ / wall_ : 0.0,
      o_.io_floor ? " (I/O floor: no propagation)" : "");
}

int run(int argc, char** argv) {
  catchInterrupts();
  const Options o = parseOptions(argc, argv);
  rosbag::Bag bag;
  openBag(bag, o.input);
  PendingFile output(o.output);  // destroyed last: the writer closes before it is removed
  BagPropagator propagator(o, bag);
  propagator.run(output.temporary());
  throwIfInterrupted();  // a signal after the last message: still no output
  if (const auto why = propagator.nothingUsable()) {
    propagator.summary(stdout, false);
    throw ToolError(o.input + ": " + *why + "; no output written", kExitNothingUsable);
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
