// The dynamic model's publish grid: states at whole multiples of 1/publish_rate in ROS time
// (docs/design.md §5.3).
#pragma once

#include <cstdint>

#include "attitude_propagator/time/source_timeline.h"

namespace attitude_propagator {

/// The grid stamp with index k: round(k / publish_rate) in ns.
Stamp gridStamp(std::int64_t k, double publish_rate);
/// The largest k with gridStamp(k, publish_rate) <= now.
std::int64_t gridIndexAtOrBefore(Stamp now, double publish_rate);

}  // namespace attitude_propagator
