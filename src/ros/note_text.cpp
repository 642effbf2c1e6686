#include "attitude_propagator/ros/note_text.h"

#include <cstdint>
#include <string>

#include "attitude_propagator/messages/input_decoders.h"
#include "attitude_propagator/models/kinematic_propagator.h"
#include "attitude_propagator/models/outcome_table.h"
#include "attitude_propagator/time/stamp_filter.h"

namespace attitude_propagator {

namespace {

std::string noteText(const EngineNote& note, const EngineCounters& c, const Parameters& p,
                     bool dynamic_model, const char* what, double t,
                     const std::string& clock_sources) {
  // The count each note reports is its kind's counter in the outcome table (noteCounter).
  const std::uint64_t EngineCounters::*counter = noteCounter(note.kind);
  const std::uint64_t so_far = counter ? c.*counter : 0;
  switch (note.kind) {
    case EngineNote::Gap:
      return formatted(
          "%s: gap longer than max_dt = %g s or %g periods of the stream before %.6f: not "
          "integrated across, state held (%lu gaps so far)",
          what, p.max_dt, kGapPeriods, t, so_far);
    case EngineNote::StampsJumpedBack:
      return formatted(
          "%s: stamps jumped back to %.3f and went on from there (looped bag, restarted "
          "driver?): %s (%lu jumps so far)",
          what, t,
          dynamic_model ? "its inputs now act late, on ROS time" : "reset to the initial state",
          so_far);
    case EngineNote::Future:
      return formatted(
          "%s: stamp %.6f more than max_future = %g s ahead of ROS time: rejected (%lu so far; "
          "unsynchronised clocks?)",
          what, t, p.max_future, so_far);
    case EngineNote::ClockJumpedBack:
      return formatted(
          "ROS time jumped back to %.3f s (looped bag or restarted clock): reset to the initial "
          "state (%lu resets so far)",
          t, so_far);
    case EngineNote::ClockTwoTimelines:
      return formatted(
          "ROS time takes turns between two timelines (%s; the other at %.3f s): two /clock "
          "publishers? The later one is followed and the other's ticks ignored, no further "
          "reset until one falls silent for %g s (%lu times so far)",
          clock_sources.empty() ? "publishers unknown" : clock_sources.c_str(), t, kClockSettle,
          so_far);
    case EngineNote::Stale:
      return formatted("%s: stamp %.6f at or before the last one: dropped (%lu so far)", what, t,
                       so_far);
    case EngineNote::NonFinite:
      return formatted("%s: NaN or infinite value or stamp: rejected (%lu so far)", what, so_far);
    case EngineNote::OutOfRange:
      return formatted(
          "%s: value out of the accepted range (its energy or step would overflow): rejected "
          "(%lu so far)",
          what, so_far);
    case EngineNote::FailedStep:
      return formatted(
          "%s: the integrator could not complete the step to %.6f: state held (%lu failed so "
          "far)",
          what, t, so_far);
    case EngineNote::PendingFull:
      return formatted(
          "%s: more inputs stamped ahead of ROS time than the queue holds: the one stamped "
          "furthest ahead dropped (%lu so far)",
          what, so_far);
    case EngineNote::HeldAhead:
      return formatted(
          "%s: stamp %.6f further ahead of ROS time than its stream by more than %g s: dropped "
          "until %d in a row confirm it (%lu so far)",
          what, t, p.time_jump_threshold, kJumpConfirmation, so_far);
    case EngineNote::StampFilterMisfit:
      return formatted(
          "%s: the stamps do not fit one sensor period (stamp jitter %.3g ms against a period of "
          "%.3g ms, more than %g periods): stamp_filter uses the receipt stamps until they fit "
          "again (below %g periods); diagnostics stamp_filter_misfit",
          what, note.jitter * 1e3, note.period * 1e3, kMisfitJitter, kFitAgainJitter);
    case EngineNote::Deferred:
      return formatted(
          "publishing fell behind ROS time at %.3f s: the rest of the grid follows on the next "
          "tick (%lu so far)",
          t, so_far);
  }
  return {};
}

}  // namespace

LogLine noteText(const EngineNote& note, const EngineCounters& c, const Parameters& p,
                 bool dynamic_model, const std::string& clock_sources) {
  const char* what = note.source ? inputTopicName(*note.source) : "ROS time";
  const double t = static_cast<double>(note.stamp) * 1e-9;
  return {ros::console::levels::Warn, "note " + std::to_string(note.kind),
          noteText(note, c, p, dynamic_model, what, t, clock_sources)};
}

}  // namespace attitude_propagator
