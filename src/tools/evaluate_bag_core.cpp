// evaluate_bag_core: every kinematic integrator, with each rate_samples choice, run over a bag's
// rate topic and compared with its truth attitude topic, in one pass over the bag. Prints the
// table and writes PREFIX.csv (one row per method) and PREFIX_series.csv (error against time,
// the largest per bin); nodes/evaluate_bag draws the charts from them.
//
// The pass: the first --calibration seconds of rates and truth are kept to align them (time
// offset, mount: alignment.h); then those rates and every later one go in batches to all the
// engines (one per method, each timed over the batch for its cost per sample), and each
// engine's states wait until the truth covers their stamps. Memory holds the calibration
// window, the batch, and the truth and states between the two streams' latest stamps.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <deque>
#include <iostream>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <geometry_msgs/TransformStamped.h>
#include <geometry_msgs/Twist.h>
#include <geometry_msgs/TwistStamped.h>
#include <nav_msgs/Odometry.h>
#include <sensor_msgs/Imu.h>
#include <tf2_msgs/TFMessage.h>

#include "alignment.h"
#include "attitude_propagator/engine.h"
#include "attitude_propagator/messages/conversions.h"
#include "attitude_propagator/messages/input_decoders.h"
#include "attitude_propagator/quaternion.h"
#include "tool_support.h"

namespace attitude_propagator {
namespace tools {
namespace {

const char* const kUsage =
    R"(usage: evaluate_bag_core IN.bag [IN2.bag ...] --rates TOPIC
                         (--truth TOPIC | --truth-tf PARENT CHILD) [options]

Runs every kinematic integrator with each rate_samples choice over the rate topic, compares
each with the truth attitude and reports, per method: largest and RMS attitude error, error
drift rate, relative rotation error over 1 s and 10 s, cost per sample, and a recommendation.
Several bags (the parts of `rosbag record --split`) are read as one stream merged by record
time, in whatever order they are given.

