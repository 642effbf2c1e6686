// evaluate_bag_core: every kinematic integrator, with each rate_samples choice, run over a bag's
// rate topic and compared with its truth attitude topic, in one pass over the bag. Prints the
// table and writes PREFIX.csv (one row per method) and PREFIX_series.csv (error against time,
// the largest per bin); nodes/evaluate_bag draws the charts from them.
//
// The pass: the first --calibration seconds of rates and truth are kept to align them (time
// offset, mount: alignment.h) and to set each method's rate_delay (the delay model:
// applyDelayModel); then those rates and every later one go in batches to all the engines (one
// per method, each timed over the batch for its cost per sample), and each truth sample waits
// until every method's states reach past its stamp, where they are interpolated to it. Memory
// holds the calibration window, the batch, and the truth and states between the two streams'
// latest stamps. With --fixes, each fix goes to every engine between the rates it was recorded
// between, as the node would receive it.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <deque>
#include <functional>
#include <iostream>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <tuple>
#include <vector>

#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/PoseWithCovarianceStamped.h>
#include <geometry_msgs/QuaternionStamped.h>
#include <geometry_msgs/TransformStamped.h>
#include <geometry_msgs/Twist.h>
#include <geometry_msgs/TwistStamped.h>
#include <nav_msgs/Odometry.h>
#include <sensor_msgs/Imu.h>
#include <sensor_msgs/MagneticField.h>
#include <tf2_msgs/TFMessage.h>

#include "aiding_summary.h"
#include "alignment.h"
#include "attitude_propagator/engine.h"
#include "attitude_propagator/messages/conversions.h"
#include "attitude_propagator/messages/fix_decoder.h"
#include "attitude_propagator/messages/input_decoders.h"
#include "attitude_propagator/messages/input_roles.h"
#include "attitude_propagator/messages/refusal_table.h"
#include "attitude_propagator/numerics/quaternion.h"
#include "bag_input.h"
#include "command_line.h"
#include "config_file.h"
#include "interrupts.h"
#include "output_files.h"
#include "progress.h"
#include "tool_error.h"

