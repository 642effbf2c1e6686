// What happened to input and time, counted: EngineCounters, and the one table that gives each
// counter its name (the node's diagnostics key), its meaning and the input it counts. The node's
// diagnostics, propagate_bag's summary and docs/node.md's table of the counters follow the
// table (test/core/test_counter_table.cpp holds the docs to it). The counters themselves are
// plain fields, incremented where the outcome happens; the table is read only to report them.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "attitude_propagator/estimation/aiding.h"

namespace attitude_propagator {

/// What happened to input and time, for diagnostics. Every counter only grows.
struct EngineCounters {
  std::uint64_t received = 0;  ///< every input submitted or rejected
  std::uint64_t accepted = 0;
  std::uint64_t rejected_non_finite = 0;
  std::uint64_t rejected_out_of_range = 0;
  std::uint64_t rejected_no_rate = 0;     ///< REP-145: angular_velocity_covariance[0] == -1
  std::uint64_t rejected_type = 0;        ///< a message type the topic does not take
  std::uint64_t rejected_covariance = 0;  ///< not symmetric, negative or huge
  /// At or before the newest input of its source (a straggler, by any amount; a run from an
  /// earlier time that broke before it was a jump, counted when it broke; a rate older than a
  /// set_state). The inputs of a run are counted when it breaks or is a jump (then as used).
  std::uint64_t dropped_stale = 0;
  std::uint64_t dropped_no_tf = 0;
  std::uint64_t dropped_no_time = 0;
  std::uint64_t late = 0;        ///< dynamic: arrived after the clock passed its stamp
  std::uint64_t gaps = 0;        ///< longer than max_dt: state held
  std::uint64_t resets = 0;      ///< the state back to the initial one: time went back, reset()
  std::uint64_t jumps_back = 0;  ///< a source's stamps went back, and persisted
  /// Two timelines recognised on the clock (ClockTimeline: two /clock publishers): the later
  /// one followed, the other's ticks ignored, no reset.
  std::uint64_t clock_conflicts = 0;
  std::uint64_t rejected_future = 0;  ///< stamped more than max_future ahead of the clock
  /// Jumped ahead of its source and of the clock by more than backward_jump beyond its source's
  /// usual lead, and not yet
  /// confirmed by kJumpConfirmation in a row: dropped (SourceTimeline::heldAhead).
  std::uint64_t held_ahead = 0;
  /// Dynamic: queued inputs a reset dropped (reset(), ROS time jumping back).
  std::uint64_t dropped_on_reset = 0;
  std::uint64_t failed_steps = 0;      ///< the integrator could not complete an interval
  std::uint64_t pending_overflow = 0;  ///< dynamic: queue full, the furthest ahead dropped
  std::uint64_t deferred_ticks = 0;    ///< dynamic: grid stamps left for the next call (budget)
  /// Gyro bias samples refused: non-finite, too large, another frame, or stamped more than
  /// max_future ahead of the clock.
  std::uint64_t rejected_bias = 0;
  std::uint64_t bias_queue_full = 0;  ///< 64 bias samples waiting: the furthest ahead dropped
  std::uint64_t bias_applied = 0;     ///< bias samples that took effect (a rate reached them)
  // Absolute attitude fixes (AttitudeEngine::submitFix, docs/design.md §6.9).
  std::uint64_t fixes_accepted = 0;  ///< applied (fused, or as a reset)
  std::uint64_t fixes_reset = 0;     ///< of those, applied as a reset (fix_mode reset, or a run)
  std::uint64_t fixes_rejected_gate = 0;   ///< fuse: the innovation beyond the chi-square gate
  std::uint64_t fixes_too_old = 0;         ///< stamped before the history (or before the anchor)
  std::uint64_t fixes_bad_quaternion = 0;  ///< non-finite, or not of unit norm
  std::uint64_t fixes_bad_covariance = 0;  ///< non-finite, asymmetric, negative or above pi^2
  std::uint64_t fixes_queue_full = 0;      ///< ahead of the newest rate, the queue full: dropped
  std::uint64_t fixes_future = 0;          ///< stamped more than max_future ahead of the clock
  std::uint64_t fixes_over_budget = 0;     ///< late, its replay beyond the second's budget
  // Gravity (use_accel) and the magnetic field (use_mag) as measurements (docs/design.md §6.10),
  // named accel_* and mag_* after AidingCounters::forEach.
  AidingCounters accel;
  AidingCounters mag;
};

/// Which input a counter counts.
enum class CounterInput {
  RateOrTorque,  ///< a rate or torque input (the counters do not tell the two apart)
  Rate,          ///< a rate input only
  Bias,          ///< a gyro bias sample
  Fix,           ///< an absolute attitude fix
  Accel,         ///< a gravity sample (use_accel)
  Mag,           ///< a magnetic field sample (use_mag)
  Clock,         ///< ROS time
  Any,           ///< whatever moves time: an input or the clock
};
/// "rate/torque", "rate", "bias", "fix", "accel", "mag", "clock" or "any" (docs/node.md).
const char* counterInputName(CounterInput input);

/// What a counter says of the inputs it counts.
enum class CounterKind {
  Received,  ///< every input taken: the used and unused ones add up to it (with those pending)
  Used,      ///< applied to the state
  Unused,    ///< refused or dropped: the input left the engine unused
  Event,     ///< something that befell time or inputs already counted (a gap, a reset)
};
/// "received", "used", "unused" or "event" (docs/node.md).
const char* counterKindName(CounterKind kind);

/// One counter of EngineCounters: its diagnostics name, its meaning (one sentence), the input it
/// counts, what it says of it, and its field: a field of EngineCounters, or (accel and mag) a
/// field of AidingCounters in EngineCounters::accel or ::mag.
struct CounterInfo {
  std::string name;
  std::string meaning;
  CounterInput input = CounterInput::Any;
  CounterKind kind = CounterKind::Event;
  std::uint64_t EngineCounters::*field = nullptr;
  std::uint64_t AidingCounters::*aiding_field = nullptr;
};

/// Every counter of EngineCounters once, in the order the diagnostics publish them and
/// docs/node.md lists them: the rate and torque counters, the bias, the fixes, then accel_* and
/// mag_* (aidingCounterTable() under each prefix).
const std::vector<CounterInfo>& engineCounterTable();

/// The value of `info`'s counter in `c`, and the counter itself.
std::uint64_t counterValue(const EngineCounters& c, const CounterInfo& info);
std::uint64_t& counterField(EngineCounters& c, const CounterInfo& info);

/// The table's name of a field of EngineCounters ("?" for none).
const char* counterName(std::uint64_t EngineCounters::*field);

/// True for the counters of rate and torque inputs left unused: with `accepted` and the inputs
/// still pending they add up to `received` (each input is submitted or rejected exactly once).
bool countsUnusedInput(const CounterInfo& info);

/// Calls f(info, value) for each counter of engineCounterTable(), in its order.
template <class F>
void forEachEngineCounter(const EngineCounters& c, F&& f) {
  for (const CounterInfo& info : engineCounterTable()) f(info, counterValue(c, info));
}

/// Calls f(name, value) for each of the engine's fix counters (the table's rows of input Fix),
/// without their `fixes_` prefix: the one list the diagnostics, propagate_bag's summary and the
/// sums of fixes not applied follow.
template <class F>
void forEachFixCounter(const EngineCounters& c, F&& f) {
  const std::size_t prefix = std::string("fixes_").size();
  for (const CounterInfo& info : engineCounterTable()) {
    if (info.input == CounterInput::Fix) f(info.name.c_str() + prefix, counterValue(c, info));
  }
}

/// The fixes the engine took and did not apply: every fix counter of kind Unused (all but
/// `accepted` and `reset`, the applied ones, resets among them).
std::uint64_t fixesNotApplied(const EngineCounters& c);

}  // namespace attitude_propagator