  --rates TOPIC        sensor_msgs/Imu, geometry_msgs/Twist or TwistStamped (default /imu/data_raw)
  --truth TOPIC        geometry_msgs/PoseStamped, PoseWithCovarianceStamped, TransformStamped
                       or nav_msgs/Odometry
  --truth-tf P C       the transform P -> C from tf2_msgs/TFMessage on --tf-topic (default /tf)
  --mount X Y Z W      q_ST, the truth body's orientation in the rate sensor's frame
                       (default: estimated from the data)
  --offset S           truth stamp minus rate stamp of the same instant, s (default: estimated)
  --max-offset S       offsets searched, +-S (default 0.5)
  --calibration S      seconds of truth used to estimate offset and mount (default 60)
  --truth-gap S        truth samples further apart are a gap: no comparison inside (default
                       2.5 truth periods)
  --integrators LIST   comma-separated (default euler,rk4,exp,exp2,cf4)
  --rate-samples LIST  comma-separated (default instantaneous,interval_average)
  --config FILE.yaml   node parameters shared by every method (e.g. stamp_filter, gyro_bias)
  --set name=value     one node parameter; repeatable
  --csv PREFIX         writes PREFIX.csv and PREFIX_series.csv (default IN.evaluation, after
                       the first input)
  --no-progress        no progress line
  --version            the package version

Times (--offset, --max-offset, --calibration, --truth-gap) are limited to +-2^32 s, the range
of ROS time. The offset search tries only offsets at which rates and truth overlap, on at most
about 5e7 / (calibration samples) points. Rate samples with a non-finite component, and truth
samples that are no rotation, are skipped and counted.

A method is scored when at least half of the samples it compared with the truth, and at least
100, were integrated from the sample before (not after a gap longer than max_dt or a reset);
only scored methods are recommended.

Exit codes:
  0    the table and both CSVs are complete, with a recommendation
  1    the bag could not be read (missing, truncated, damaged) or a CSV not written
  2    usage: bad options or parameters, an output that is an input, an input given twice
  3    the bag was read, but no method was scored (the report says why): no recommendation,
       no CSV written
  128+N  stopped by signal N (130: Ctrl-C); nothing written
)";

constexpr double kNs = 1e-9;
constexpr std::size_t kBatch = 512;
constexpr std::size_t kSeriesPoints = 2048;  // per method, before bins merge
const double kWindows[2] = {1.0, 10.0};      // relative rotation error windows, s
constexpr std::uint64_t kWindowStride = 4;
// Times given on the command line: at most the range of ROS time, so that a stamp plus an
// offset stays within a 64-bit count of nanoseconds (2 * 2^32 s < 9.2e9 s).
constexpr double kMaxSeconds = 4294967296.0;
// Scored (recommendable): at least this share of a method's compared samples, and at least
// kMinScored of them, integrated from the sample before.
constexpr double kMinScoredShare = 0.5;
constexpr std::uint64_t kMinScored = 100;

struct Options {
  std::vector<std::string> inputs;
  std::string input;  // the inputs, for messages
  std::string rates_topic = "/imu/data_raw";
  std::string truth_topic;
  std::string tf_topic = "/tf";
  std::string tf_parent, tf_child;
  std::optional<Eigen::Quaterniond> mount;
  std::optional<double> offset;
  double max_offset = 0.5;
  double calibration = 60.0;
  std::optional<double> truth_gap;
  std::vector<std::string> integrators = integratorNames(integratorsFor(Model::Kinematic));
  std::vector<std::string> rate_samples{"instantaneous", "interval_average"};
  std::string prefix;
  bool progress = true;
  Parameters parameters;
};

std::vector<std::string> splitList(const std::string& text) {
  std::vector<std::string> items;
  std::size_t start = 0;
  while (start <= text.size()) {
    const auto comma = text.find(',', start);
    const std::string item = text.substr(start, comma - start);
    if (!item.empty()) items.push_back(item);
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return items;
}

Options parseOptions(int argc, char** argv) {
  Options o;
  std::vector<std::string> configs, sets;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "-h" || a == "--help") {
      std::cout << kUsage;
      std::exit(0);
    } else if (a == "--version") {
      std::cout << "evaluate_bag (attitude_propagator) " << AP_VERSION << "\n";
      std::exit(0);
    } else if (a == "--rates") {
      o.rates_topic = optionValue(argc, argv, i);
    } else if (a == "--truth") {
      o.truth_topic = optionValue(argc, argv, i);
    } else if (a == "--truth-tf") {
      o.tf_parent = optionValue(argc, argv, i);
      o.tf_child = optionValue(argc, argv, i);
    } else if (a == "--tf-topic") {
      o.tf_topic = optionValue(argc, argv, i);
    } else if (a == "--mount") {
      double c[4];
      for (double& x : c) x = parseNumber(a, optionValue(argc, argv, i));
      const auto q = safeNormalized(Eigen::Quaterniond(c[3], c[0], c[1], c[2]));
      if (!q) throw UsageError("--mount: a zero quaternion");
      o.mount = *q;
    } else if (a == "--offset") {
      o.offset = parseNumber(a, optionValue(argc, argv, i), kMaxSeconds, "the range of ROS time");
    } else if (a == "--max-offset") {
      o.max_offset =
          parseNumber(a, optionValue(argc, argv, i), kMaxSeconds, "the range of ROS time");
    } else if (a == "--calibration") {
      o.calibration =
          parseNumber(a, optionValue(argc, argv, i), kMaxSeconds, "the range of ROS time");
    } else if (a == "--truth-gap") {
      o.truth_gap =
          parseNumber(a, optionValue(argc, argv, i), kMaxSeconds, "the range of ROS time");
    } else if (a == "--integrators") {
      o.integrators = splitList(optionValue(argc, argv, i));
    } else if (a == "--rate-samples") {
      o.rate_samples = splitList(optionValue(argc, argv, i));
    } else if (a == "--config") {
      configs.push_back(optionValue(argc, argv, i));
    } else if (a == "--set") {
      sets.push_back(optionValue(argc, argv, i));
    } else if (a == "--csv") {
      o.prefix = optionValue(argc, argv, i);
    } else if (a == "--no-progress") {
      o.progress = false;
    } else if (!a.empty() && a[0] == '-') {
      throw UsageError(a + ": unknown option (see --help)");
    } else {
      o.inputs.push_back(a);
      o.input += (o.input.empty() ? "" : ", ") + a;
    }
  }
  if (o.inputs.empty()) throw UsageError("no input bag (see --help)");
  if (o.truth_topic.empty() == o.tf_parent.empty()) {
    throw UsageError("give the truth as --truth TOPIC or --truth-tf PARENT CHILD (one of them)");
  }
  if (!(o.max_offset >= 0.0) || !(o.calibration > 0.0) || (o.truth_gap && !(*o.truth_gap > 0.0))) {
    throw UsageError("--max-offset must be >= 0, --calibration and --truth-gap > 0");
  }
  for (const auto& c : configs) loadConfigFile(c, o.parameters);
  for (const auto& s : sets) applySetting(s, o.parameters);
  // Each method's parameters refused now (std::invalid_argument: a usage error), not after
  // the bag is opened; a method named twice runs once.
  for (auto* list : {&o.integrators, &o.rate_samples}) {
    std::vector<std::string> unique;
    for (const auto& x : *list) {
      if (std::find(unique.begin(), unique.end(), x) == unique.end()) unique.push_back(x);
    }
    *list = unique;
  }
  for (const auto& samples : o.rate_samples) {
    for (const auto& integrator : o.integrators) {
      Parameters p = o.parameters;
      p.model = "kinematic";
      p.integrator = integrator;
      p.rate_samples = samples;
      validateParameters(p);
    }
  }
  if (o.prefix.empty()) {
    const std::string& first = o.inputs.front();
    const bool bag = first.size() > 4 && first.compare(first.size() - 4, 4, ".bag") == 0;
    o.prefix = (bag ? first.substr(0, first.size() - 4) : first) + ".evaluation";
  }
  std::vector<std::string> inputs = configs;
  inputs.insert(inputs.end(), o.inputs.begin(), o.inputs.end());
  for (const char* suffix : {".csv", "_series.csv"})
    refuseOutputOverInput(o.prefix + suffix, inputs);
  return o;
}

// ---------------------------------------------------------------------------------------------
// One method: an engine and its statistics
// ---------------------------------------------------------------------------------------------

struct RateSample {
  Stamp stamp;
  Eigen::Vector3d w;
};

struct TruthSample {
  Stamp stamp;
  Eigen::Quaterniond q;
};

/// The truth at a stamp: slerp between its neighbours, nothing inside a gap. The methods of
/// one reading ask for the same stamps one after the other, so results are kept in a small
/// direct-mapped table: the interpolation is done once per stamp, not once per method.
class TruthLookup {
 public:
  enum class Status { Wait, Outside, Gap, Ok };
  TruthLookup(const std::deque<TruthSample>& truth, double gap) : truth_(truth), gap_(gap) {}

