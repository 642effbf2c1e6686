#include "attitude_propagator/time/time_policy.h"

namespace attitude_propagator {

bool isStale(double newest, double t) { return t <= newest; }

StampClass classifyStamp(double last, double t, const TimePolicy& policy) {
  if (isStale(last, t)) return StampClass::Stale;
  return t - last > policy.max_dt ? StampClass::Gap : StampClass::Forward;
}

bool stateHoldsAtStamp(StampOutcome outcome) {
  switch (outcome) {
    case StampOutcome::Anchored:
    case StampOutcome::Advanced:
    case StampOutcome::HeldGap:
    case StampOutcome::FailedStep:
      return true;
    case StampOutcome::DroppedStale:
    case StampOutcome::Waiting:
    case StampOutcome::RejectedNonFinite:
    case StampOutcome::RejectedOutOfRange:
      return false;
  }
  return false;
}

const char* outcomeName(StampOutcome outcome) {
  switch (outcome) {
    case StampOutcome::Anchored:
      return "anchored";
    case StampOutcome::Advanced:
      return "advanced";
    case StampOutcome::DroppedStale:
      return "dropped_stale";
    case StampOutcome::HeldGap:
      return "held_gap";
    case StampOutcome::Waiting:
      return "waiting";
    case StampOutcome::RejectedNonFinite:
      return "rejected_non_finite";
    case StampOutcome::RejectedOutOfRange:
      return "rejected_out_of_range";
    case StampOutcome::FailedStep:
      return "failed_step";
  }
  return "unknown";
}

}  // namespace attitude_propagator
