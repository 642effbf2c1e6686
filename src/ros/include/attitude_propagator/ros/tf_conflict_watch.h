// The tf-conflict watch: another parent of the frame we publish as a child (or the same edge
// from another node) seen on /tf or /tf_static. It counts, names the conflict with its fix and,
// with `tf_conflict: stop`, stops our tf rather than fight over the tree until the conflict is
// over (resumeTfIfClear) or publish_tf is switched off and on (resumeTf). Pure: the wrapper
// subscribes, drops the messages of its own node name when it runs as a node of its own, logs
// the lines returned and asks stopped() before each transform it publishes. In a nodelet
// manager every nodelet publishes under the manager's name, so there the wrapper tells the
// watch each transform it sends (sent) and the watch tells ours from a sibling's by content.
#pragma once

#include <cstddef>
#include <cstdint>
#include <deque>
#include <optional>
#include <string>
#include <unordered_set>

#include <geometry_msgs/TransformStamped.h>
#include <ros/time.h>
#include <tf2_msgs/TFMessage.h>

#include "attitude_propagator/config/parameters.h"
#include "attitude_propagator/ros/log_text.h"

namespace attitude_propagator {

// tf stopped by a conflict on /tf resumes after this long (wall s) without another parent of
// our child frame there: tf publishers repeat their transforms at 10 Hz or more, so 2 s is
// many missed messages, not a pause between two.
constexpr double kTfConflictClearance = 2.0;

// Stamps of our own transforms kept to recognise them in a nodelet manager: more than the
// watch's subscriber queue (1000 messages) can hold of ours before the watch sees them.
constexpr std::size_t kOwnStampsKept = 4096;

class TfConflictWatch {
 public:
  /// A message on /tf (latched false) or /tf_static (latched true), seen at wall time `now`;
  /// `p` names our edge (reverse_tf, the frames) and tf_conflict. `named_like_us`: its
  /// publisher has our node name (a nodelet manager's): a transform of our edge with a stamp we
  /// sent is ours, any other of our child frame a sibling nodelet's conflict. Otherwise the
  /// message is another node's. The warning to log: at the first conflict with `warn`, at each
  /// stop with `stop`.
  std::optional<LogLine> onTfSeen(const tf2_msgs::TFMessage& msg, const std::string& publisher,
                                  bool named_like_us, bool latched, const Parameters& p,
                                  const ros::WallTime& now);
  /// A transform we published (in a nodelet manager): remembered by its stamp, the newest
  /// kOwnStampsKept of them.
  void sent(const geometry_msgs::TransformStamped& t);
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
  std::deque<std::uint64_t> own_stamps_;            // ns, oldest first
  std::unordered_multiset<std::uint64_t> own_set_;  // the same, for the look-up
};

}  // namespace attitude_propagator