  /// The truth at tau; Wait when the truth has not reached it yet (unless at the end).
  Status at(Stamp tau, bool at_end, Eigen::Quaterniond& q) {
    // Fibonacci hashing: stamps on a regular grid spread over all slots (tau % kSlots would
    // fold a 5 ms grid onto 64 of them).
    Slot& slot = slots_[(static_cast<std::uint64_t>(tau) * 0x9E3779B97F4A7C15ULL) >> (64 - kBits)];
    if (slot.tau == tau) {
      q = slot.q;
      return slot.status;
    }
    if (truth_.empty() || (!at_end && truth_.back().stamp < tau)) return Status::Wait;
    if (tau < truth_.front().stamp || tau > truth_.back().stamp) return Status::Outside;
    // Known from here on: later truth samples cannot change a stamp's neighbours.
    slot.tau = tau;
    slot.status = interpolate(tau, slot.q);
    q = slot.q;
    return slot.status;
  }

 private:
  static constexpr int kBits = 12;
  static constexpr std::size_t kSlots = std::size_t(1) << kBits;
  struct Slot {
    Stamp tau = std::numeric_limits<Stamp>::min();
    Status status = Status::Wait;
    Eigen::Quaterniond q;
  };

  Status interpolate(Stamp tau, Eigen::Quaterniond& q) const {
    const auto b = std::lower_bound(truth_.begin(), truth_.end(), tau,
                                    [](const TruthSample& s, Stamp t) { return s.stamp < t; });
    if (b->stamp == tau) {
      q = b->q;
      return Status::Ok;
    }
    const auto a = std::prev(b);
    const double h = double(b->stamp - a->stamp) * kNs;
    if (h > gap_) return Status::Gap;
    q = slerp(a->q, b->q, double(tau - a->stamp) * kNs / h);
    return Status::Ok;
  }

  const std::deque<TruthSample>& truth_;
  double gap_;
  std::vector<Slot> slots_ = std::vector<Slot>(kSlots);
};

/// A compared instant: the estimate mapped onto the truth (A q_WS q_ST) and the truth.
struct Compared {
  Stamp stamp;
  Eigen::Quaterniond estimate;
  Eigen::Quaterniond truth;
};

/// Error against time, bounded: the largest error per bin; bins double when full.
class BinnedSeries {
 public:
  void add(double t, double e) {
    if (count_ == 0 || e > bin_.second) bin_ = {t, e};
    if (++count_ == stride_) flush();
  }
  const std::vector<std::pair<double, double>>& points() {
    if (count_ > 0) flush();
    return points_;
  }

 private:
  void flush() {
    points_.push_back(bin_);
    count_ = 0;
    if (points_.size() < kSeriesPoints) return;
    std::vector<std::pair<double, double>> merged;
    for (std::size_t i = 0; i + 1 < points_.size(); i += 2) {
      merged.push_back(points_[i].second >= points_[i + 1].second ? points_[i] : points_[i + 1]);
    }
    points_.swap(merged);
    stride_ *= 2;
  }
  std::vector<std::pair<double, double>> points_;
  std::pair<double, double> bin_{0.0, 0.0};
  std::size_t count_ = 0;
  std::size_t stride_ = 1;
};

struct WindowStats {
  std::uint64_t n = 0;
  double sum_sq = 0.0;
  double max = 0.0;
  void add(double e) {
    ++n;
    sum_sq += e * e;
    max = std::max(max, e);
  }
  double rms() const { return n > 0 ? std::sqrt(sum_sq / double(n)) : std::nan(""); }
};

class Method : public EngineSink {
 public:
  Method(const std::string& integrator, const std::string& samples, Parameters p)
      : integrator_(integrator), samples_(samples) {
    p.model = "kinematic";
    p.integrator = integrator;
    p.rate_samples = samples;
    engine_ = std::make_unique<AttitudeEngine>(engineConfig(validateParameters(p)), *this);
  }

  std::string name() const { return integrator_ + "/" + samples_; }
  const std::string& integrator() const { return integrator_; }
  const std::string& samples() const { return samples_; }
  bool averaged() const { return samples_ == "interval_average"; }

  /// Feeds the batch (from the first sample the truth covers), timing the engine alone.
  void feed(const std::vector<RateSample>& batch, Stamp truth_start) {
    const auto start = std::chrono::steady_clock::now();
    Input input;
    std::size_t n = 0;
    for (const RateSample& s : batch) {
      if (!started_ && double(s.stamp - truth_start) * kNs + offset < 0.0) continue;
      started_ = true;
      input.stamp = s.stamp;
      input.value = s.w;
      engine_->submit(input);
      ++n;
    }
    fed_ += n;
    const double ns =
        std::chrono::duration<double, std::nano>(std::chrono::steady_clock::now() - start).count();
    if (n > 0) batch_costs_.push_back(static_cast<float>(ns / double(n)));
  }

  /// Compares the states the truth covers; at the end, every state left.
  void compare(TruthLookup& truth, bool at_end);
  /// The stamp (in the truth's time) of the oldest state still waiting, or nothing.
  std::optional<Stamp> oldestNeeded() const {
    if (pending_.empty()) return std::nullopt;
    return pending_.front().first + static_cast<Stamp>(std::llround(offset / kNs));
  }

  void publishState(const EngineState& s) override { pending_.emplace_back(s.stamp, s.q_WB); }
  void inputApplied(const Input&, const EngineState&) override {}
  void note(const EngineNote&) override {}

  double offset = 0.0;  ///< s, truth stamp minus rate stamp for this interpretation
  Eigen::Quaterniond mount = Eigen::Quaterniond::Identity();  ///< q_ST

