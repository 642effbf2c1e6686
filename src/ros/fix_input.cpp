#include "attitude_propagator/ros/fix_input.h"

#include <cstring>
#include <optional>

#include <ros/console.h>
#include <ros/master.h>
#include <ros/serialization.h>

#include "attitude_propagator/messages/conversions.h"
#include "attitude_propagator/messages/refusal_table.h"
#include "attitude_propagator/ros/log_text.h"
#include "attitude_propagator/ros/node_queues.h"

namespace attitude_propagator {

namespace {

// Throttle period (s) of warnings about fixes that keep coming bad, as for the other inputs.
constexpr double kFixWarnPeriod = 5.0;

/// A FrameSource that notes whether it was asked at all.
class NotingFrames : public FrameSource {
 public:
  NotingFrames(FrameSource& frames, bool& asked) : frames_(frames), asked_(asked) {}
  std::optional<Eigen::Quaterniond> rotation(const std::string& target, const std::string& source,
                                             const ros::Time& stamp, std::string* error) override {
    asked_ = true;
    return frames_.rotation(target, source, stamp, error);
  }

 private:
  FrameSource& frames_;
  bool& asked_;
};

}  // namespace

FixInput::FixInput(const NodeConfig& config, InstanceLog& log)
    : decoder_(FixFrames::of(config)), config_(engineConfig(config).fixes), log_(log) {}

void FixInput::warn(const char* kind, const std::string& text) {
  log_.log(LogLine{ros::console::levels::Warn, kind, text}, ros::WallTime::now().toSec(),
           kFixWarnPeriod);
}

void FixInput::onMessage(const topic_tools::ShapeShifter& msg, const ros::Time& arrival,
                         const std::string& publisher, AttitudeEngine& engine,
                         FrameSource& frames) {
  buffer_.resize(msg.size());
  ros::serialization::OStream bytes(buffer_.data(), static_cast<std::uint32_t>(buffer_.size()));
  msg.write(bytes);
  if (const std::optional<std::uint32_t> seq = headerSeq(buffer_.data(), buffer_.size())) {
    if (const std::uint64_t lost = gaps_.observe(publisher, *seq)) {
      warn("fix lost",
           formatted("orientation_fix: %lu fixes from %s lost before the node (header.seq "
                     "jumped to %u: its subscriber queue of %u overflowed, or the "
                     "connection dropped them) (%lu lost so far)",
                     lost, logText(publisher).c_str(), *seq, kSparseQueueSize, gaps_.lost()));
    }
  }
  NotingFrames noting(frames, uses_tf_);
  const Decoded<Fix> fix = decoder_.topic(msg, arrival, &noting);
  for (const auto& w : decoder_.takeFrameWarnings()) {
    log_.log(LogLine{ros::console::levels::Warn, "",
                     "orientation_fix: " + logText(w, 4 * kLogTextBytes)},
             ros::WallTime::now().toSec(), kFixWarnPeriod);
  }
  if (!fix) return logRefusal(*fix.refusal);
  logOutcome(engine.submitFix(fix->stamp, fix->q_WB, fix->R_B), fix->stamp, engine);
}

std::uint64_t FixInput::notApplied(const EngineCounters& c) const {
  return fixesNotApplied(c) + decoder_.refusals().total();
}

std::uint64_t FixInput::notAppliedInARow(const EngineCounters& c) {
  if (c.fixes_accepted != applied_seen_) {
    applied_seen_ = c.fixes_accepted;
    not_applied_at_last_apply_ = notApplied(c);
  }
  return notApplied(c) - not_applied_at_last_apply_;
}

std::string FixInput::warning(const EngineCounters& c) {
  const std::uint64_t run = notAppliedInARow(c);
  if (run < kFixWarnRun) return {};
  return "the last " + std::to_string(run) +
         " orientation fixes were not applied (latest: " + last_reason_ +
         "): the state is not corrected by them";
}

void FixInput::diagnose(diagnostic_updater::DiagnosticStatusWrapper& status,
                        const AttitudeEngine& engine) const {
  const FixRefusals& r = decoder_.refusals();
  status.add("fixes_refused", r.total());
  for (const RefusalRow& row : refusalTable()) {
    if (row.fix_count) status.add(row.fix_counter, r.*row.fix_count);
  }
  status.add("fixes_pending", engine.pendingFixes());
  status.add("fixes_lost", gaps_.lost());
  status.add("fixes_other_type", other_type_.empty() ? std::string("none") : other_type_);
  if (config_.estimate_gyro_bias) {
    const Eigen::Vector3d& b = engine.gyroBiasEstimate();
    const Eigen::Vector3d s = engine.gyroBiasStddev();
    status.addf("gyro_bias_estimate", "[%g, %g, %g]", b.x(), b.y(), b.z());
    status.addf("gyro_bias_estimate_stddev", "[%g, %g, %g]", s.x(), s.y(), s.z());
  }
}

void FixInput::checkRegisteredType(const std::string& topic) {
  if (decoder_.type().datatype().empty()) return;  // no type of our own yet
  ros::master::V_TopicInfo topics;
  if (!ros::master::getTopics(topics)) return;
  for (const auto& t : topics) {
    if (t.name != topic) continue;
    const std::optional<std::string> other = decoder_.type().otherRegistered(t.datatype);
    if (!other || *other == other_type_) return;
    other_type_ = *other;
    log_.log(
        LogLine{ros::console::levels::Warn, "",
                formatted("orientation_fix: a publisher of %s is registered on %s, which "
                          "carries %s (its first message's type): ROS 1 refuses that "
                          "publisher's connection, so its fixes never reach the node and "
                          "cannot be counted (accepted: one of %s per topic)",
                          logText(other_type_).c_str(), topic.c_str(),
                          decoder_.type().datatype().c_str(), decoder_.type().accepted().c_str())},
        ros::WallTime::now().toSec(), kFixWarnPeriod);
    return;
  }
}

void FixInput::logRefusal(const Refusal& r) {
  const FixFrames& f = decoder_.frames();
  switch (r.why) {
    case Refused::NoTransform:
      warn("fix refused no_tf",
           formatted("orientation_fix: no transform for frame '%s' (the header frame must be "
                     "joined to '%s', fix_frame to '%s'): refused (%lu so far; %s)",
                     logText(r.frame).c_str(), f.fixed.c_str(),
                     (f.fix.empty() ? f.body : f.fix).c_str(), decoder_.refusals().no_tf,
                     logText(r.detail, 4 * kLogTextBytes).c_str()));
      break;
    case Refused::WrongType:
      warn("fix refused type",
           formatted("orientation_fix: message type %s refused; the topic carries %s (its "
                     "first message's type; accepted: %s) (%lu so far)",
                     logText(r.detail).c_str(), decoder_.type().datatype().c_str(),
                     decoder_.type().accepted().c_str(), decoder_.refusals().type));
      break;
    case Refused::NoTime:
      warn("fix refused no_time",
           formatted("orientation_fix: unstamped fix and no ROS time yet (/clock): refused"));
      break;
    case Refused::NoOrientation:
      warn("fix refused no_orientation",
           formatted("orientation_fix: sensor_msgs/Imu with orientation_covariance[0] == -1 "
                     "(no orientation, REP-145): refused (%lu so far)",
                     decoder_.refusals().no_orientation));
      break;
    case Refused::FixBodyFrame:
      warn("fix refused body_frame",
           formatted("orientation_fix: header frame '%s' is body_frame: a fix must be given "
                     "in a frame joined to '%s' without passing through '%s': refused (%lu so "
                     "far)",
                     logText(r.frame).c_str(), f.fixed.c_str(), f.body.c_str(),
                     decoder_.refusals().body_frame));
      break;
    default:
      break;  // the fix decoder makes no other
  }
  last_reason_ = fixRefusedCounter(r.why) + std::strlen("fixes_");  // refused_...
}

void FixInput::logOutcome(FixOutcome outcome, Stamp stamp, const AttitudeEngine& engine) {
  const FixOutcomeRow& row = fixOutcomeRow(outcome);
  if (row.why == nullptr) {  // applied, or waiting for the rates
    ROS_DEBUG("%sorientation_fix at %.9f s: %s", log_.prefix().c_str(), toRosTime(stamp).toSec(),
              row.name);
    return;
  }
  last_reason_ = row.name;
  warn("fix outcome",
       formatted("orientation_fix at %.9f s: %s: %s (%lu accepted so far)",
                 toRosTime(stamp).toSec(), row.name, row.why, engine.counters().fixes_accepted));
}

}  // namespace attitude_propagator
