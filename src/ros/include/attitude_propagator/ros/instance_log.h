// Where one instance of the node logs: every line names the instance when it shares its
// process with others (nodelets in one manager all log under the manager's node name), and
// lines are throttled per instance and kind, so one instance's flood never hides another's.
#pragma once

#include <map>
#include <optional>
#include <string>

#include "attitude_propagator/ros/log_text.h"

namespace attitude_propagator {

/// The text that names an instance in its log lines: empty for a node of its own (rosout and
/// rosconsole already name its process), "<private namespace>: " for a nodelet, whose private
/// namespace is its own name while the process is the manager's.
std::string instancePrefix(const std::string& private_namespace, const std::string& node_name);

class InstanceLog {
 public:
  explicit InstanceLog(std::string prefix = {}) : prefix_(std::move(prefix)) {}

  /// Logs the line with the instance's prefix; a line with a kind only when none of that kind
  /// was logged in the last `period` seconds of wall time (ROS_LOG_THROTTLE's rule, on wall
  /// time: ROS time may take turns between two /clock publishers; a wall clock that went back
  /// lets the line through).
  void log(const std::optional<LogLine>& line, double wall_now, double period);

  /// True when a line of `kind` is due at wall_now (and then counts it as logged).
  bool due(const std::string& kind, double wall_now, double period);

  const std::string& prefix() const { return prefix_; }

 private:
  std::string prefix_;
  std::map<std::string, double> last_logged_;  // per kind: wall time (s) last logged
};

}  // namespace attitude_propagator