  // Results
  std::uint64_t compared = 0, in_gap = 0, outside = 0;
  /// Compared samples integrated from the one before: those after a gap longer than max_dt or
  /// a reset only restart the integration (the state is held), so they do not score a method.
  std::uint64_t integrated() const {
    const EngineCounters& c = engine_->counters();
    const std::uint64_t restarts = c.gaps + c.resets + (fed_ > 0 ? 1 : 0);  // the first too
    return compared > restarts ? compared - restarts : 0;
  }
  bool scored() const {
    return integrated() >= kMinScored && double(integrated()) >= kMinScoredShare * double(compared);
  }
  double max_error = 0.0;
  /// The median over the batches of the time per sample: a batch during which the process
  /// was descheduled (the machine is shared) does not count.
  double costNs() const {
    if (batch_costs_.empty()) return 0.0;
    std::vector<float> c = batch_costs_;
    std::nth_element(c.begin(), c.begin() + c.size() / 2, c.end());
    return c[c.size() / 2];
  }
  double rms() const { return compared > 0 ? std::sqrt(sum_sq_ / double(compared)) : std::nan(""); }
  /// Least-squares slope of the error against time, rad/s.
  double drift() const {
    const double n = double(compared);
    const double d = n * stt_ - st_ * st_;
    return compared > 2 && d > 0.0 ? (n * ste_ - st_ * se_) / d : std::nan("");
  }
  const WindowStats& window(int i) const { return windows_[i]; }
  BinnedSeries series;
  const EngineCounters& counters() const { return engine_->counters(); }

 private:
  void record(Stamp stamp, const Eigen::Quaterniond& q_WS, const Eigen::Quaterniond& q_VT);
  void relativeErrors(const Compared& c);
  void trimRecent(const Compared& c);

  std::string integrator_, samples_;
  std::unique_ptr<AttitudeEngine> engine_;
  bool started_ = false;
  std::uint64_t fed_ = 0;
  std::vector<float> batch_costs_;                            // ns per sample, one per batch
  std::deque<std::pair<Stamp, Eigen::Quaterniond>> pending_;  // states awaiting the truth
  std::optional<Eigen::Quaterniond> align_;                   // A = q_VW
  std::optional<Stamp> t0_;
  double sum_sq_ = 0.0, st_ = 0.0, se_ = 0.0, stt_ = 0.0, ste_ = 0.0;
  std::deque<Compared> recent_;  // the last 10 s, for the relative errors
  std::size_t cursor_[2] = {0, 0};
  WindowStats windows_[2];
};

void Method::compare(TruthLookup& truth, bool at_end) {
  const Stamp shift = static_cast<Stamp>(std::llround(offset / kNs));
  Eigen::Quaterniond q_VT;
  while (!pending_.empty()) {
    const auto& [stamp, q_WS] = pending_.front();
    switch (truth.at(stamp + shift, at_end, q_VT)) {
      case TruthLookup::Status::Wait:
        return;
      case TruthLookup::Status::Outside:
        ++outside;
        break;
      case TruthLookup::Status::Gap:
        ++in_gap;
        break;
      case TruthLookup::Status::Ok:
        record(stamp, q_WS, q_VT);
        break;
    }
    pending_.pop_front();
  }
}

void Method::record(Stamp stamp, const Eigen::Quaterniond& q_WS, const Eigen::Quaterniond& q_VT) {
  // A from the first matched pair: q_VT = A q_WS q_ST there.
  if (!align_) align_ = (q_VT * mount.conjugate() * q_WS.conjugate()).normalized();
  if (!t0_) t0_ = stamp;
  const Compared c{stamp, *align_ * q_WS * mount, q_VT};
  const double e = rotationAngle(c.estimate, c.truth);
  const double t = double(stamp - *t0_) * kNs;
  ++compared;
  max_error = std::max(max_error, e);
  sum_sq_ += e * e;
  st_ += t, se_ += e, stt_ += t * t, ste_ += t * e;
  series.add(t, e);
  relativeErrors(c);
  trimRecent(c);
}

void Method::relativeErrors(const Compared& c) {
  recent_.push_back(c);
  // Windows end at every kWindowStride-th compared instant: thousands of windows still, at a
  // fraction of the cost.
  if (compared % kWindowStride != 0) return;
  for (int i = 0; i < 2; ++i) {
    // The compared instant closest to Delta before this one, from at or before it.
    const Stamp target = c.stamp - static_cast<Stamp>(kWindows[i] / kNs);
    std::size_t& k = cursor_[i];
    while (k + 1 < recent_.size() && recent_[k + 1].stamp <= target) ++k;
    const Compared& a = recent_[k];
    if (a.stamp > target || double(target - a.stamp) * kNs > 0.05 * kWindows[i]) continue;
    const Eigen::Quaterniond d_truth = a.truth.conjugate() * c.truth;
    const Eigen::Quaterniond d_estimate = a.estimate.conjugate() * c.estimate;
    windows_[i].add(rotationAngle(d_truth, d_estimate));
  }
}

void Method::trimRecent(const Compared& c) {
  // Keep one instant at or before the longest window's start.
  const Stamp oldest = c.stamp - static_cast<Stamp>(kWindows[1] / kNs);
  while (recent_.size() > 1 && recent_[1].stamp <= oldest) {
    recent_.pop_front();
    for (auto& k : cursor_) k = k > 0 ? k - 1 : 0;
  }
}

// ---------------------------------------------------------------------------------------------
// The evaluation
// ---------------------------------------------------------------------------------------------

class Evaluation {
 public:
  explicit Evaluation(const Options& o) : o_(o) {
    for (const auto& s : o.rate_samples) {
      for (const auto& i : o.integrators) {
        methods_.push_back(std::make_unique<Method>(i, s, o.parameters));
      }
    }
    if (methods_.empty()) throw UsageError("no method to run (--integrators, --rate-samples)");
  }

