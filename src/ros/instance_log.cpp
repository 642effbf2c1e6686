#include "attitude_propagator/ros/instance_log.h"

#include <ros/console.h>

namespace attitude_propagator {

std::string instancePrefix(const std::string& private_namespace, const std::string& node_name) {
  return private_namespace == node_name ? std::string() : logText(private_namespace) + ": ";
}

bool InstanceLog::due(const std::string& kind, double wall_now, double period) {
  const auto it = last_logged_.find(kind);
  if (it != last_logged_.end() && it->second + period > wall_now && wall_now >= it->second) {
    return false;
  }
  last_logged_[kind] = wall_now;
  return true;
}

void InstanceLog::log(const std::optional<LogLine>& line, double wall_now, double period) {
  if (!line) return;
  if (!line->kind.empty() && !due(line->kind, wall_now, period)) return;
  ROS_LOG(line->level, ROSCONSOLE_DEFAULT_NAME, "%s%s", prefix_.c_str(), line->text.c_str());
}

}  // namespace attitude_propagator
