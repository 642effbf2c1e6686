// The bag tools' account of the gravity and field samples (use_accel, use_mag): one line each,
// the counters under the names the node's diagnostics give them (messages/aiding_counters.h).
#pragma once

#include <cstdio>
#include <string>

#include "attitude_propagator/engine.h"

namespace attitude_propagator {
namespace tools {

/// "accel_accepted 10, accel_aligned 1, ..." for the counters whose names start with `prefix`
/// (accel_ or mag_), every one of them, zeros included, in the core's order.
std::string aidingCountersText(const EngineCounters& c, const std::string& prefix);

/// Prints "  accel: ..." and "  mag: ..." for the kinds configured, and the samples read of each
/// (`accel_read`: Imu messages with an acceleration, `mag_read`: field messages).
void printAidingSummary(std::FILE* out, const EngineCounters& c, bool use_accel, bool use_mag,
                        unsigned long long accel_read, unsigned long long mag_read);

}  // namespace tools
}  // namespace attitude_propagator
