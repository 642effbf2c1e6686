// The log line for each EngineNote: what the engine tells the node about its input and time
// (a gap, a jump, a refused stamp ...), as text with the count of its kind so far. Pure: the
// wrapper logs the line, throttled per kind.
#pragma once

#include <string>

#include "attitude_propagator/config/parameters.h"
#include "attitude_propagator/models/propagator.h"
#include "attitude_propagator/ros/log_text.h"

namespace attitude_propagator {

/// The warning for `note`, counted from `c` (the counters after the note); `p` gives max_dt
/// and max_future, `dynamic_model` what a backward jump of stamps did. The kind is the
/// note's kind. `clock_sources` names the /clock publishers of two timelines (clockSourcesText),
/// for ClockTwoTimelines (clockPublishersText).
LogLine noteText(const EngineNote& note, const EngineCounters& c, const Parameters& p,
                 bool dynamic_model, const std::string& clock_sources = "");

}  // namespace attitude_propagator
