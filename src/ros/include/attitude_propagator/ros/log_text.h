// Log lines of the ROS layer: composed without ROS, logged by the wrapper. Text from a message
// goes through logText (attitude_propagator/quoted_text.h, the core's one capping rule).
#pragma once

#include <cstddef>
#include <string>

#include <ros/console_backend.h>

#include "attitude_propagator/quoted_text.h"  // logText: the capping rule

namespace attitude_propagator {

/// printf into a string (the log lines are composed before the wrapper logs them).
std::string formatted(const char* format, ...) __attribute__((format(printf, 1, 2)));

/// A line for the log, composed without ROS: the wrapper logs it, throttled per kind.
struct LogLine {
  ros::console::levels::Level level = ros::console::levels::Warn;
  /// Lines of one kind share one throttle, so a flood of one kind never hides another;
  /// empty: logged every time.
  std::string kind;
  std::string text;
};

}  // namespace attitude_propagator
