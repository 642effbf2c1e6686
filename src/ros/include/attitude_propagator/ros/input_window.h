// The input window: what became of the rate samples received over the last kInputWindow of
// wall time, judged from the engine's counters at the window's two ends. When most were lost,
// problem() names the commonest cause for the diagnostics' summary. Pure: the wrapper closes
// the window from its watchdog.
#pragma once

#include <string>

#include <ros/time.h>

#include "attitude_propagator/models/propagator.h"

namespace attitude_propagator {

/// The node's advice on a cause of lost rate samples, by the counter's name in the core's table
/// (engineCounterTable); nullptr for a counter without one (its meaning is shown instead).
const char* inputLossAdvice(const std::string& counter);

// Diagnostics judge what became of the rate samples over windows of this long (wall s).
constexpr double kInputWindow = 1.0;

class InputWindow {
 public:
  /// Closes the window when it is due (the first call opens the first one): counters `c` at
  /// wall time `now`, max_dt in force.
  void closeInputWindow(const ros::WallTime& now, const EngineCounters& c, double max_dt);
  /// Empty while most rate samples of the last complete window were used; else "most rate
  /// samples of the last second were lost (L of N): <the cause of most of them>".
  const std::string& problem() const { return input_window_problem_; }

 private:
  // The counters at the window's start, and the verdict on the last complete one.
  EngineCounters window_start_counters_;
  ros::WallTime window_start_;
  std::string input_window_problem_;  // empty: most rate samples were used
};

}  // namespace attitude_propagator
