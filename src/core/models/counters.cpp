#include "attitude_propagator/models/counters.h"

namespace attitude_propagator {

const char* counterInputName(CounterInput input) {
  switch (input) {
    case CounterInput::RateOrTorque:
      return "rate/torque";
    case CounterInput::Rate:
      return "rate";
    case CounterInput::Bias:
      return "bias";
    case CounterInput::Fix:
      return "fix";
    case CounterInput::Accel:
      return "accel";
    case CounterInput::Mag:
      return "mag";
    case CounterInput::Clock:
      return "clock";
    case CounterInput::Any:
      return "any";
  }
  return "?";
}

const char* counterKindName(CounterKind kind) {
  switch (kind) {
    case CounterKind::Received:
      return "received";
    case CounterKind::Used:
      return "used";
    case CounterKind::Unused:
      return "unused";
    case CounterKind::Event:
      return "event";
  }
  return "?";
}

namespace {

using C = EngineCounters;
using In = CounterInput;
using Kind = CounterKind;

/// The counters that are fields of EngineCounters itself, in the diagnostics' order.
std::vector<CounterInfo> ownCounters() {
  return {
      {"received", "every rate or torque input submitted or rejected", In::RateOrTorque,
       Kind::Received, &C::received},
      {"accepted", "handed to the model", In::RateOrTorque, Kind::Used, &C::accepted},
      {"rejected_non_finite", "a NaN or infinite stamp, value or covariance", In::RateOrTorque,
       Kind::Unused, &C::rejected_non_finite},
      {"rejected_out_of_range",
       "a rate above 1e5 rad/s, a torque above 1e28 N m, or energy that would overflow",
       In::RateOrTorque, Kind::Unused, &C::rejected_out_of_range},
      {"rejected_no_rate", "REP-145: angular_velocity_covariance[0] == -1", In::Rate, Kind::Unused,
       &C::rejected_no_rate},
      {"rejected_type", "a message type the topic does not take", In::RateOrTorque, Kind::Unused,
       &C::rejected_type},
      {"rejected_covariance", "a rate covariance not symmetric, negative or above 1e6 rad²/s²",
       In::Rate, Kind::Unused, &C::rejected_covariance},
      {"dropped_stale",
       "stamped at or before the newest input of its source (a straggler, a run that broke "
       "before it was a jump back, a rate older than a set_state)",
       In::RateOrTorque, Kind::Unused, &C::dropped_stale},
      {"dropped_no_tf", "its frame unknown to tf, or a frame id refused", In::RateOrTorque,
       Kind::Unused, &C::dropped_no_tf},
      {"dropped_no_time", "unstamped, before the first ROS time (sim time, no /clock yet)",
       In::RateOrTorque, Kind::Unused, &C::dropped_no_time},
      {"late", "dynamic model: arrived after the clock passed its stamp", In::RateOrTorque,
       Kind::Event, &C::late},
      {"gaps", "a gap longer than max_dt (stamps, or ROS time): the state held", In::Any,
       Kind::Event, &C::gaps},
      {"resets", "the state back to the initial one: time went back, or reset()", In::Any,
       Kind::Event, &C::resets},
      {"jumps_back", "a source's stamps went back, and persisted", In::RateOrTorque, Kind::Event,
       &C::jumps_back},
      {"clock_conflicts",
       "two timelines recognised on the clock: the later followed, the other's ticks ignored",
       In::Clock, Kind::Event, &C::clock_conflicts},
      {"rejected_future", "stamped more than max_future ahead of the clock", In::RateOrTorque,
       Kind::Unused, &C::rejected_future},
      {"held_ahead",
       "jumped ahead of its source and of the clock beyond its source's lead, not yet "
       "confirmed: dropped",
       In::RateOrTorque, Kind::Unused, &C::held_ahead},
      {"dropped_on_reset", "dynamic model: waiting for the clock when a reset came",
       In::RateOrTorque, Kind::Unused, &C::dropped_on_reset},
      {"failed_steps", "the integrator could not complete an interval: the state held", In::Any,
       Kind::Event, &C::failed_steps},
      {"pending_overflow", "dynamic model: the queue full, the one furthest ahead dropped",
       In::RateOrTorque, Kind::Unused, &C::pending_overflow},
      {"deferred_ticks", "dynamic model: grid stamps left for the next call (its budget)",
       In::Clock, Kind::Event, &C::deferred_ticks},
      {"rejected_bias", "refused: non-finite, too large, another frame, or beyond max_future",
       In::Bias, Kind::Unused, &C::rejected_bias},
      {"bias_queue_full", "64 samples waiting: the one furthest ahead dropped", In::Bias,
       Kind::Unused, &C::bias_queue_full},
      {"bias_applied", "took effect (a rate reached its stamp)", In::Bias, Kind::Used,
       &C::bias_applied},
      {"fixes_accepted", "applied (fused, or as a reset)", In::Fix, Kind::Used, &C::fixes_accepted},
      {"fixes_reset", "of those, applied as a reset (fix_mode reset, or a run of gated ones)",
       In::Fix, Kind::Event, &C::fixes_reset},
      {"fixes_rejected_gate", "fuse: the innovation beyond the chi-square gate", In::Fix,
       Kind::Unused, &C::fixes_rejected_gate},
      {"fixes_too_old", "stamped before the history (or before the anchor)", In::Fix, Kind::Unused,
       &C::fixes_too_old},
      {"fixes_bad_quaternion", "non-finite, or not of unit norm", In::Fix, Kind::Unused,
       &C::fixes_bad_quaternion},
      {"fixes_bad_covariance", "non-finite, asymmetric, negative or above pi^2", In::Fix,
       Kind::Unused, &C::fixes_bad_covariance},
      {"fixes_queue_full", "ahead of the newest rate, the queue full: dropped", In::Fix,
       Kind::Unused, &C::fixes_queue_full},
      {"fixes_future", "stamped more than max_future ahead of the clock", In::Fix, Kind::Unused,
       &C::fixes_future},
      {"fixes_over_budget", "late, its replay beyond the second's budget", In::Fix, Kind::Unused,
       &C::fixes_over_budget},
  };
}

/// The rows of aidingCounterTable() under `prefix` (accel_, mag_).
void appendAidingCounters(std::vector<CounterInfo>& table, const std::string& prefix,
                          CounterInput input) {
  for (const AidingCounterInfo& a : aidingCounterTable()) {
    table.push_back({prefix + a.name, a.meaning, input, a.applied ? Kind::Used : Kind::Unused,
                     nullptr, a.field});
  }
}

std::vector<CounterInfo> makeTable() {
  std::vector<CounterInfo> table = ownCounters();
  appendAidingCounters(table, "accel_", In::Accel);
  appendAidingCounters(table, "mag_", In::Mag);
  return table;
}

/// The AidingCounters an accel or mag row's field lies in.
const AidingCounters& aidingOf(const EngineCounters& c, const CounterInfo& info) {
  return info.input == In::Mag ? c.mag : c.accel;
}
AidingCounters& aidingOf(EngineCounters& c, const CounterInfo& info) {
  return info.input == In::Mag ? c.mag : c.accel;
}

}  // namespace

const std::vector<CounterInfo>& engineCounterTable() {
  static const std::vector<CounterInfo> table = makeTable();
  return table;
}

std::uint64_t counterValue(const EngineCounters& c, const CounterInfo& info) {
  return info.field != nullptr ? c.*info.field : aidingOf(c, info).*info.aiding_field;
}

std::uint64_t& counterField(EngineCounters& c, const CounterInfo& info) {
  if (info.field != nullptr) return c.*info.field;
  AidingCounters& aiding = aidingOf(c, info);
  return aiding.*info.aiding_field;
}

const char* counterName(std::uint64_t EngineCounters::*field) {
  for (const CounterInfo& info : engineCounterTable()) {
    if (info.field == field) return info.name.c_str();
  }
  return "?";
}

bool countsUnusedInput(const CounterInfo& info) {
  return info.kind == Kind::Unused && (info.input == In::RateOrTorque || info.input == In::Rate);
}

std::uint64_t fixesNotApplied(const EngineCounters& c) {
  std::uint64_t n = 0;
  for (const CounterInfo& info : engineCounterTable()) {
    if (info.input == In::Fix && info.kind == Kind::Unused) n += counterValue(c, info);
  }
  return n;
}

}  // namespace attitude_propagator