  void run(BagSet& bag);
  void report(std::FILE* out) const;
  void writeCsv(const std::string& summary_path, const std::string& series_path);
  /// Why no method can be recommended, or nothing.
  std::optional<std::string> noRecommendation() const;

 private:
  void checkTopics(BagSet& bag);
  void handle(const rosbag::MessageInstance& m);
  bool decodeRate(const rosbag::MessageInstance& m, RateSample& out);
  bool decodeTruth(const rosbag::MessageInstance& m, TruthSample& out);
  void addTruth(const TruthSample& s);
  void calibrate();
  void push(const RateSample& s);
  void flush(bool at_end);
  /// The recommended method (among the scored ones; see noRecommendation()).
  std::size_t recommended() const;
  /// One truth lookup per reading (the two readings look at different offsets).
  TruthLookup& lookup(const Method& m) {
    auto& l = m.averaged() ? lookup_averaged_ : lookup_instantaneous_;
    if (!l) l = std::make_unique<TruthLookup>(truth_, truth_gap_);
    return *l;
  }

  const Options& o_;
  std::vector<std::unique_ptr<Method>> methods_;
  std::string rates_topic_, truth_topic_, rates_type_, truth_type_;
  std::vector<std::uint8_t> buffer_;
  // Decoding, reused.
  sensor_msgs::Imu imu_;
  InputDecoders decoders_{DecoderFrames{}};  // body_twist's type; frames are not looked up
  geometry_msgs::PoseStamped pose_;
  geometry_msgs::PoseWithCovarianceStamped pose_cov_;
  geometry_msgs::TransformStamped transform_;
  nav_msgs::Odometry odometry_;
  tf2_msgs::TFMessage tf_;
  ros::Time record_;
  // Calibration window, then the stream.
  bool calibrating_ = true;
  std::vector<RateSample> calibration_rates_;
  std::deque<TruthSample> truth_;
  std::optional<Stamp> truth_start_;
  std::vector<RateSample> batch_;
  std::unique_ptr<TruthLookup> lookup_instantaneous_, lookup_averaged_;
  double truth_gap_ = 0.0;
  double rate_period_ = 0.0, truth_period_ = 0.0;
  double offset_instantaneous_ = 0.0;
  double offset_averaged_ = 0.0;
  OffsetEstimate offset_estimate_;
  std::string mount_note_;
  Eigen::Quaterniond mount_ = Eigen::Quaterniond::Identity();
  std::uint64_t rate_count_ = 0, truth_count_ = 0, truth_unordered_ = 0, before_truth_ = 0;
  std::uint64_t rate_non_finite_ = 0, truth_unusable_ = 0;
  Stamp first_rate_ = 0, last_rate_ = 0;
  double wall_ = 0.0;
};

void Evaluation::checkTopics(BagSet& bag) {
  rates_type_ = requireTopic(bag, o_.rates_topic, "rate",
                             {typeOf<sensor_msgs::Imu>(), typeOf<geometry_msgs::Twist>(),
                              typeOf<geometry_msgs::TwistStamped>()});
  rates_topic_ = o_.rates_topic;
  if (!o_.truth_topic.empty()) {
    truth_type_ = requireTopic(
        bag, o_.truth_topic, "truth",
        {typeOf<geometry_msgs::PoseStamped>(), typeOf<geometry_msgs::PoseWithCovarianceStamped>(),
         typeOf<geometry_msgs::TransformStamped>(), typeOf<nav_msgs::Odometry>()});
    truth_topic_ = o_.truth_topic;
  } else {
    truth_type_ = requireTopic(bag, o_.tf_topic, "tf", {typeOf<tf2_msgs::TFMessage>()});
    truth_topic_ = o_.tf_topic;
  }
  if (sameTopic(truth_topic_, rates_topic_))
    throw UsageError("the rate and truth topics are the same");
}

void Evaluation::run(BagSet& bag) {
  checkTopics(bag);
  for (const std::string& overlap : bag.overlaps({rates_topic_, truth_topic_})) {
    std::fprintf(stderr,
                 "evaluate_bag: %s of record time: their messages are interleaved by record "
                 "time\n",
                 overlap.c_str());
  }
  rosbag::View view;
  bag.addQuery(view, {rates_topic_, truth_topic_});
  Progress progress(view.size(), o_.progress);
  std::uint64_t done = 0;
  visitMessages(view, o_.input, progress, done, [this](const rosbag::MessageInstance& m) {
    record_ = m.getTime();
    handle(m);
  });
  if (calibrating_) calibrate();
  flush(true);
  progress.finish();
  wall_ = progress.elapsed();
  if (truth_count_ == 0) {
    throw ToolError("no truth: no transform " + o_.tf_parent + " -> " + o_.tf_child + " on " +
                    truth_topic_);
  }
}

void Evaluation::handle(const rosbag::MessageInstance& m) {
  if (sameTopic(m.getTopic(), rates_topic_)) {
    RateSample s;
    if (!decodeRate(m, s)) return;
    if (!s.w.allFinite()) {
      // Skipped like a lost sample: one NaN would otherwise reach the offset search's sums.
      ++rate_non_finite_;
      return;
    }
    if (rate_count_++ == 0) first_rate_ = s.stamp;
    last_rate_ = std::max(last_rate_, s.stamp);
    if (!calibrating_) return push(s);
    calibration_rates_.push_back(s);
    if (!truth_start_) {
      // Before any truth only the last max_offset (+1 s) of rates can still be compared.
      const Stamp keep = s.stamp - static_cast<Stamp>((o_.max_offset + 1.0) / kNs);
      const auto old = std::find_if(calibration_rates_.begin(), calibration_rates_.end(),
                                    [keep](const RateSample& r) { return r.stamp >= keep; });
      before_truth_ += static_cast<std::uint64_t>(old - calibration_rates_.begin());
      calibration_rates_.erase(calibration_rates_.begin(), old);
    }
    return;
  }
  TruthSample t;
  if (!decodeTruth(m, t)) return;
  addTruth(t);
  if (calibrating_ && double(t.stamp - *truth_start_) * kNs >= o_.calibration) calibrate();
}

bool Evaluation::decodeRate(const rosbag::MessageInstance& m, RateSample& out) {
  // The node's reading of a rate message in its own frame (the mount is this tool's to
  // estimate): REP-145's "no rate" and covariances that are not ones refused, the type of
  // body_twist's first message kept, a zero stamp taken as the record time.
  Decoded<Reading> read;
  if (isType<sensor_msgs::Imu>(m)) {
    decodeInto(m, buffer_, imu_);
    read = readImu(imu_, record_);
  } else {
    read = decoders_.readTwistTopic(m, record_);
  }
  if (!read) return false;
  out = {read->stamp, read->value};
  return true;
}

bool Evaluation::decodeTruth(const rosbag::MessageInstance& m, TruthSample& out) {
  if (isType<geometry_msgs::PoseStamped>(m)) {
    decodeInto(m, buffer_, pose_);
    out = {stampOr(pose_.header.stamp, record_), toEigen(pose_.pose.orientation)};
  } else if (isType<geometry_msgs::PoseWithCovarianceStamped>(m)) {
    decodeInto(m, buffer_, pose_cov_);
    out = {stampOr(pose_cov_.header.stamp, record_), toEigen(pose_cov_.pose.pose.orientation)};
  } else if (isType<geometry_msgs::TransformStamped>(m)) {
    decodeInto(m, buffer_, transform_);
    out = {stampOr(transform_.header.stamp, record_), rotationOf(transform_)};
  } else if (isType<nav_msgs::Odometry>(m)) {
    decodeInto(m, buffer_, odometry_);
    out = {stampOr(odometry_.header.stamp, record_), toEigen(odometry_.pose.pose.orientation)};
  } else {
    decodeInto(m, buffer_, tf_);
    const auto it =
        std::find_if(tf_.transforms.begin(), tf_.transforms.end(), [this](const auto& t) {
          return t.header.frame_id == o_.tf_parent && t.child_frame_id == o_.tf_child;
        });
    if (it == tf_.transforms.end()) return false;
    out = {stampOr(it->header.stamp, record_), rotationOf(*it)};
  }
  const auto q = safeNormalized(out.q);
  if (!q) {
    ++truth_unusable_;  // non-finite or zero: no rotation
    return false;
  }
  out.q = *q;
  return true;
}

void Evaluation::addTruth(const TruthSample& s) {
  if (!truth_.empty() && s.stamp <= truth_.back().stamp) {
    ++truth_unordered_;  // a repeated or older stamp: the truth must increase
    return;
  }
  ++truth_count_;
  if (!truth_start_) truth_start_ = s.stamp;
  truth_.push_back(s);
  // One hemisphere along the stream (q and -q are one rotation; differences stay short).
  if (truth_.size() > 1 && truth_[truth_.size() - 2].q.coeffs().dot(s.q.coeffs()) < 0.0) {
    truth_.back().q.coeffs() *= -1.0;
  }
  if (!calibrating_) {
    for (auto& method : methods_) method->compare(lookup(*method), false);
    // Drop the truth no waiting state needs (keep one sample before the oldest need).
    std::optional<Stamp> need;
    for (const auto& method : methods_) {
      if (const auto n = method->oldestNeeded()) need = need ? std::min(*need, *n) : *n;
    }
    // Rates not yet turned into states need the truth from their stamps on (a second of
    // margin for filtered stamps, which may precede the input's).
    const Stamp next_rate = batch_.empty() ? last_rate_ : batch_.front().stamp;
    double smallest_offset = 0.0;
    for (const auto& method : methods_) smallest_offset = std::min(smallest_offset, method->offset);
    const Stamp upcoming = next_rate + static_cast<Stamp>((smallest_offset - 1.0) / kNs);
    const Stamp keep = need ? std::min(*need, upcoming) : upcoming;
    while (truth_.size() > 2 && truth_[1].stamp <= keep) truth_.pop_front();
  }
}

void Evaluation::calibrate() {
  calibrating_ = false;
  if (truth_.size() < 3 || calibration_rates_.size() < 10) {
    throw ToolError("too little data to align: " + std::to_string(truth_.size()) +
                        " truth samples and " + std::to_string(calibration_rates_.size()) +
                        " rate samples overlap in the first " + std::to_string(o_.calibration) +
                        " s",
                    kExitNothingUsable);
  }
  // Seconds from the first truth stamp keep the calibration arithmetic precise.
  const Stamp base = truth_.front().stamp;
  std::vector<TimedAttitude> attitudes;
  std::vector<double> truth_times, rate_times;
  for (const auto& t : truth_) {
    attitudes.push_back({double(t.stamp - base) * kNs, t.q});
    truth_times.push_back(attitudes.back().t);
  }
  std::vector<TimedRate> gyro;
  for (const auto& r : calibration_rates_) {
    gyro.push_back({double(r.stamp - base) * kNs, r.w});
    rate_times.push_back(gyro.back().t);
  }
  truth_period_ = medianInterval(truth_times);
  rate_period_ = medianInterval(rate_times);
  truth_gap_ = o_.truth_gap ? *o_.truth_gap : 2.5 * truth_period_;
  const std::vector<TimedRate> truth_rates = differentiate(attitudes, truth_gap_);
  const RateTrack track(truth_rates, truth_gap_);
  std::optional<Eigen::Matrix3d> mount;
  if (o_.mount) mount = o_.mount->toRotationMatrix();
  if (o_.offset) {
    offset_estimate_ = {*o_.offset, true, "given"};
  } else {
    const double step = 0.5 * std::min(truth_period_, rate_period_);
    offset_estimate_ = estimateOffset(gyro, track, o_.max_offset, step, mount, throwIfInterrupted);
  }
  offset_instantaneous_ = offset_estimate_.offset;
  // A sample taken as the mean over the interval it closes stands for its middle, half a
  // period before its stamp: the estimated offset, found with samples at their stamps, moves
  // by that much for that reading. A given offset is the clocks' own and holds for both.
  offset_averaged_ = offset_instantaneous_ + (o_.offset ? 0.0 : 0.5 * rate_period_);
  // The mount relates the rate vectors, whichever instant a sample stands for: fitted with
  // the samples at their stamps and the offset found that way, it holds for both readings.
  if (o_.mount) {
    mount_ = *o_.mount;
    mount_note_ = "given";
  } else {
    double ratio = 0.0;
    mount_ = Eigen::Quaterniond(estimateMount(gyro, track, offset_instantaneous_, &ratio));
    mount_note_ = ratio < 1e-3 ? "estimated; the rates turn about one axis only, so the mount's "
                                 "rotation about it is not observable (closest to identity used)"
                               : "estimated from the rate directions (Wahba)";
  }
  for (auto& method : methods_) {
    method->mount = mount_;
    method->offset = method->averaged() ? offset_averaged_ : offset_instantaneous_;
  }
  for (const auto& r : calibration_rates_) push(r);
  calibration_rates_.clear();
  calibration_rates_.shrink_to_fit();
}

void Evaluation::push(const RateSample& s) {
  batch_.push_back(s);
  if (batch_.size() == kBatch) flush(false);
}

void Evaluation::flush(bool at_end) {
  for (auto& method : methods_) {
    method->feed(batch_, *truth_start_);
    method->compare(lookup(*method), at_end);
  }
  batch_.clear();
}

std::size_t Evaluation::recommended() const {
  // The cheapest scored method whose RMS error is within 10 % of the best one's: below that
  // the difference is not worth its cost on this data.
  double best = std::numeric_limits<double>::infinity();
  for (const auto& m : methods_) {
    if (m->scored()) best = std::min(best, m->rms());
  }
  std::size_t pick = 0;
  double cost = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < methods_.size(); ++i) {
    const Method& m = *methods_[i];
    if (m.scored() && m.rms() <= 1.1 * best && m.costNs() < cost) pick = i, cost = m.costNs();
  }
  return pick;
}

