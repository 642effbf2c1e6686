// The bag tools' account of the gravity and field samples (use_accel, use_mag): one line each,
// the counters under the names the node's diagnostics give them (messages/aiding_counters.h).
#pragma once

#include <cstdio>
#include <string>

#include "attitude_propagator/engine.h"
#include "attitude_propagator/estimation/hard_iron_fit.h"

namespace attitude_propagator {
namespace tools {

/// "accel_accepted 10, accel_aligned 1, ..." for the counters whose names start with `prefix`
/// (accel_ or mag_), every one of them, zeros included, in the core's order.
std::string aidingCountersText(const EngineCounters& c, const std::string& prefix);

/// Prints "  accel: ..." and "  mag: ..." for the kinds configured, and the samples read of each
/// (`accel_read`: Imu messages with an acceleration, `mag_read`: field messages).
void printAidingSummary(std::FILE* out, const EngineCounters& c, bool use_accel, bool use_mag,
                        unsigned long long accel_read, unsigned long long mag_read);

/// Prints "  mag_bias from the reads: [x, y, z] T ..." with the sphere the field reads lie on
/// (HardIronFit): its centre is the `mag_bias` to give, said to be determined or not, or that
/// the reads fix no sphere.
void printFieldFit(std::FILE* out, const HardIronFit& fit);

}  // namespace tools
}  // namespace attitude_propagator