namespace attitude_propagator {
namespace tools {
namespace {

constexpr double kNs = 1e-9;
constexpr std::size_t kBatch = 512;
constexpr std::size_t kTimedChunk = 32;      // samples per timing of an engine
constexpr std::size_t kSeriesPoints = 2048;  // per method, before bins merge
// Relative rotation error windows shown in every report, s; the ranking's windows follow them
// (rankingWindows(): chosen from the data).
const double kShownWindows[2] = {1.0, 10.0};
constexpr std::uint64_t kWindowStride = 4;
// Times given on the command line: at most the range of ROS time, so that a stamp plus an
// offset stays within a 64-bit count of nanoseconds (2 * 2^32 s < 9.2e9 s).
constexpr double kMaxSeconds = 4294967296.0;
// Scored (recommendable): at least this share of a method's compared samples, and at least
// kMinScored of them, integrated from the sample before.
constexpr double kMinScoredShare = 0.5;
constexpr std::uint64_t kMinScored = 100;
// Costs closer than this (relative) count as equal, at least: twice the run-to-run spread of a
// method's cost per sample on a shared machine (measured: up to 25 % between runs under a load
// average of 24 on 2 cores, the ratios between methods within one run moving by 5 %), so that
// a ratio between two methods does not sit at the boundary. The kinematic methods cost within
// 1.3x of each other (the engine's per-sample work dominates): their order decides.
constexpr double kCostNoise = 0.5;
// A ranking window counts when at least this many windows were measured.
constexpr std::uint64_t kMinWindows = 10;
// Truth quaternions that are not unit: skipped and counted up to this share of the truth,
// refused beyond (a stray corrupt sample is not a wrong topic).
constexpr double kMaxNonUnitShare = 0.01;

struct Options {
  std::vector<std::string> inputs;
  std::string input;  // the inputs, for messages
  std::string rates_topic = "/imu/data_raw";
  std::string truth_topic;
  std::string fixes_topic;  // empty: no fixes
  std::string mag_topic;    // empty: /imu/mag with use_mag
  std::string tf_topic = "/tf";
  std::string tf_parent, tf_child;
  std::optional<Eigen::Quaterniond> mount;
  std::optional<double> offset;
  bool truth_clock_same = false;  // the truth's clock unknown unless the user states it
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

/// The command line as given, before it is checked and combined (parseOptions).
struct Given {
  Options o;
  std::vector<std::string> configs, sets;
};

/// The items with commas between them (a default list as --help shows it).
std::string joined(const std::vector<std::string>& items) {
  std::string text;
  for (const std::string& item : items) text += (text.empty() ? "" : ",") + item;
  return text;
}

/// A time option: seconds within the range of ROS time.
std::function<void(const std::string&)> seconds(const char* option, double& field) {
  return [option, &field](const std::string& v) {
    field = parseNumber(option, v, kMaxSeconds, "the range of ROS time");
  };
}

CommandLine commandLine(Given& g) {
  Options& o = g.o;
  auto to = [](std::string& field) { return [&field](const std::string& v) { field = v; }; };
  return {
      std::string("evaluate_bag (attitude_propagator) ") + AP_VERSION,
      20,
      {helpParagraph(R"(usage: evaluate_bag_core IN.bag [IN2.bag ...] --rates TOPIC
                         (--truth TOPIC | --truth-tf PARENT CHILD) [options]

Runs every kinematic integrator with each rate_samples choice over the rate topic, compares
each with the truth attitude at the truth's stamps (the method's states interpolated to them)
and reports, per method: largest and RMS attitude error, error drift rate, relative rotation
error over 1 s, 10 s and the ranking window, cost per sample, the rate_delay it ran with, and a
recommendation.
Several bags (the parts of `rosbag record --split`) are read as one stream merged by record
time, in whatever order they are given.

)"),
       valueOption("--rates", "TOPIC", typesText(InputRole::Rate) + "\n(default /imu/data_raw)",
                   to(o.rates_topic)),
       valueOption("--truth", "TOPIC",
                   "geometry_msgs/PoseStamped, PoseWithCovarianceStamped, TransformStamped,\n"
                   "sensor_msgs/Imu (its orientation; REP-145's \"none\" refused; may be the\n"
                   "rates' own topic: an IMU's AHRS) or nav_msgs/Odometry (with a warning:\n"
                   "odometry yaw is rarely a truth)",
                   to(o.truth_topic)),
       valuesOption("--truth-tf", "P C",
                    "the transform P -> C from tf2_msgs/TFMessage on --tf-topic (default /tf)",
                    [&o](const std::vector<std::string>& v) {
                      o.tf_parent = v[0];
                      o.tf_child = v[1];
                    }),
       valueOption("--fixes", "TOPIC",
                   "absolute attitude fixes (the node's orientation_fix types), given to every\n"
                   "method between the rates they were recorded between; the truth must be\n"
                   "another topic, in the fixes' fixed frame (no world alignment then)",
                   to(o.fixes_topic)),
       valueOption("--mag", "TOPIC",
                   "magnetometer (sensor_msgs/MagneticField, the node's imu/mag), given to\n"
                   "every method like the fixes, with use_mag (default /imu/mag); in the\n"
                   "rates' own frame, as the rates are read. With use_accel the rates' Imu\n"
                   "messages give the accelerometer, in their frame too",
                   to(o.mag_topic)),
       valuesOption("--mount", "X Y Z W",
                    "q_ST, the truth body's orientation in the rate sensor's frame\n"
                    "(default: estimated from the data)",
                    [&o](const std::vector<std::string>& v) {
                      double c[4];
                      for (int k = 0; k < 4; ++k) c[k] = parseNumber("--mount", v[k]);
                      const auto q = safeNormalized(Eigen::Quaterniond(c[3], c[0], c[1], c[2]));
                      if (!q) throw UsageError("--mount: a zero quaternion");
                      o.mount = *q;
                    }),
       valueOption("--truth-clock", "same|separate",
                   "separate (default): the truth's clock is unknown; the offset found is\n"
                   "the clocks' and holds any rate delay, which the data cannot tell apart\n"
                   "(none is estimated or recommended). same: your statement that the truth\n"
                   "is stamped at its instants on the rates' clock, so the offset found is\n"
                   "the rates' lag (an on-chip filter's group delay): estimated, recommended\n"
                   "as rate_delay, every method run with it and compared at offset 0. When\n"
                   "the data contradict it (a truth found later than the rates, or a lag\n"
                   "beyond max_dt), the run is compared as `separate`, says so, and exits 5",
                   [&o](const std::string& v) {
                     if (v != "same" && v != "separate") {
                       throw UsageError("--truth-clock: same or separate");
                     }
                     o.truth_clock_same = v == "same";
                   }),
       valueOption("--offset", "S",
                   "truth stamp minus rate stamp of the same instant, s (default:\n"
                   "estimated); every method compared at it, with the configured rate_delay",
                   [&o](const std::string& v) {
                     o.offset = parseNumber("--offset", v, kMaxSeconds, "the range of ROS time");
                   }),
       valueOption("--max-offset", "S", "offsets searched, +-S (default 0.5)",
                   seconds("--max-offset", o.max_offset)),
       valueOption("--calibration", "S",
                   "seconds of truth used to estimate offset and mount (default 60)",
                   seconds("--calibration", o.calibration)),
       valueOption("--truth-gap", "S",
                   "truth samples further apart are not differentiated across when\n"
                   "aligning (default 2.5 truth periods)",
                   [&o](const std::string& v) {
                     o.truth_gap =
                         parseNumber("--truth-gap", v, kMaxSeconds, "the range of ROS time");
                   }),
       valueOption("--integrators", "LIST",
                   "comma-separated (default " + joined(o.integrators) + ")",
                   [&o](const std::string& v) { o.integrators = splitList(v); }),
       valueOption("--rate-samples", "LIST",
                   "comma-separated (default instantaneous,interval_average)",
                   [&o](const std::string& v) { o.rate_samples = splitList(v); }),
       valueOption("--config", "FILE.yaml",
                   "node parameters shared by every method (e.g. stamp_filter, gyro_bias)",
                   [&g](const std::string& v) { g.configs.push_back(v); }),
       valueOption("--set", "name=value", "one node parameter; repeatable",
                   [&g](const std::string& v) { g.sets.push_back(v); }),
       valueOption("--csv", "PREFIX",
                   "writes PREFIX.csv and PREFIX_series.csv (default IN.evaluation, after\n"
                   "the first input)",
                   to(o.prefix)),
       flagOption("--no-progress", "no progress line", [&o] { o.progress = false; }),
       versionOption("the package version"),
       helpParagraph(R"(
Times (--offset, --max-offset, --calibration, --truth-gap) are limited to +-2^32 s, the range
of ROS time. The offset search tries only offsets at which rates and truth overlap, on at most
about 5e7 / (calibration samples) points. Rate samples with a non-finite component, and truth
samples that are no rotation, are skipped and counted.

The truth is refused (exit 4) when it has no orientation, when more than 1 % of its quaternions
are not unit, or when it turns more than twice as far as the rates, or less than half as far.

A method is scored when at least half of the truth samples its states meet, and at least 100,
are compared with states integrated one from the other (not across a gap longer than max_dt or
a reset; with --fixes, from the first state after the first applied fix); only scored methods
are recommended, ranked by their RMS relative error over the ranking window (from 10 periods of
the slower stream, doubling to 10 s: the shortest at which the smallest error is above what the
truth resolves): among those within 10 % of the lowest (or of the smallest error the truth
resolves), the cheapest, costs within the timing noise counting as equal, ties in the
integrator table's order, instantaneous first.

Exit codes:
  0    the table and both CSVs are complete, with a recommendation
  1    the bag could not be read (missing, truncated, damaged) or a CSV not written
  2    usage: bad options or parameters, an output that is an input, an input given twice
  3    the bag was read, but no method was scored (the report says why): no recommendation,
       no CSV written
  4    the truth cannot be one (no orientation, non-unit quaternions, a rotation the rates do
       not make; the message says which): no CSV written
  5    the table and both CSVs are complete, but --truth-clock same was contradicted by the
       data: compared as with the truth's clock unknown
  128+N  stopped by signal N (130: Ctrl-C); nothing written
)")}};
}

Options parseOptions(int argc, char** argv) {
  Given g;
  Options& o = g.o;
  o.inputs = parseCommandLine(commandLine(g), argc, argv);
  for (const std::string& input : o.inputs) o.input += (o.input.empty() ? "" : ", ") + input;
  std::vector<std::string>& configs = g.configs;
  std::vector<std::string>& sets = g.sets;
  if (o.inputs.empty()) throw UsageError("no input bag (see --help)");
  if (o.truth_topic.empty() == o.tf_parent.empty()) {
    throw UsageError("give the truth as --truth TOPIC or --truth-tf PARENT CHILD (one of them)");
  }
  if (!o.fixes_topic.empty()) {
    // Scored against the fixes themselves, a method would be scored on what it was given.
    const std::string truth = o.truth_topic.empty() ? o.tf_topic : o.truth_topic;
    if (sameTopic(o.fixes_topic, truth)) {
      throw UsageError("--fixes " + o.fixes_topic + " and the truth " + truth +
                       " are one topic: score against a truth the fixes are not");
    }
    if (sameTopic(o.fixes_topic, o.rates_topic)) {
      throw UsageError("--fixes " + o.fixes_topic + " and --rates " + o.rates_topic +
                       " are one topic");
    }
  }
  if (!(o.max_offset >= 0.0) || !(o.calibration > 0.0) || (o.truth_gap && !(*o.truth_gap > 0.0))) {
    throw UsageError("--max-offset must be >= 0, --calibration and --truth-gap > 0");
  }
  for (const auto& c : configs) loadConfigFile(c, o.parameters);
  for (const auto& s : sets) applySetting(s, o.parameters);
  if (o.mag_topic.empty()) o.mag_topic = "/imu/mag";
  if (o.parameters.use_mag && (sameTopic(o.mag_topic, o.rates_topic) ||
                               (!o.fixes_topic.empty() && sameTopic(o.mag_topic, o.fixes_topic)))) {
    throw UsageError("--mag " + o.mag_topic + ": the topic of another input");
  }
  // tf1's leading '/' in a frame parameter is read without it (frame_ids.h), with a warning.
  for (const auto& w : tf2FrameParameters(o.parameters)) {
    std::fprintf(stderr, "warning: %s\n", w.c_str());
  }
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
  return std::move(o);
}

// ---------------------------------------------------------------------------------------------
// One method: an engine and its statistics
// ---------------------------------------------------------------------------------------------

struct RateSample {
  Stamp stamp;
  Eigen::Vector3d w;
  std::uint64_t seq = 0;  ///< usable rate samples read before this one
  /// use_accel: the Imu's specific force in the rates' frame, at their stamp (none: REP-145)
  std::optional<BodyVector> f;
};

/// A decoded fix, or a magnetometer sample (`field` set), and where it was recorded in the rate
/// stream: after `after` usable rate samples (it goes to the engines before the rate sample
/// whose seq is `after`).
struct FixSample {
  std::uint64_t after;
  Fix fix;
  std::optional<BodyVector> field;
};

struct TruthSample {
  Stamp stamp;
  Eigen::Quaterniond q;
};

/// A compared instant (a truth stamp): the estimate mapped onto the truth (A q_WS q_ST) and the
/// truth.
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

/// One method: an engine, its states, and their comparison with the truth at the truth's own
/// stamps. The states (at the rate stamps, moved back by rate_delay) are interpolated to each
/// truth stamp (interpolateAttitude: degree 5 through the six states around it, from one
/// segment: a gap longer than max_dt or a reset starts a new one), so the truth is never
/// interpolated and its sample spacing adds no error of its own.
class Method : public EngineSink {
 public:
  Method(const std::string& integrator, const std::string& samples, Parameters p)
      : integrator_(integrator), samples_(samples), parameters_(std::move(p)) {
    parameters_.model = "kinematic";
    parameters_.integrator = integrator;
    parameters_.rate_samples = samples;
    validateParameters(parameters_);
  }

  std::string name() const { return integrator_ + "/" + samples_; }
  const std::string& integrator() const { return integrator_; }
  const std::string& samples() const { return samples_; }
  bool averaged() const { return samples_ == "interval_average"; }
  /// The fixed tie-break order: the integrator table's, instantaneous before interval_average.
  std::pair<int, int> order() const {
    return {static_cast<int>(integratorFromName(integrator_)), averaged() ? 1 : 0};
  }
  double configuredRateDelay() const { return parameters_.rate_delay; }
  const Parameters& parameters() const { return parameters_; }
  double maxDt() const { return parameters_.max_dt; }

  /// Creates the engine, with the rate_delay this method runs with (in [0, max_dt]) and the
  /// offset at which its states meet the truth (truth stamp minus the states' stamp).
  void start(double rate_delay, double compare_offset) {
    parameters_.rate_delay = rate_delay;
    offset = compare_offset;
    engine_ =
        std::make_unique<AttitudeEngine>(engineConfig(validateParameters(parameters_)), *this);
  }
  double rateDelay() const { return parameters_.rate_delay; }

  /// Feeds the batch (from a few samples before the truth's start), timing the engine alone;
  /// each fix (numbered from `fixes_base`) before the rate sample it was recorded before.
  void feed(const std::vector<RateSample>& batch, const std::deque<FixSample>& fixes,
            std::uint64_t fixes_base, Stamp truth_start, double lead) {
    Input input;
    const double shift = offset - parameters_.rate_delay;  // truth time - rate stamp
    auto first = batch.begin();
    while (!started_ && first != batch.end() &&
           double(first->stamp - truth_start) * kNs + shift < -lead) {
      ++first;
    }
    if (first != batch.end()) started_ = true;
    // Timed in chunks of kTimedChunk samples: many timings, so that those spoilt by the
    // machine's load are a minority whatever the bag's length.
    while (first != batch.end()) {
      const auto last =
          batch.end() - first > std::ptrdiff_t(kTimedChunk) ? first + kTimedChunk : batch.end();
      const auto start = std::chrono::steady_clock::now();
      for (auto s = first; s != last; ++s) {
        submitFixes(fixes, fixes_base, s->seq);
        input.stamp = s->stamp;
        input.value = s->w;
        engine_->submit(input);
        if (s->f) engine_->submitAcceleration(s->f->stamp, s->f->value_B, s->f->covariance_B);
      }
      const double ns =
          std::chrono::duration<double, std::nano>(std::chrono::steady_clock::now() - start)
              .count();
      const auto n = static_cast<std::size_t>(last - first);
      fed_ += n;
      if (n == kTimedChunk) chunk_costs_.push_back(static_cast<float>(ns / double(n)));
      first = last;
    }
    cost_.reset();
  }

  /// Submits the fixes recorded before the rate sample `seq` (all of them: the maximum).
  void submitFixes(const std::deque<FixSample>& fixes, std::uint64_t fixes_base,
                   std::uint64_t seq) {
    if (!engine_) return;
    for (; next_fix_ < fixes_base + fixes.size(); ++next_fix_) {
      const FixSample& f = fixes[next_fix_ - fixes_base];
      if (f.after > seq) return;
      if (f.field) {
        engine_->submitMagneticField(f.field->stamp, f.field->value_B, f.field->covariance_B);
      } else {
        engine_->submitFix(f.fix.stamp, f.fix.q_WB, f.fix.R_B);  // counted in fixes_*
      }
    }
  }
  /// The first fix (numbered from the stream's first) not yet submitted.
  std::uint64_t nextFix() const { return next_fix_; }
  std::size_t pendingFixes() const { return engine_ ? engine_->pendingFixes() : 0; }

  /// Compares the truth samples from the first not yet compared, as far as the states reach;
  /// at the end, every one left.
  void compare(const std::deque<TruthSample>& truth, bool at_end);
  /// The first truth stamp this method has not compared yet.
  Stamp nextTruth() const { return next_truth_; }

  void publishState(const EngineState& s) override {
    if (!states_.empty() && s.stamp <= states_.back().stamp) {
      // Stamps went back (a reset): the older states cannot be interpolated with these.
      states_.clear();
      ++segment_;
    } else if (!states_.empty() &&
               double(s.stamp - states_.back().stamp) * kNs > parameters_.max_dt) {
      ++segment_;
    }
    states_.push_back({s.stamp, s.q_WB, segment_});
    // With fixes the scores start at the first state published after a fix was applied.
    if (with_fixes && !score_from_ && engine_ && engine_->counters().fixes_accepted > 0) {
      score_from_ = s.stamp;
    }
  }
  void inputApplied(const Input&, const EngineState&) override {}
  void note(const EngineNote& n) override {
    // The state is held across a gap or starts again after a reset: a new segment.
    if (n.kind == EngineNote::Gap || n.kind == EngineNote::StampsJumpedBack ||
        n.kind == EngineNote::ClockJumpedBack) {
      ++segment_;
    }
  }

  double offset = 0.0;  ///< s, truth stamp minus the states' stamp
  Eigen::Quaterniond mount = Eigen::Quaterniond::Identity();  ///< q_ST
  /// A = q_VW from the first compared pair; off with fixes: they set the states' world, which
  /// the truth must share (an alignment would hide the fixes' error).
  bool align_world = true;

  // Results: truth samples compared, between two segments of states (a gap of the rates
  // longer than max_dt, or a reset), outside the states.
  std::uint64_t compared = 0, in_gap = 0, outside = 0;
  /// Scored: enough truth samples met states integrated one from the other (within one
  /// segment), not across a gap longer than max_dt or a reset.
  bool scored() const {
    return compared >= kMinScored &&
           double(compared) >= kMinScoredShare * double(compared + in_gap);
  }
  double max_error = 0.0;
  /// The lower quartile over the timed chunks of the time per sample: the machine's load
  /// (other processes, descheduling) only ever adds time, so the lower quartile is what the
  /// method costs, steadier from run to run than the median.
  double costNs() const {
    if (!cost_) {
      std::vector<float> c = chunk_costs_;
      if (c.empty()) return 0.0;
      std::nth_element(c.begin(), c.begin() + c.size() / 4, c.end());
      cost_ = c[c.size() / 4];
    }
    return *cost_;
  }
  double rms() const { return compared > 0 ? std::sqrt(sum_sq_ / double(compared)) : std::nan(""); }
  /// Least-squares slope of the error against time, rad/s.
  double drift() const {
    const double n = double(compared);
    const double d = n * stt_ - st_ * st_;
    return compared > 2 && d > 0.0 ? (n * ste_ - st_ * se_) / d : std::nan("");
  }
  /// The white part of the residual between this method and the truth, rad (RMS angle):
  /// from the second differences of the residual rotation vectors at consecutive truth
  /// samples, sqrt(mean |r_i - 2 r_(i-1) + r_(i-2)|^2 / 6). A smooth error (the method's)
  /// barely enters; the truth's own noise, and the jitter of its stamps, do. NaN: too few.
  double whiteResidual() const {
    return d2_count_ >= 10 ? std::sqrt(d2_sum_ / double(d2_count_) / 6.0) : std::nan("");
  }
  /// The relative error windows: first kShownWindows, then the ranking's (s); the truth's
  /// period (a window's start may be off its length by about half of it); the step the turned
  /// angles are summed over (s).
  void setWindows(std::vector<double> windows, double truth_period, double turn_step) {
    turn_step_ = turn_step;
    window_lengths_ = std::move(windows);
    windows_.assign(window_lengths_.size(), WindowStats{});
    cursor_.assign(window_lengths_.size(), 0);
    truth_period_ = truth_period;
  }
  const WindowStats& window(std::size_t i) const { return windows_[i]; }
  /// rad: the angles the truth and this method's states (mapped onto the truth) turn through,
  /// summed over steps of about turn_step between compared instants (not across gaps): the
  /// paths they turn along, seen at the shortest ranking window.
  double truth_turn = 0.0, estimate_turn = 0.0;
  /// With fixes: truth samples before the states the first applied fix corrected (not scored).
  std::uint64_t before_fix = 0;
  bool with_fixes = false;
  BinnedSeries series;
  const EngineCounters& counters() const { return engine_->counters(); }
  bool started() const { return engine_ != nullptr; }

 private:
  struct State {
    Stamp stamp;
    Eigen::Quaterniond q;
    std::uint64_t segment;
  };
  enum class Found { Wait, Outside, Gap, Ok };
  /// The state interpolated to `stamp` (the states' time).
  Found stateAt(Stamp stamp, bool at_end, Eigen::Quaterniond& q);
  void record(Stamp stamp, const Eigen::Quaterniond& q_WS, const Eigen::Quaterniond& q_VT);
  void relativeErrors(const Compared& c);
  void trimRecent(const Compared& c);

  std::string integrator_, samples_;
  Parameters parameters_;
  std::unique_ptr<AttitudeEngine> engine_;
  bool started_ = false;
  std::uint64_t fed_ = 0;
  std::uint64_t next_fix_ = 0;
  std::vector<float> chunk_costs_;  // ns per sample, one per timed chunk
  mutable std::optional<double> cost_;
  std::deque<State> states_;  // states the truth may still need
  std::uint64_t segment_ = 0;
  Stamp next_truth_ = std::numeric_limits<Stamp>::min();
  std::optional<Eigen::Quaterniond> align_;  // A = q_VW
  std::optional<Stamp> t0_;
  double sum_sq_ = 0.0, st_ = 0.0, se_ = 0.0, stt_ = 0.0, ste_ = 0.0;
  std::deque<Compared> recent_;  // the longest window, for the relative errors
  std::vector<double> window_lengths_;
  std::vector<std::size_t> cursor_;
  std::vector<WindowStats> windows_;
  double truth_period_ = 0.0;
  double turn_step_ = 1.0;
  std::optional<Compared> turn_anchor_;
  std::optional<Stamp> score_from_;  // with fixes: the first state after the first applied fix
  // Residual rotation vectors of the last two consecutive compared truth samples.
  std::vector<Eigen::Vector3d> residuals_;
  double d2_sum_ = 0.0;
  std::uint64_t d2_count_ = 0;
};

Method::Found Method::stateAt(Stamp stamp, bool at_end, Eigen::Quaterniond& q) {
  if (states_.empty()) return at_end ? Found::Outside : Found::Wait;
  const auto after = std::upper_bound(states_.begin(), states_.end(), stamp,
                                      [](Stamp t, const State& s) { return t < s.stamp; });
  if (after == states_.begin()) return Found::Outside;  // before the first state
  const std::size_t k = static_cast<std::size_t>(after - states_.begin()) - 1;
  const std::size_t n = states_.size();
  const std::uint64_t segment = states_[k].segment;
  // Up to three states after k in its segment; fewer only when the segment has ended.
  std::size_t hi = k;
  while (hi + 1 < n && hi - k < 3 && states_[hi + 1].segment == segment) ++hi;
  const bool ended = hi + 1 < n || at_end;
  if (hi - k < 3 && !ended) return Found::Wait;
  if (hi == k && states_[k].stamp != stamp) return hi + 1 < n ? Found::Gap : Found::Outside;
  // Two states before k, more when fewer follow: six nodes where the segment has them.
  std::size_t lo = k;
  while (lo > 0 && k - lo < 2 && states_[lo - 1].segment == segment) --lo;
  while (lo > 0 && hi - lo + 1 < kInterpolationNodes && states_[lo - 1].segment == segment) --lo;
  const std::size_t count = hi - lo + 1;
  // A segment of one state is a restart alone (the state held): nothing integrated to compare.
  if (count < 2) return Found::Gap;
  TimedAttitude nodes[kInterpolationNodes];
  for (std::size_t i = 0; i < count; ++i) {
    nodes[i] = {double(states_[lo + i].stamp - stamp) * kNs, states_[lo + i].q};
  }
  q = interpolateAttitude(nodes, count, 0.0);
  // Later truth stamps are later: the states before k - 5 are not needed again.
  const std::size_t keep_from = k > kInterpolationNodes ? k - kInterpolationNodes : 0;
  states_.erase(states_.begin(), states_.begin() + static_cast<std::ptrdiff_t>(keep_from));
  return Found::Ok;
}

void Method::compare(const std::deque<TruthSample>& truth, bool at_end) {
  if (!engine_) return;
  const Stamp shift = static_cast<Stamp>(std::llround(offset / kNs));
  auto it = std::lower_bound(truth.begin(), truth.end(), next_truth_,
                             [](const TruthSample& s, Stamp t) { return s.stamp < t; });
  Eigen::Quaterniond q_WS;
  for (; it != truth.end(); ++it) {
    const Found found = stateAt(it->stamp - shift, at_end, q_WS);
    if (found == Found::Wait) return;
    next_truth_ = it->stamp + 1;
    if (found == Found::Ok && with_fixes && (!score_from_ || it->stamp - shift < *score_from_)) {
      ++before_fix;  // the start-up, before any fix was applied: not the fused output
      residuals_.clear();
      turn_anchor_.reset();
      continue;
    }
    if (found == Found::Ok) {
      record(it->stamp, q_WS, it->q);
      continue;
    }
    ++(found == Found::Gap ? in_gap : outside);
    residuals_.clear();  // the next residual does not follow on from the last
    turn_anchor_.reset();
  }
}

void Method::record(Stamp stamp, const Eigen::Quaterniond& q_WS, const Eigen::Quaterniond& q_VT) {
  // A from the first matched pair: q_VT = A q_WS q_ST there.
  if (!align_) {
    align_ = align_world ? (q_VT * mount.conjugate() * q_WS.conjugate()).normalized()
                         : Eigen::Quaterniond::Identity();
  }
  if (!t0_) t0_ = stamp;
  const Compared c{stamp, *align_ * q_WS * mount, q_VT};
  const double e = rotationAngle(c.estimate, c.truth);
  const double t = double(stamp - *t0_) * kNs;
  ++compared;
  max_error = std::max(max_error, e);
  sum_sq_ += e * e;
  st_ += t, se_ += e, stt_ += t * t, ste_ += t * e;
  series.add(t, e);
  residuals_.push_back(logMap(c.truth.conjugate() * c.estimate));
  if (residuals_.size() == 3) {
    d2_sum_ += (residuals_[2] - 2.0 * residuals_[1] + residuals_[0]).squaredNorm();
    ++d2_count_;
    residuals_.erase(residuals_.begin());
  }
  if (!turn_anchor_) {
    turn_anchor_ = c;
  } else if (double(stamp - turn_anchor_->stamp) * kNs >= turn_step_) {
    truth_turn += rotationAngle(turn_anchor_->truth, c.truth);
    estimate_turn += rotationAngle(turn_anchor_->estimate, c.estimate);
    turn_anchor_ = c;
  }
  relativeErrors(c);
  trimRecent(c);
}

void Method::relativeErrors(const Compared& c) {
  recent_.push_back(c);
  // Windows end at every kWindowStride-th compared instant: thousands of windows still, at a
  // fraction of the cost.
  if (compared % kWindowStride != 0) return;
  for (std::size_t i = 0; i < window_lengths_.size(); ++i) {
    // The compared instant closest to Delta before this one, from at or before it: within
    // 5 % of Delta, or of half a truth period more than that (short windows of a slow truth).
    const double length = window_lengths_[i];
    const Stamp target = c.stamp - static_cast<Stamp>(length / kNs);
    std::size_t& k = cursor_[i];
    while (k + 1 < recent_.size() && recent_[k + 1].stamp <= target) ++k;
    const Compared& a = recent_[k];
    const double tolerance = std::max(0.05 * length, 0.55 * truth_period_);
    if (a.stamp > target || double(target - a.stamp) * kNs > tolerance) continue;
    const Eigen::Quaterniond d_truth = a.truth.conjugate() * c.truth;
    const Eigen::Quaterniond d_estimate = a.estimate.conjugate() * c.estimate;
    windows_[i].add(rotationAngle(d_truth, d_estimate));
  }
}

void Method::trimRecent(const Compared& c) {
  // Keep one instant at or before the longest window's start.
  const double longest = *std::max_element(window_lengths_.begin(), window_lengths_.end());
  const Stamp oldest = c.stamp - static_cast<Stamp>(longest / kNs);
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
    if (!o.fixes_topic.empty()) {
      // The frames are the methods' (they differ in integrator and rate_samples only).
      fix_decoder_.emplace(FixFrames::of(validateParameters(methods_.front()->parameters())));
      for (auto& m : methods_) {
        m->align_world = false;
        m->with_fixes = true;
      }
    }
  }

  void run(BagSet& bag);
  void report(std::FILE* out) const;
  void writeCsv(const std::string& summary_path, const std::string& series_path);
  /// Why no method can be recommended, or nothing.
  std::optional<std::string> noRecommendation() const;
  /// --truth-clock same was given and the data contradict it (compared as separate clocks).
  bool clockContradicted() const { return clock_contradicted_; }

 private:
  void checkTopics(BagSet& bag);
  void handle(const rosbag::MessageInstance& m);
  bool decodeRate(const rosbag::MessageInstance& m, RateSample& out);
  bool decodeTruth(const rosbag::MessageInstance& m, TruthSample& out);
  /// A fix by the node's rules (FixDecoder), kept for the engines; no tf here, as for the
  /// rates: only fixed_frame and body_frame (the rate sensor's frame) are known.
  void addFix(const rosbag::MessageInstance& m);
  /// use_mag: a field sample read in its own frame (taken as the rates'), queued as a fix is.
  void addMag(const rosbag::MessageInstance& m);
  /// use_accel, use_mag: per method, the accel_* and mag_* counters.
  void reportAiding(std::FILE* out) const;
  /// The fixes' line of the report.
  void reportFixes(std::FILE* out) const;
  void addTruth(const TruthSample& s);
  void handleRate(const rosbag::MessageInstance& m);
  void keepForCalibration(const RateSample& s);
  void handleTruth(const rosbag::MessageInstance& m);
  /// Refuses a truth that cannot be one (ToolError, kExitTruthRefused): no sample a rotation,
  /// non-unit quaternions, REP-145's "no orientation", or a turn the rates do not make.
  void checkTruthSamples() const;
  void checkTruthTurn() const;
  void calibrate();
  void push(const RateSample& s);
  void flush(bool at_end);
  /// Each method's rate_delay and comparison offset, from the offset and the delay model.
  void applyDelayModel();
  /// The recommended method (among the scored ones; see noRecommendation()).
  std::size_t recommended() const;
  /// The RMS relative error of `m` over ranking window `w` (NaN: fewer than kMinWindows).
  double rankingError(const Method& m, std::size_t w) const;
  /// True when a scored method's error over the ranking window was measured (at least
  /// kMinWindows windows); otherwise the methods are ranked by their whole-run RMS error.
  bool rankedByWindow() const {
    return std::any_of(methods_.begin(), methods_.end(), [this](const auto& m) {
      return m->scored() && !std::isnan(rankingError(*m, rank_window_));
    });
  }
  /// The ranking window, s (0 before the calibration).
  double rankingWindow() const {
    return ranking_windows_.empty() ? 0.0 : ranking_windows_[rank_window_];
  }
  /// The smallest RMS error the truth resolves: twice the white part of the residuals (the
  /// smallest among the scored methods: the truth's noise), and never below the round-off
  /// floor 10 eps sqrt(N). Errors below it cannot be told apart.
  double resolutionFloor() const;
  /// Costs closer than this (relative) count as equal: the larger of kCostNoise and the median
  /// over the integrators of the difference between their two readings (about the same work
  /// per sample: the difference is timing noise).
  double costTolerance() const;

  const Options& o_;
  std::vector<std::unique_ptr<Method>> methods_;
  std::string rates_topic_, truth_topic_, rates_type_, truth_type_, fixes_topic_, fixes_type_;
  std::string mag_topic_;  // empty: not read
  sensor_msgs::MagneticField mag_;
  std::uint64_t mag_count_ = 0, accel_count_ = 0;
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
  // Fixes: decoded once, kept until every method has had them (numbered from fixes_base_).
  std::optional<FixDecoder> fix_decoder_;
  std::deque<FixSample> fixes_;
  std::uint64_t fixes_base_ = 0, fix_count_ = 0;
  // Calibration window, then the stream.
  bool calibrating_ = true;
  std::vector<RateSample> calibration_rates_;
  std::deque<TruthSample> truth_;
  std::optional<Stamp> truth_start_;
  std::vector<RateSample> batch_;
  double truth_gap_ = 0.0;
  double rate_period_ = 0.0, truth_period_ = 0.0;
  OffsetEstimate offset_estimate_;
  // The delay model: with one clock (--truth-clock same) the offset found with the samples at
  // their stamps is minus the rates' lag, total_delay_; otherwise it is the clocks' offset.
  bool delay_estimated_ = false;
  double total_delay_ = 0.0;
  std::string delay_note_;
  std::string mount_note_;
  Eigen::Quaterniond mount_ = Eigen::Quaterniond::Identity();
  std::uint64_t rate_count_ = 0, truth_count_ = 0, truth_unordered_ = 0, before_truth_ = 0;
  std::uint64_t rate_non_finite_ = 0, truth_unusable_ = 0, truth_non_unit_ = 0;
  std::uint64_t truth_no_orientation_ = 0;
  IntervalStats intervals_;  // between consecutive usable rate samples
  std::vector<double> ranking_windows_;
  std::size_t rank_window_ = 0;      // in ranking_windows_, chosen after the run
  bool clock_contradicted_ = false;  // --truth-clock same, and the data say otherwise
  Stamp first_rate_ = 0, last_rate_ = 0;
  double wall_ = 0.0;
};

void Evaluation::checkTopics(BagSet& bag) {
  rates_type_ = requireTopic(bag, o_.rates_topic, "rate", typesOf(InputRole::Rate));
  rates_topic_ = o_.rates_topic;
  if (!o_.truth_topic.empty()) {
    truth_type_ = requireTopic(
        bag, o_.truth_topic, "truth",
        {typeOf<geometry_msgs::PoseStamped>(), typeOf<geometry_msgs::PoseWithCovarianceStamped>(),
         typeOf<geometry_msgs::TransformStamped>(), typeOf<nav_msgs::Odometry>(),
         typeOf<sensor_msgs::Imu>()});
    truth_topic_ = o_.truth_topic;
    if (truth_type_ == typeOf<nav_msgs::Odometry>().first) {
      std::fprintf(stderr,
                   "evaluate_bag: warning: the truth %s is odometry: its orientation is rarely a "
                   "truth (a wheeled robot's yaw from its wheels slips and skids); it is checked "
                   "against the rates before use\n",
                   truth_topic_.c_str());
    }
  } else {
    truth_type_ = requireTopic(bag, o_.tf_topic, "tf", {typeOf<tf2_msgs::TFMessage>()});
    truth_topic_ = o_.tf_topic;
  }
  // One Imu topic may carry both: the gyro's rates and the orientation of the IMU's own
  // estimator (an AHRS), the one absolute reference most recordings have.
  if (sameTopic(truth_topic_, rates_topic_) &&
      !(truth_type_ == typeOf<sensor_msgs::Imu>().first && rates_type_ == truth_type_))
    throw UsageError("the rate and truth topics are the same");
  if (o_.parameters.use_mag) {
    requireTopic(bag, o_.mag_topic, "magnetometer", inputRoleOf(InputRole::Field).types);
    mag_topic_ = o_.mag_topic;
  }
  if (!o_.fixes_topic.empty()) {
    fixes_type_ = requireTopic(bag, o_.fixes_topic, "fix", inputRoleOf(InputRole::Fix).types);
    fixes_topic_ = o_.fixes_topic;
  }
}

void Evaluation::run(BagSet& bag) {
  checkTopics(bag);
  std::vector<std::string> topics{rates_topic_, truth_topic_};
  if (!fixes_topic_.empty()) topics.push_back(fixes_topic_);
  if (!mag_topic_.empty()) topics.push_back(mag_topic_);
  for (const std::string& overlap : bag.overlaps(topics)) {
    std::fprintf(stderr,
                 "evaluate_bag: %s of record time: their messages are interleaved by record "
                 "time\n",
                 overlap.c_str());
  }
  rosbag::View view;
  bag.addQuery(view, topics);
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
  checkTruthSamples();
  if (truth_count_ == 0) {
    throw ToolError("no truth: no transform " + o_.tf_parent + " -> " + o_.tf_child + " on " +
                    truth_topic_);
  }
  checkTruthTurn();
  // The ranking's window: where the scored methods' relative errors differ most.
  std::vector<std::vector<double>> rpe(ranking_windows_.size());
  for (std::size_t w = 0; w < ranking_windows_.size(); ++w) {
    for (const auto& m : methods_) {
      if (m->scored()) rpe[w].push_back(rankingError(*m, w));
    }
  }
  rank_window_ = chooseRankingWindow(rpe, resolutionFloor());
}

double Evaluation::rankingError(const Method& m, std::size_t w) const {
  const WindowStats& s = m.window(std::size(kShownWindows) + w);
  // Too few windows to say anything: not measured.
  return s.n >= kMinWindows ? s.rms() : std::nan("");
}

void Evaluation::checkTruthSamples() const {
  const std::uint64_t seen =
      truth_count_ + truth_unordered_ + truth_unusable_ + truth_non_unit_ + truth_no_orientation_;
  char text[512];
  const char* what = truth_topic_.c_str();
  if (truth_count_ == 0 && truth_no_orientation_ > 0 && truth_unusable_ + truth_non_unit_ == 0) {
    std::snprintf(text, sizeof text,
                  "the truth %s has no orientation: its %llu messages say so (REP-145: "
                  "orientation_covariance[0] = -1)",
                  what, static_cast<unsigned long long>(truth_no_orientation_));
    throw ToolError(text, kExitTruthRefused);
  }
  if (truth_count_ == 0 && truth_unusable_ > 0 && truth_non_unit_ == 0) {
    std::snprintf(text, sizeof text,
                  "the truth %s has no orientation: all %llu of its quaternions are zero or "
                  "non-finite, no rotation",
                  what, static_cast<unsigned long long>(truth_unusable_));
    throw ToolError(text, kExitTruthRefused);
  }
  if (truth_non_unit_ > 0 && double(truth_non_unit_) > kMaxNonUnitShare * double(seen)) {
    std::snprintf(text, sizeof text,
                  "the truth %s is no attitude: %llu of its %llu quaternions are not unit (norm "
                  "off 1 by more than %.0e; a truth's are)",
                  what, static_cast<unsigned long long>(truth_non_unit_),
                  static_cast<unsigned long long>(seen), kUnitTolerance);
    throw ToolError(text, kExitTruthRefused);
  }
}

void Evaluation::checkTruthTurn() const {
  // The method with the most compared samples: every method integrates the same rates, and
  // the angles they turn through differ by their errors only.
  const Method* most = methods_.front().get();
  for (const auto& m : methods_) {
    if (m->compared > most->compared) most = m.get();
  }
  char seconds[32];
  std::snprintf(seconds, sizeof seconds, "%.3g",
                ranking_windows_.empty() ? 0.0 : ranking_windows_.front());
  if (const auto why = turnMismatch(most->truth_turn, most->estimate_turn)) {
    throw ToolError("the truth " + truth_topic_ + " is no truth of the rates " + rates_topic_ +
                        ": " + *why + " (summed over steps of " + seconds + " s)",
                    kExitTruthRefused);
  }
}

void Evaluation::handle(const rosbag::MessageInstance& m) {
  if (!fixes_topic_.empty() && sameTopic(m.getTopic(), fixes_topic_)) return addFix(m);
  if (!mag_topic_.empty() && sameTopic(m.getTopic(), mag_topic_)) return addMag(m);
  const bool rate = sameTopic(m.getTopic(), rates_topic_);
  if (rate) handleRate(m);
  // An Imu topic may be both (rates_topic_ == truth_topic_: an AHRS's orientation as truth).
  if (!rate || sameTopic(m.getTopic(), truth_topic_)) handleTruth(m);
}

void Evaluation::handleRate(const rosbag::MessageInstance& m) {
  RateSample s;
  if (!decodeRate(m, s)) return;
  if (!s.w.allFinite()) {
    // Skipped like a lost sample: one NaN would otherwise reach the offset search's sums.
    ++rate_non_finite_;
    return;
  }
  s.seq = rate_count_;
  if (rate_count_ > 0 && s.stamp > last_rate_) intervals_.add(double(s.stamp - last_rate_) * kNs);
  if (rate_count_++ == 0) first_rate_ = s.stamp;
  last_rate_ = std::max(last_rate_, s.stamp);
  if (!calibrating_) return push(s);
  keepForCalibration(s);
}

void Evaluation::keepForCalibration(const RateSample& s) {
  calibration_rates_.push_back(s);
  if (!truth_start_) {
    // Before any truth only the last max_offset (+1 s) of rates can still be compared.
    const Stamp keep = s.stamp - static_cast<Stamp>((o_.max_offset + 1.0) / kNs);
    const auto old = std::find_if(calibration_rates_.begin(), calibration_rates_.end(),
                                  [keep](const RateSample& r) { return r.stamp >= keep; });
    before_truth_ += static_cast<std::uint64_t>(old - calibration_rates_.begin());
    calibration_rates_.erase(calibration_rates_.begin(), old);
  }
}

void Evaluation::handleTruth(const rosbag::MessageInstance& m) {
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
    deserializeInto(m, buffer_, imu_);
    read = readImu(imu_, record_);
  } else {
    read = decoders_.readTwistTopic(m, record_);
  }
  if (!read) return false;
  out = {read->stamp, read->value};
  if (o_.parameters.use_accel && isType<sensor_msgs::Imu>(m)) {
    // The accelerometer in the rates' own frame, as the rates (the mount is this tool's).
    if (const std::optional<Reading> f = readImuAcceleration(imu_, record_)) {
      out.f = BodyVector{f->stamp, f->value, f->covariance};
      ++accel_count_;
    }
  }
  return true;
}

bool Evaluation::decodeTruth(const rosbag::MessageInstance& m, TruthSample& out) {
  // The node's stamp rule (stampOf): the header stamp, or the record time, which rosbag never
  // writes as zero.
  auto stamp = [this](const ros::Time& header) { return stampOf(header, record_).value_or(0); };
  if (isType<geometry_msgs::PoseStamped>(m)) {
    deserializeInto(m, buffer_, pose_);
    out = {stamp(pose_.header.stamp), toEigen(pose_.pose.orientation)};
  } else if (isType<geometry_msgs::PoseWithCovarianceStamped>(m)) {
    deserializeInto(m, buffer_, pose_cov_);
    out = {stamp(pose_cov_.header.stamp), toEigen(pose_cov_.pose.pose.orientation)};
  } else if (isType<geometry_msgs::TransformStamped>(m)) {
    deserializeInto(m, buffer_, transform_);
    out = {stamp(transform_.header.stamp), rotationOf(transform_)};
  } else if (isType<nav_msgs::Odometry>(m)) {
    deserializeInto(m, buffer_, odometry_);
    out = {stamp(odometry_.header.stamp), toEigen(odometry_.pose.pose.orientation)};
  } else if (isType<sensor_msgs::Imu>(m)) {
    deserializeInto(m, buffer_, imu_);
    // REP-145: orientation_covariance[0] == -1 says the message has no orientation.
    if (imu_.orientation_covariance[0] == -1.0) {
      ++truth_no_orientation_;
      return false;
    }
    out = {stamp(imu_.header.stamp), toEigen(imu_.orientation)};
  } else {
    deserializeInto(m, buffer_, tf_);
    const auto it =
        std::find_if(tf_.transforms.begin(), tf_.transforms.end(), [this](const auto& t) {
          return t.header.frame_id == o_.tf_parent && t.child_frame_id == o_.tf_child;
        });
    if (it == tf_.transforms.end()) return false;
    out = {stamp(it->header.stamp), rotationOf(*it)};
  }
  const auto q = safeNormalized(out.q);
  if (!q) {
    ++truth_unusable_;  // non-finite or zero: no rotation
    return false;
  }
  if (std::abs(out.q.norm() - 1.0) > kUnitTolerance) {
    ++truth_non_unit_;  // a rotation only after normalising: not what a truth gives
    return false;
  }
  out.q = *q;
  return true;
}

void Evaluation::addFix(const rosbag::MessageInstance& m) {
  ++fix_count_;
  const Decoded<Fix> fix = fix_decoder_->topic(m, record_, nullptr);  // refusals counted there
  if (fix) fixes_.push_back({rate_count_, *fix});
}

void Evaluation::addMag(const rosbag::MessageInstance& m) {
  ++mag_count_;
  deserializeInto(m, buffer_, mag_);
  const Decoded<Reading> read = readMagneticField(mag_, record_);
  if (!read) return;  // no time: as the node drops it
  fixes_.push_back({rate_count_, Fix{}, BodyVector{read->stamp, read->value, read->covariance}});
}

void Evaluation::reportAiding(std::FILE* out) const {
  const Parameters& p = o_.parameters;
  for (const auto& [on, prefix, read] :
       {std::tuple<bool, const char*, std::uint64_t>{p.use_accel, "accel_", accel_count_},
        std::tuple<bool, const char*, std::uint64_t>{p.use_mag, "mag_", mag_count_}}) {
    if (!on) continue;
    std::fprintf(out, "  %.*s: %llu read; per method:", static_cast<int>(std::strlen(prefix) - 1),
                 prefix, static_cast<unsigned long long>(read));
    for (const auto& m : methods_) {
      if (!m->started()) continue;
      std::fprintf(out, " %s (%s);", m->name().c_str(),
                   aidingCountersText(m->counters(), prefix).c_str());
    }
    std::fputc('\n', out);
  }
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
    for (auto& method : methods_) method->compare(truth_, false);
    // Drop the truth every method has compared.
    Stamp keep = std::numeric_limits<Stamp>::max();
    for (const auto& method : methods_) keep = std::min(keep, method->nextTruth());
    while (!truth_.empty() && truth_.front().stamp < keep) truth_.pop_front();
  }
}

void Evaluation::calibrate() {
  calibrating_ = false;
  checkTruthSamples();
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
  ranking_windows_ = rankingWindows(truth_period_, rate_period_);
  std::vector<double> windows(std::begin(kShownWindows), std::end(kShownWindows));
  windows.insert(windows.end(), ranking_windows_.begin(), ranking_windows_.end());
  for (auto& method : methods_)
    method->setWindows(windows, truth_period_, ranking_windows_.front());
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
  // The mount relates the rate vectors, whichever instant a sample stands for: fitted with
  // the samples at their stamps and the offset found that way, it holds for both readings.
  if (o_.mount) {
    mount_ = *o_.mount;
    mount_note_ = "given";
  } else {
    double ratio = 0.0;
    mount_ = Eigen::Quaterniond(estimateMount(gyro, track, offset_estimate_.offset, &ratio));
    mount_note_ = ratio < 1e-3 ? "estimated; the rates turn about one axis only, so the mount's "
                                 "rotation about it is not observable (closest to identity used)"
                               : "estimated from the rate directions (Wahba)";
  }
  for (auto& method : methods_) method->mount = mount_;
  applyDelayModel();
  for (const auto& r : calibration_rates_) push(r);
  calibration_rates_.clear();
  calibration_rates_.shrink_to_fit();
}

void Evaluation::applyDelayModel() {
  const double o = offset_estimate_.offset;
  // A reading's own lag: a sample taken as the mean over the interval it closes stands for
  // its middle, half a period before its stamp; an instantaneous one for its stamp.
  auto own = [this](const Method& m) { return m.averaged() ? 0.5 * rate_period_ : 0.0; };
  char text[512];
  if (o_.offset) {
    // A given offset: the clocks' own, for both readings, with the configured rate_delay.
    for (auto& m : methods_) m->start(m->configuredRateDelay(), o);
    delay_note_ =
        "not estimated (--offset given: every method at that offset, with the "
        "configured rate_delay)";
    return;
  }
  if (!offset_estimate_.observable) {
    // Nothing found: offset 0 for samples at their stamps, which is also where the mount was
    // fitted (for a motion whose time shift is a rotation, the mount takes that shift up); an
    // interval-average reading places its samples half a period earlier, so it meets the
    // truth half a period later.
    for (auto& m : methods_)
      m->start(m->configuredRateDelay(), o + own(*m) + m->configuredRateDelay());
    delay_note_ =
        "not estimated (the offset is not observable: samples at their stamps taken at offset "
        "0, where the mount was fitted; the configured rate_delay used)";
    return;
  }
  std::string fallback;
  if (o_.truth_clock_same) {
    total_delay_ = -o;
    // Estimates agree to a few microseconds; a lag below -2 % of a period is a truth stamped
    // after its instant (a latency) or another clock, not a rate newer than its stamp.
    const double tolerance = 0.02 * rate_period_;
    bool fits = total_delay_ >= -tolerance;
    for (const auto& m : methods_) fits = fits && total_delay_ - own(*m) <= m->maxDt();
    if (fits) {
      delay_estimated_ = true;
      std::string readings;
      for (auto& m : methods_) {
        const double needed = total_delay_ - own(*m);
        m->start(std::max(0.0, needed), 0.0);
      }
      for (const bool averaged : {false, true}) {
        const auto m = std::find_if(methods_.begin(), methods_.end(), [averaged](const auto& x) {
          return x->averaged() == averaged;
        });
        if (m == methods_.end()) continue;
        const double needed = total_delay_ - own(**m);
        std::snprintf(text, sizeof text, "%s%s %.4f ms%s", readings.empty() ? "" : ", ",
                      averaged ? "as interval averages" : "as instantaneous rates",
                      std::max(0.0, needed) * 1e3,
                      needed < -tolerance ? " (would need a negative delay: this reading cannot "
                                            "explain the lag, and runs with 0)"
                                          : "");
        readings += text;
      }
      std::snprintf(text, sizeof text,
                    "%.4f ms estimated (--truth-clock same: the truth is stamped at its instants "
                    "on the rates' clock, so the rates' lag is minus the offset); each method "
                    "runs with it less its reading's own lag (half a period for interval "
                    "averages): rate_delay %s; compared at offset 0",
                    total_delay_ * 1e3, readings.c_str());
      delay_note_ = text;
      return;
    }
    std::snprintf(text, sizeof text,
                  "not estimated: the data contradict --truth-clock same (with one clock the "
                  "rates would lag by %.4f ms, which %s); compared as with the truth's clock "
                  "unknown (--truth-clock separate), exit code 5. ",
                  total_delay_ * 1e3,
                  total_delay_ < 0.0 ? "is no delay: the truth is stamped late or on another clock"
                                     : "exceeds max_dt (rate_delay is at most max_dt)");
    fallback = text;
    clock_contradicted_ = true;
  }
  for (auto& m : methods_)
    m->start(m->configuredRateDelay(), o + own(*m) + m->configuredRateDelay());
  delay_note_ = fallback +
                (fallback.empty() ? std::string("not estimated (the truth's clock unknown: "
                                                "--truth-clock separate, the default): ")
                                  : "") +
                "the offset is the clocks' and holds any delay of the rates, which this data "
                "cannot tell from it; every method runs with the configured rate_delay";
}

void Evaluation::push(const RateSample& s) {
  batch_.push_back(s);
  if (batch_.size() == kBatch) flush(false);
}

void Evaluation::flush(bool at_end) {
  // States from a few rate periods before the truth's start: the first truth samples have
  // states on both sides.
  const double lead = (kInterpolationNodes / 2 + 1) * rate_period_;
  std::uint64_t fixes_done = fixes_base_ + fixes_.size();
  for (auto& method : methods_) {
    method->feed(batch_, fixes_, fixes_base_, *truth_start_, lead);
    // At the end the fixes after the last rate too: they wait, counted as pending.
    if (at_end) method->submitFixes(fixes_, fixes_base_, std::numeric_limits<std::uint64_t>::max());
    method->compare(truth_, at_end);
    fixes_done = std::min(fixes_done, method->nextFix());
  }
  batch_.clear();
  for (; fixes_base_ < fixes_done; ++fixes_base_) fixes_.pop_front();
}

double Evaluation::resolutionFloor() const {
  double white = std::numeric_limits<double>::infinity();
  std::uint64_t n = 0;
  for (const auto& m : methods_) {
    if (!m->scored()) continue;
    if (!std::isnan(m->whiteResidual())) white = std::min(white, m->whiteResidual());
    n = std::max(n, m->compared);
  }
  const double roundoff = 10.0 * std::numeric_limits<double>::epsilon() * std::sqrt(double(n));
  return std::isfinite(white) ? std::max(2.0 * white, roundoff) : roundoff;
}

double Evaluation::costTolerance() const {
  // The median over the integrators run with both readings (one descheduled batch can spoil
  // one method's cost: the median keeps it from setting the tolerance).
  std::vector<double> differences;
  for (const auto& a : methods_) {
    if (a->averaged()) continue;
    for (const auto& b : methods_) {
      if (a->integrator() != b->integrator() || !b->averaged()) continue;
      const double lo = std::min(a->costNs(), b->costNs()), hi = std::max(a->costNs(), b->costNs());
      if (lo > 0.0) differences.push_back(hi / lo - 1.0);
    }
  }
  if (differences.empty()) return kCostNoise;
  std::sort(differences.begin(), differences.end());
  const std::size_t n = differences.size();
  const double median =
      n % 2 ? differences[n / 2] : 0.5 * (differences[n / 2 - 1] + differences[n / 2]);
  return std::max(kCostNoise, median);
}

std::size_t Evaluation::recommended() const {
  // Among the scored methods whose RMS error is within 10 % of the best one's (or of the
  // smallest error the truth resolves, when the best is below it): the cheapest, costs within
  // the timing noise counting as equal, ties broken in a fixed order (the integrator table's,
  // instantaneous before interval_average). Errors are the same on every run; the costs are
  // not, so the order, not the clock, decides between methods the clock cannot tell apart.
  // The error ranked: the relative error over the ranking window (the integrator's own, not
  // the drift of the bias and of the truth), or the whole-run RMS where no window was measured.
  const bool windowed = rankedByWindow();
  auto error = [this, windowed](const Method& m) {
    const double e = windowed ? rankingError(m, rank_window_) : m.rms();
    return std::isnan(e) ? std::numeric_limits<double>::infinity() : e;
  };
  double best = std::numeric_limits<double>::infinity();
  for (const auto& m : methods_) {
    if (m->scored()) best = std::min(best, error(*m));
  }
  const double level = 1.1 * std::max(best, resolutionFloor());
  double cheapest = std::numeric_limits<double>::infinity();
  for (const auto& m : methods_) {
    if (m->scored() && error(*m) <= level) cheapest = std::min(cheapest, m->costNs());
  }
  const double affordable = cheapest * (1.0 + costTolerance());
  std::optional<std::size_t> pick;
  for (std::size_t i = 0; i < methods_.size(); ++i) {
    const Method& m = *methods_[i];
    if (!m.scored() || error(m) > level || m.costNs() > affordable) continue;
    if (!pick || m.order() < methods_[*pick]->order()) pick = i;
  }
  return pick.value_or(0);
}

std::optional<std::string> Evaluation::noRecommendation() const {
  for (const auto& m : methods_) {
    if (m->scored()) return std::nullopt;
  }
  // Say it for the method that came closest.
  const Method* closest = methods_.front().get();
  for (const auto& m : methods_) {
    if (m->compared > closest->compared) closest = m.get();
  }
  const EngineCounters& c = closest->counters();
  return "no method was scored on enough of the truth (at least half of the truth samples met "
         "by its states, and at least " +
         std::to_string(kMinScored) +
         ", compared with states integrated one from the other, not across a gap longer than "
         "max_dt or a reset): " +
         closest->name() + " compared " + std::to_string(closest->compared) + " (" +
         std::to_string(closest->in_gap) +
         " truth samples between such gaps: " + std::to_string(c.gaps) +
         " gaps longer than max_dt, " + std::to_string(c.resets) + " resets; " +
         std::to_string(closest->outside) + " outside its states; " +
         std::to_string(before_truth_) + " rate samples before the truth)";
}

void Evaluation::report(std::FILE* out) const {
  const double span = double(last_rate_ - first_rate_) * kNs;
  std::fprintf(out, "evaluate_bag: %s, %.1f s of rates\n", o_.input.c_str(), span);
  // The mean rate over the whole run, and the intervals' spread beside it (receipt stamps of a
  // jittered stream: its median interval alone can be far from the mean).
  std::fprintf(out,
               "  rates %s (%s): %llu samples, %.1f Hz mean (intervals %.3f ms mean, %.3f ms "
               "standard deviation, %.3f ms median over the calibration)\n",
               rates_topic_.c_str(), rates_type_.c_str(),
               static_cast<unsigned long long>(rate_count_),
               intervals_.mean > 0 ? 1.0 / intervals_.mean : 0.0, intervals_.mean * 1e3,
               intervals_.sd() * 1e3, rate_period_ * 1e3);
  std::fprintf(out,
               "  truth %s%s (%s): %llu samples, %.1f Hz; not differentiated across gaps above "
               "%.4g s%s\n",
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
  std::fprintf(out, "  time offset (truth - rates, samples at their stamps): %+.4f ms (%s)\n",
               offset_estimate_.offset * 1e3, offset_estimate_.how.c_str());
  std::fprintf(out, "  rate delay: %s\n", delay_note_.c_str());
  const double mount_angle = 2.0 * std::atan2(mount_.vec().norm(), std::abs(mount_.w()));
  std::fprintf(out, "  mount q_ST [x y z w] = [%.6f %.6f %.6f %.6f] (%.3f deg; %s)\n", mount_.x(),
               mount_.y(), mount_.z(), mount_.w(), mount_angle * 180.0 / M_PI, mount_note_.c_str());
  const Method& first = *methods_.front();
  std::fprintf(out,
               "  compared at the truth's stamps, each method's states interpolated to them "
               "(degree 5 through six states): %llu per method; between gaps of the rates: %llu; "
               "outside the states: %llu; rate samples before the truth: %llu\n",
               static_cast<unsigned long long>(first.compared),
               static_cast<unsigned long long>(first.in_gap),
               static_cast<unsigned long long>(first.outside),
               static_cast<unsigned long long>(before_truth_));
  if (fix_decoder_) reportFixes(out);
  reportAiding(out);
  const auto refused = noRecommendation();
  const double floor = resolutionFloor();
  std::string unresolved;
  for (const auto& m : methods_) {
    if (m->scored() && m->rms() < floor) unresolved += (unresolved.empty() ? "" : ", ") + m->name();
  }
  std::fprintf(out,
               "  truth resolves RMS errors down to %.3g rad (twice the white part of the "
               "residuals, at least the round-off floor)\n",
               floor);
  if (!unresolved.empty()) {
    std::fprintf(out,
                 "  warning: the truth cannot resolve the errors of %s (below %.3g rad): they "
                 "count as equally accurate\n",
                 unresolved.c_str(), floor);
  }
  char ranked[32];
  std::snprintf(ranked, sizeof ranked, "RPE %.3g s", rankingWindow());
  std::string windows;
  for (std::size_t w = 0; w < ranking_windows_.size(); ++w) {
    char text[32];
    std::snprintf(text, sizeof text, "%s%.3g", w ? ", " : "", ranking_windows_[w]);
    windows += text;
  }
  std::fprintf(out,
               "  ranking window: %.3g s, of %s s (from %.0f periods of the slower stream, "
               "doubling to %.0f s): the shortest at which the smallest relative error is above "
               "what the truth resolves; the drift of the gyro's bias and of the truth grows "
               "with the window and hides the integrator's own error\n",
               rankingWindow(), windows.c_str(), kRankingWindowSamples, kLongestRankingWindow);
  if (!rankedByWindow()) {
    std::fprintf(out,
                 "  warning: fewer than %llu windows measured at any of them: ranked by the "
                 "whole-run RMS error\n",
                 static_cast<unsigned long long>(kMinWindows));
  }
  if (fix_decoder_) {
    std::fprintf(out,
                 "  with fixes: scored from the first state after the first applied fix "
                 "(%llu truth samples before it not scored, %s)\n",
                 static_cast<unsigned long long>(first.before_fix), first.name().c_str());
  }
  std::fprintf(out, "\n  %-24s %10s %10s %11s %10s %10s %10s %9s %9s\n", "method", "max [rad]",
               "RMS [rad]", "drift[rad/s]", "RPE 1 s", "RPE 10 s", ranked, "ns/sample",
               "delay[ms]");
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
    std::fprintf(out, "  %-24s %s %s %s %s %s %s %9.1f %9.4f%s\n", m.name().c_str(),
                 cell(m.max_error, 10).c_str(), cell(m.rms(), 10).c_str(),
                 cell(m.drift(), 11).c_str(), cell(m.window(0).rms(), 10).c_str(),
                 cell(m.window(1).rms(), 10).c_str(),
                 cell(rankingError(m, rank_window_), 10).c_str(), m.costNs(), m.rateDelay() * 1e3,
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
  char ranked_error[64];
  if (rankedByWindow()) {
    std::snprintf(ranked_error, sizeof ranked_error, "relative error over %.3g s", rankingWindow());
  } else {
    std::snprintf(ranked_error, sizeof ranked_error, "whole-run RMS error");
  }
  std::fprintf(
      out,
      "\n  recommendation: integrator %s, rate_samples %s (the cheapest within 10 %% of the "
      "lowest %s, costs within %.0f %% equal, ties in the integrator table's order)\n",
      r.integrator().c_str(), r.samples().c_str(), ranked_error, 100.0 * costTolerance());
  // rate_delay only when the clocks are known to be one: otherwise the offset holds it.
  std::fprintf(out, "  settings:\n    integrator: %s\n    rate_samples: %s\n",
               r.integrator().c_str(), r.samples().c_str());
  if (delay_estimated_) {
    std::fprintf(out, "    rate_delay: %.6g\n", r.rateDelay());
  } else {
    std::fprintf(out,
                 "    # rate_delay: not recommended (the truth's clock is not known to be the "
                 "rates': the offset found holds any delay; give --truth-clock same when one "
                 "clock stamps both)\n");
  }
  std::fprintf(out, "  %.3f s wall for %llu messages\n", wall_,
               static_cast<unsigned long long>(rate_count_ + truth_count_));
}

void Evaluation::reportFixes(std::FILE* out) const {
  // Per method, every fix given: accepted, rejected (gate, too old, bad), or still waiting.
  const FixRefusals& r = fix_decoder_->refusals();
  auto u = [](std::uint64_t x) { return static_cast<unsigned long long>(x); };
  std::fprintf(out,
               "  fixes %s (%s): %llu, refused before the engines %llu (%s; no_tf: only "
               "fixed_frame and body_frame, the rates' frame, are known here); per method "
               "accepted/rejected_gate/too_old/other/pending:",
               fixes_topic_.c_str(), fixes_type_.c_str(), u(fix_count_), u(r.total()),
               fixRefusalCounts(r).c_str());
  for (const auto& m : methods_) {
    if (!m->started()) continue;
    const EngineCounters& c = m->counters();
    const std::uint64_t other = fixesNotApplied(c) - c.fixes_rejected_gate - c.fixes_too_old;
    std::fprintf(out, " %s %llu/%llu/%llu/%llu/%llu", m->name().c_str(), u(c.fixes_accepted),
                 u(c.fixes_rejected_gate), u(c.fixes_too_old), u(other), u(m->pendingFixes()));
  }
  std::fputc('\n', out);
}

void Evaluation::writeCsv(const std::string& summary_path, const std::string& series_path) {
  CsvFile summary(summary_path, o_.prefix + ".csv");
  std::fputs(
      "method,integrator,rate_samples,offset_s,rate_delay_s,compared,in_rate_gaps,outside_states,"
      "max_error_rad,rms_error_rad,drift_rad_per_s,rpe_1s_rms_rad,rpe_1s_max_rad,"
      "rpe_10s_rms_rad,rpe_10s_max_rad,ranking_window_s,rpe_ranking_rms_rad,cost_ns_per_sample,"
      "recommended\n",
      summary.get());
  const std::size_t pick = recommended();
  for (std::size_t i = 0; i < methods_.size(); ++i) {
    const Method& m = *methods_[i];
    std::fprintf(summary.get(),
                 "%s,%s,%s,%.9g,%.9g,%llu,%llu,%llu,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,"
                 "%.2f,%d\n",
                 m.name().c_str(), m.integrator().c_str(), m.samples().c_str(), m.offset,
                 m.rateDelay(), static_cast<unsigned long long>(m.compared),
                 static_cast<unsigned long long>(m.in_gap),
                 static_cast<unsigned long long>(m.outside), m.max_error, m.rms(), m.drift(),
                 m.window(0).rms(), m.window(0).max, m.window(1).rms(), m.window(1).max,
                 rankingWindow(), rankingError(m, rank_window_), m.costNs(), i == pick ? 1 : 0);
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
  if (evaluation.clockContradicted()) {
    std::fprintf(stderr,
                 "evaluate_bag: --truth-clock same is contradicted by the data: compared with the "
                 "truth's clock unknown (see the rate delay line)\n");
    return kExitClockContradicted;
  }
  return 0;
}

}  // namespace
}  // namespace tools
}  // namespace attitude_propagator

int main(int argc, char** argv) {
  return attitude_propagator::tools::runTool("evaluate_bag", attitude_propagator::tools::run, argc,
                                             argv);
}
