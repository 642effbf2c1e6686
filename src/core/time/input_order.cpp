#include "attitude_propagator/time/input_order.h"

namespace attitude_propagator {

SourceOrder::Judged SourceOrder::judge(Stamp stamp, std::optional<Stamp> clock,
                                       const TimePolicy& policy) {
  if (clock && line_.heldAhead(*clock, stamp, policy)) {
    // One forward glitch: taken, it would make the on-time inputs after it a jump back. It
    // neither goes on with the run from an earlier time nor breaks it.
    return {OrderVerdict::HeldAhead, false};
  }
  const SourceTimeline::Verdict verdict = line_.judge(stamp, policy);
  // A jump's lag is observed once the model has restarted (observeLag), which may forget it.
  if (verdict == SourceTimeline::Verdict::JumpedBack) return {OrderVerdict::JumpedBack, false};
  // The run held so far is over unless this input goes on with it.
  const bool run_broke = line_.run() <= 1;
  if (verdict == SourceTimeline::Verdict::Straggler) {
    return {line_.run() >= 1 ? OrderVerdict::HeldInRun : OrderVerdict::Stale, run_broke};
  }
  observeLag(clock, stamp);
  return {OrderVerdict::Use, run_broke};
}

void SourceOrder::startAgainAt(Stamp stamp, const TimePolicy& policy) {
  line_.judge(stamp, policy);  // forgotten with the rest: the first again
}

void SourceOrder::forget() { line_.forget(); }

void SourceOrder::observeLag(std::optional<Stamp> clock, Stamp stamp) {
  if (clock) line_.observeLag(*clock, stamp);
}

}  // namespace attitude_propagator
