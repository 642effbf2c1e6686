// What the engine knows of one input source's timeline (docs/design.md §6.5): the newest stamp it
// accepted, a run of stamps from an earlier time that may become a backward jump, and how far
// behind the clock its inputs arrive. An input is judged against the inputs of its own source,
// never against the clock: lateness is not a jump.
#pragma once

#include <cstdint>
#include <optional>

#include "attitude_propagator/time/time_policy.h"

namespace attitude_propagator {

/// A point in time: nanoseconds since the epoch, as ROS time. 64 bits hold every ros::Time
/// and every difference of two, so stamp arithmetic cannot overflow.
using Stamp = std::int64_t;

/// Inputs in a row, each further back than backward_jump from the newest and each going on from
/// the one before (later, by at most max_dt), that make a backward jump. One straggler is noise;
/// two can be a driver resending its last pair after a reconnect; three in order are a timeline
/// (a looped bag, a restarted driver). The engine holds the ones before it and uses them once
/// the jump is recognised (or drops them when the run breaks): no sample of a jump is lost.
constexpr int kJumpConfirmation = 3;

/// Weight of a new input in the mean lag (an exponential mean over about this many inputs'
/// reciprocal: 1/32 settles in about a hundred inputs and smooths transport jitter).
constexpr double kLagWeight = 1.0 / 32.0;

class SourceTimeline {
 public:
  enum class Verdict {
    InOrder,    ///< newer than the newest accepted: use it
    Straggler,  ///< at or before the newest (or a jump not yet confirmed): drop and count
    JumpedBack  ///< the kJumpConfirmation-th in a row from an earlier time: a new timeline
  };

  /// Judges `stamp` and remembers it when it is used (InOrder or JumpedBack).
  Verdict judge(Stamp stamp, const TimePolicy& policy);
  /// With the sensor-clock stamp filter, a stamp equal to the newest is in order: a FIFO read
  /// stamps its samples alike, and the filter gives each its own stamp (docs/numerics.md §3).
  void allowRepeatedStamps(bool allow) { repeats_ = allow; }

  /// Whether an input stamped `stamp`, at `clock`, jumps ahead of its source's newest by more
  /// than backward_jump, is stamped after the clock, and is ahead of the clock by more than
  /// backward_jump beyond how far its source's inputs arrive ahead (the mean lag): one such is
  /// a glitch, held (its stamp would make the next on-time inputs look like a jump back); the
  /// kJumpConfirmation-th in a row, each going on from the one before, is the source's new
  /// lead, and its lag is measured afresh. False before the lag is known.
  bool heldAhead(Stamp clock, Stamp stamp, const TimePolicy& policy);

  /// Records how far behind `clock` an input stamped `stamp` arrived (negative: ahead).
  void observeLag(Stamp clock, Stamp stamp);
  /// Mean clock - stamp of the inputs seen with a clock, in seconds; empty before the first.
  std::optional<double> lag() const { return lag_; }

  /// The newest stamp used, empty before the first.
  std::optional<Stamp> newest() const { return newest_; }
  /// How many inputs in a row, the last one judged included, make the run from an earlier time
  /// that may become a backward jump (0: none; reset to 0 when the jump is recognised).
  int run() const { return run_; }
  /// Forgets every stamp: time itself went back (the clock), so every stamp starts afresh.
  void forget() {
    newest_.reset();
    run_last_.reset();
    run_ = 0;
    lag_.reset();
    ahead_last_.reset();
    ahead_run_ = 0;
  }

 private:
  std::optional<Stamp> newest_;
  std::optional<Stamp> run_last_;  // the last stamp of the run from an earlier time
  int run_ = 0;
  std::optional<Stamp> ahead_last_;  // the last stamp of a run held ahead of the others
  int ahead_run_ = 0;
  std::optional<double> lag_;
  bool repeats_ = false;
};

/// Seconds of the followed clock without a tick of the other timeline after which a clock seen
/// on two timelines has settled on one; and how long after a jump back a return to the timeline
/// it left is taken for a second timeline (docs/design.md §6.5).
constexpr double kClockSettle = 5.0;

/// What the engine knows of ROS time itself (docs/design.md §6.5): the clock it follows, and
/// whether two timelines take turns on it (two /clock publishers: a stale simulator and a bag;
/// or one clock alternating between two times). A jump back by more than backward_jump starts
/// time again; a jump forward that returns, within kClockSettle, to the timeline the last jump
/// back left shows two timelines: from then on the later one is followed and the ticks of the
/// other are ignored (no reset), until the other has been silent for kClockSettle seconds of
/// the followed clock, or the followed one for kClockSettle seconds of the other (then time
/// has gone back for good: one reset).
class ClockTimeline {
 public:
  enum class Verdict {
    On,          ///< forward by at most max_dt, or back within backward_jump (jitter: it stays)
    Ahead,       ///< forward by more than max_dt: a gap
    JumpedBack,  ///< back by more than backward_jump: time starts again
    /// Forward to the timeline the last jump back left: two timelines. The later one is
    /// followed from this tick (a gap from the earlier one), without a reset.
    TwoTimelines,
    OtherTimeline,  ///< a tick of the earlier timeline while two are seen: ignored
  };

  Verdict judge(Stamp now, const TimePolicy& policy);
  /// The clock followed; empty before the first tick.
  std::optional<Stamp> now() const { return now_; }
  /// While two timelines are seen: the newest tick of the one not followed.
  std::optional<Stamp> other() const { return two_ ? other_ : std::nullopt; }

 private:
  std::optional<Stamp> now_;
  std::optional<Stamp> left_;     // the clock the last jump back left
  std::optional<Stamp> back_to_;  // where that jump landed
  bool two_ = false;
  std::optional<Stamp> other_;        // newest tick of the other timeline
  Stamp other_seen_at_ = 0;           // the followed clock when the other last ticked
  std::optional<Stamp> other_since_;  // the other's first tick since the followed one ticked
};

}  // namespace attitude_propagator
