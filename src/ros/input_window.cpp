#include "attitude_propagator/ros/input_window.h"

#include <algorithm>
#include <cstdint>
#include <cstdio>

namespace attitude_propagator {

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
  const Loss losses[] = {
      {c.gaps - s.gaps, gap_cause},
      {c.dropped_stale - s.dropped_stale,
       "stamps at or before the previous one (two publishers on one topic, or a source that "
       "loops)"},
      {c.rejected_future - s.rejected_future,
       "stamps more than max_future ahead of ROS time (clocks not synchronised?)"},
      {c.held_ahead - s.held_ahead, "stamps further ahead of ROS time than their stream's"},
      {c.rejected_non_finite - s.rejected_non_finite, "NaN or infinite rates or stamps"},
      {c.rejected_out_of_range - s.rejected_out_of_range, "rates out of the accepted range"},
      {c.rejected_no_rate - s.rejected_no_rate,
       "angular_velocity_covariance[0] == -1 (REP-145: no rate)"},
      {c.rejected_type - s.rejected_type, "a message type the topic does not take"},
      {c.rejected_covariance - s.rejected_covariance, "rate covariances that are not ones"},
      {c.dropped_no_tf - s.dropped_no_tf, "no transform from the rates' frame to the body yet"},
      {c.dropped_no_time - s.dropped_no_time, "unstamped messages before the first /clock"},
  };
  std::uint64_t lost = 0;
  const Loss* worst = &losses[0];
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
