// The time policy of docs/design.md §6, shared by the kinematic and the dynamic propagators so the
// node only forwards stamps.
#pragma once

namespace attitude_propagator {

/// What a propagator did with a stamped input.
enum class StampOutcome {
  Anchored,  // first input (or first after a reset): the state holds at this stamp
  Advanced,  // integrated up to the stamp
  /// Stamp at or before the last one, by any amount: a propagator never goes back in time. A
  /// backward jump that persists (a looped bag, a restarted driver) is the engine's to
  /// recognise (SourceTimeline); it then resets the propagator and anchors again.
  DroppedStale,
  HeldGap,  // gap longer than max_dt: not integrated across, state held, re-anchored
  /// Accepted, not integrated yet: a mean stamped at its interval's start or midpoint waits
  /// for the next sample to show where the interval ends (average_stamp). State unchanged.
  Waiting,
  RejectedNonFinite,  // NaN or infinite value or stamp: ignored, state unchanged
  /// A finite input beyond the door bounds of limits.h (a rate above kMaxBodyRate, a torque
  /// above kMaxTorque), whose energy, momentum or step would overflow: ignored, state unchanged.
  RejectedOutOfRange,
  /// The integrator could not complete the interval (step-size control failed, the closed form
  /// could not be evaluated, the result left the finite numbers or kMaxStateRate, or the call
  /// used up its step budget). Like a gap: the state at the last stamp is held and re-anchored
  /// at the new stamp; nothing of the failed interval is committed.
  FailedStep,
};

/// Thresholds of the policy, in seconds.
struct TimePolicy {
  double max_dt = 1.0;  ///< largest gap integrated across
  /// The engine's: a step back by more than this, when it persists (SourceTimeline) or when
  /// the clock itself steps back, starts time again (looped bag); less is a straggler or jitter.
  double backward_jump = 1.0;
};

enum class StampClass { Forward, Stale, Gap };

/// The one rule of staleness: a stamp at or before the newest one a model has taken, by any
/// amount, is stale (DroppedStale). classifyStamp applies it to the model's time, IntervalEnds
/// to the mean waiting for its interval's end.
bool isStale(double newest, double t);

/// Classifies stamp t against the last accepted stamp: stale (isStale), a gap beyond max_dt, or
/// a step forward.
StampClass classifyStamp(double last, double t, const TimePolicy& policy);

/// True for the outcomes after which the propagator's state holds at the new stamp.
bool stateHoldsAtStamp(StampOutcome outcome);

const char* outcomeName(StampOutcome outcome);

}  // namespace attitude_propagator
