// The tf-conflict watch: another parent of the frame we publish as a child (or the same edge
// from another node) seen on /tf or /tf_static. It counts, names the conflict with its fix and,
// with `tf_conflict: stop`, stops our tf rather than fight over the tree until the conflict is
// over (resumeTfIfClear) or publish_tf is switched off and on (resumeTf). Pure: the wrapper
// subscribes, drops our own messages, logs the lines returned and asks stopped() before each
// transform it publishes.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include <ros/time.h>
#include <tf2_msgs/TFMessage.h>

#include "attitude_propagator/config/parameters.h"
#include "attitude_propagator/ros/log_text.h"

namespace attitude_propagator {

// tf stopped by a conflict on /tf resumes after this long (wall s) without another parent of
// our child frame there: tf publishers repeat their transforms at 10 Hz or more, so 2 s is
// many missed messages, not a pause between two.
constexpr double kTfConflictClearance = 2.0;

class TfConflictWatch {
 public:
  /// A message on /tf (latched false) or /tf_static (latched true) from another node, seen at
  /// wall time `now`; `p` names our edge (reverse_tf, the frames) and tf_conflict. The warning
  /// to log: at the first conflict with `warn`, at each stop with `stop`.
  std::optional<LogLine> onTfSeen(const tf2_msgs::TFMessage& msg, const std::string& publisher,
                                  bool latched, const Parameters& p, const ros::WallTime& now);
  /// Resumes tf stopped by a conflict on /tf once no other parent has been seen there for
  /// kTfConflictClearance. A /tf_static parent stays in every tf buffer: no time clears it.
  std::optional<LogLine> resumeTfIfClear(const Parameters& p, const ros::WallTime& now);
  /// Clears a stop (publish_tf switched off and on, or reverse_tf changing our child frame).
  std::optional<LogLine> resumeTf(const char* why, const Parameters& p);

  /// Our tf is stopped: publish none.
  bool stopped() const { return tf_stopped_; }
  std::uint64_t conflicts() const { return tf_conflicts_; }
  std::uint64_t resumes() const { return tf_resumes_; }

 private:
  std::uint64_t tf_conflicts_ = 0;
  bool tf_stopped_ = false;
  bool tf_conflict_latched_ = false;  // the stop came from /tf_static: only a toggle clears it
  ros::WallTime last_tf_conflict_;    // the latest other parent of our child frame seen on /tf
  std::uint64_t tf_resumes_ = 0;
};

}  // namespace attitude_propagator
