#include "attitude_propagator/ros/input_window.h"

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <map>
#include <vector>

#include "attitude_propagator/models/counters.h"

namespace attitude_propagator {

const char* inputLossAdvice(const std::string& counter) {
  // What to look at, for the causes a user can act on; the rest are told by their meaning.
  static const std::map<std::string, const char*> advice = {
      {"dropped_stale",
       "stamps at or before the previous one (two publishers on one topic, or a source that "
       "loops)"},
      {"rejected_future",
       "stamps more than max_future ahead of ROS time (clocks not synchronised?)"},
      {"held_ahead", "stamps further ahead of ROS time than their stream's"},
      {"rejected_non_finite", "NaN or infinite rates or stamps"},
      {"rejected_out_of_range", "rates out of the accepted range"},
      {"rejected_no_rate", "angular_velocity_covariance[0] == -1 (REP-145: no rate)"},
      {"rejected_type", "a message type the topic does not take"},
      {"rejected_covariance", "rate covariances that are not ones"},
      {"dropped_no_tf", "no transform from the rates' frame to the body yet"},
      {"dropped_no_time", "unstamped messages before the first /clock"},
  };
  const auto it = advice.find(counter);
  return it == advice.end() ? nullptr : it->second;
}

void InputWindow::closeInputWindow(const ros::WallTime& now, const EngineCounters& c,
                                   double max_dt) {
  if (window_start_.isZero()) {
    window_start_ = now;
    window_start_counters_ = c;
    return;
  }
  const double seconds = (now - window_start_).toSec();
  if (seconds < kInputWindow) return;
  const EngineCounters& s = window_start_counters_;
  // Counts of rate samples lost in the window, by cause. Torque counts with them: the
  // counters do not tell the sources apart (a torque topic rarely fails alone).
  struct Loss {
    std::uint64_t count;
    std::string cause;
  };
  const std::uint64_t received = c.received - s.received;
  const double period = received > 0 ? seconds / static_cast<double>(received) : 0.0;
  char gap_cause[160];
  if (max_dt < period) {
    std::snprintf(gap_cause, sizeof(gap_cause), "max_dt %g s is below the input period %g s",
                  max_dt, period);
  } else {
    std::snprintf(gap_cause, sizeof(gap_cause),
                  "gaps longer than max_dt %g s (input period %g s): messages lost on the way "
                  "or stamps far apart",
                  max_dt, period);
  }
  // Every counter of an input left unused (the core's table), after the gaps; the node's
  // advice for its cause where it has one, else the table's meaning.
  std::vector<Loss> losses{{c.gaps - s.gaps, gap_cause}};
  forEachEngineCounter(c, [&](const CounterInfo& info, std::uint64_t n) {
    if (!countsUnusedInput(info)) return;
    const char* advice = inputLossAdvice(info.name);
    losses.push_back({n - counterValue(s, info), advice != nullptr ? advice : info.meaning});
  });
  std::uint64_t lost = 0;
  const Loss* worst = &losses.front();
  for (const Loss& loss : losses) {
    lost += loss.count;
    if (loss.count > worst->count) worst = &loss;
  }
  input_window_problem_.clear();
  // Half or more lost: WARN (a stream at half its rate is no longer the one configured).
  if (received > 0 && 2 * lost >= received) {
    input_window_problem_ = "half or more of the rate samples of the last second were lost (" +
                            std::to_string(std::min(lost, received)) + " of " +
                            std::to_string(received) + "): " + worst->cause;
  }
  window_start_ = now;
  window_start_counters_ = c;
}

}  // namespace attitude_propagator