std::optional<std::string> Evaluation::noRecommendation() const {
  for (const auto& m : methods_) {
    if (m->scored()) return std::nullopt;
  }
  // Say it for the method that came closest.
  const Method* closest = methods_.front().get();
  for (const auto& m : methods_) {
    if (m->integrated() > closest->integrated()) closest = m.get();
  }
  const EngineCounters& c = closest->counters();
  return "no method was scored on enough of the truth (at least half of its compared samples, "
         "and at least " +
         std::to_string(kMinScored) + ", integrated from the sample before): " + closest->name() +
         " integrated " + std::to_string(closest->integrated()) + " of " +
         std::to_string(closest->compared) + " compared (" + std::to_string(c.gaps) +
         " gaps longer than max_dt, " + std::to_string(c.resets) + " resets; " +
         std::to_string(closest->in_gap) + " samples in truth gaps, " +
         std::to_string(closest->outside + before_truth_) + " outside the truth)";
}

void Evaluation::report(std::FILE* out) const {
  const double span = double(last_rate_ - first_rate_) * kNs;
  std::fprintf(out, "evaluate_bag: %s, %.1f s of rates\n", o_.input.c_str(), span);
  std::fprintf(out, "  rates %s (%s): %llu samples, %.1f Hz\n", rates_topic_.c_str(),
               rates_type_.c_str(), static_cast<unsigned long long>(rate_count_),
               rate_period_ > 0 ? 1.0 / rate_period_ : 0.0);
  std::fprintf(out, "  truth %s%s (%s): %llu samples, %.1f Hz; gaps above %.4g s are skipped%s\n",
               truth_topic_.c_str(),
               o_.tf_parent.empty() ? "" : (" " + o_.tf_parent + " -> " + o_.tf_child).c_str(),
               truth_type_.c_str(), static_cast<unsigned long long>(truth_count_),
               truth_period_ > 0 ? 1.0 / truth_period_ : 0.0, truth_gap_,
               truth_unordered_ > 0 ? (", " + std::to_string(truth_unordered_) +
                                       " out-of-order truth samples ignored")
                                          .c_str()
                                    : "");
  if (rate_non_finite_ > 0 || truth_unusable_ > 0) {
    std::fprintf(out,
                 "  skipped: %llu rate samples with a non-finite component, %llu truth samples "
                 "that are no rotation\n",
                 static_cast<unsigned long long>(rate_non_finite_),
                 static_cast<unsigned long long>(truth_unusable_));
  }
  std::fprintf(out,
               "  time offset (truth - rates): %+.4f ms as instantaneous, %+.4f ms as interval "
               "averages (%s)\n",
               offset_instantaneous_ * 1e3, offset_averaged_ * 1e3, offset_estimate_.how.c_str());
  const double mount_angle = 2.0 * std::atan2(mount_.vec().norm(), std::abs(mount_.w()));
  std::fprintf(out, "  mount q_ST [x y z w] = [%.6f %.6f %.6f %.6f] (%.3f deg; %s)\n", mount_.x(),
               mount_.y(), mount_.z(), mount_.w(), mount_angle * 180.0 / M_PI, mount_note_.c_str());
  const Method& first = *methods_.front();
  std::fprintf(out,
               "  compared per method: %llu; in truth gaps: %llu; outside the truth: %llu; "
               "before the truth: %llu\n",
               static_cast<unsigned long long>(first.compared),
               static_cast<unsigned long long>(first.in_gap),
               static_cast<unsigned long long>(first.outside),
               static_cast<unsigned long long>(before_truth_));
  std::fprintf(out, "\n  %-24s %10s %10s %11s %10s %10s %9s\n", "method", "max [rad]", "RMS [rad]",
               "drift[rad/s]", "RPE 1 s", "RPE 10 s", "ns/sample");
  const auto refused = noRecommendation();
  const std::size_t pick = recommended();
  for (std::size_t i = 0; i < methods_.size(); ++i) {
    const Method& m = *methods_[i];
    // "-": no value (a window longer than the data, nothing compared).
    auto cell = [](double x, int width) {
      char text[32];
      if (std::isnan(x)) {
        std::snprintf(text, sizeof text, "%*s", width, "-");
      } else {
        std::snprintf(text, sizeof text, "%*.3g", width, x);
      }
      return std::string(text);
    };
    std::fprintf(out, "  %-24s %s %s %s %s %s %9.1f%s\n", m.name().c_str(),
                 cell(m.max_error, 10).c_str(), cell(m.rms(), 10).c_str(),
                 cell(m.drift(), 11).c_str(), cell(m.window(0).rms(), 10).c_str(),
                 cell(m.window(1).rms(), 10).c_str(), m.costNs(),
                 !m.scored()             ? "  (not scored)"
                 : !refused && i == pick ? "  <- recommended"
                                         : "");
  }
  if (refused) {
    std::fprintf(out, "\n  no recommendation: %s\n  %.3f s wall for %llu messages\n",
                 refused->c_str(), wall_,
                 static_cast<unsigned long long>(rate_count_ + truth_count_));
    return;
  }
  const Method& r = *methods_[pick];
  std::fprintf(out,
               "\n  recommendation: integrator %s, rate_samples %s (the cheapest within 10 %% of "
               "the lowest RMS error)\n  %.3f s wall for %llu messages\n",
               r.integrator().c_str(), r.samples().c_str(), wall_,
               static_cast<unsigned long long>(rate_count_ + truth_count_));
}

void Evaluation::writeCsv(const std::string& summary_path, const std::string& series_path) {
  CsvFile summary(summary_path, o_.prefix + ".csv");
  std::fputs(
      "method,integrator,rate_samples,offset_s,compared,in_truth_gaps,outside_truth,"
      "max_error_rad,rms_error_rad,drift_rad_per_s,rpe_1s_rms_rad,rpe_1s_max_rad,"
      "rpe_10s_rms_rad,rpe_10s_max_rad,cost_ns_per_sample,recommended\n",
      summary.get());
  const std::size_t pick = recommended();
  for (std::size_t i = 0; i < methods_.size(); ++i) {
    const Method& m = *methods_[i];
    std::fprintf(
        summary.get(), "%s,%s,%s,%.9g,%llu,%llu,%llu,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.2f,%d\n",
        m.name().c_str(), m.integrator().c_str(), m.samples().c_str(), m.offset,
        static_cast<unsigned long long>(m.compared), static_cast<unsigned long long>(m.in_gap),
        static_cast<unsigned long long>(m.outside), m.max_error, m.rms(), m.drift(),
        m.window(0).rms(), m.window(0).max, m.window(1).rms(), m.window(1).max, m.costNs(),
        i == pick ? 1 : 0);
  }
  summary.close();
  CsvFile series(series_path, o_.prefix + "_series.csv");
  std::fputs("method,t_s,error_rad\n", series.get());
  for (auto& m : methods_) {
    for (const auto& [t, e] : m->series.points()) {
      std::fprintf(series.get(), "%s,%.6f,%.6g\n", m->name().c_str(), t, e);
      series.check();
    }
  }
  series.close();
}

int run(int argc, char** argv) {
  catchInterrupts();
  const Options o = parseOptions(argc, argv);
  BagSet bags(o.inputs);
  PendingFile summary(o.prefix + ".csv"), series(o.prefix + "_series.csv");
  Evaluation evaluation(o);
  // The CSVs: a row per method, and at most kSeriesPoints of about 48 bytes per method.
  requireFreeSpace(
      summary.path(),
      (o.integrators.size() * o.rate_samples.size()) * (kSeriesPoints * 48 + 512) + 4096);
  evaluation.run(bags);
  throwIfInterrupted();  // a signal during the last comparisons: still no output
  if (const auto why = evaluation.noRecommendation()) {
    evaluation.report(stdout);
    throw ToolError(o.input + ": no recommendation: " + *why + "; no CSV written",
                    kExitNothingUsable);
  }
  evaluation.writeCsv(summary.temporary(), series.temporary());
  summary.commit();
  series.commit();
  evaluation.report(stdout);
  std::printf("  wrote %s and %s\n", summary.path().c_str(), series.path().c_str());
  return 0;
}

}  // namespace
}  // namespace tools
}  // namespace attitude_propagator

int main(int argc, char** argv) {
  return attitude_propagator::tools::runTool("evaluate_bag", attitude_propagator::tools::run, argc,
                                             argv);
}
