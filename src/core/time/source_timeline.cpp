#include "attitude_propagator/time/source_timeline.h"

#include <algorithm>

namespace attitude_propagator {

namespace {
double seconds(Stamp ns) { return static_cast<double>(ns) * 1e-9; }
}  // namespace

SourceTimeline::Verdict SourceTimeline::judge(Stamp stamp, const TimePolicy& policy) {
  if (!newest_ || stamp > *newest_ || (repeats_ && stamp == *newest_)) {
    newest_ = stamp;
    run_ = 0;
    run_last_.reset();
    return Verdict::InOrder;
  }
  if (seconds(*newest_ - stamp) <= policy.backward_jump) {
    run_ = 0;  // a straggler within the threshold interrupts a run from an earlier time
    run_last_.reset();
    return Verdict::Straggler;
  }
  const bool goes_on =
      run_last_ && stamp > *run_last_ && seconds(stamp - *run_last_) <= policy.max_dt;
  run_ = goes_on ? run_ + 1 : 1;
  run_last_ = stamp;
  if (run_ < kJumpConfirmation) return Verdict::Straggler;
  newest_ = stamp;
  run_ = 0;
  run_last_.reset();
  return Verdict::JumpedBack;
}

bool SourceTimeline::heldAhead(Stamp clock, Stamp stamp, const TimePolicy& policy) {
  // A jump ahead of its own source (by more than backward_jump after the newest) that its
  // usual lead does not explain: lead - usual lead = (stamp - clock) - (-lag). A stream that
  // goes on ahead of a clock that stands still jumps nowhere.
  // Only a stamp ahead of the clock is held: a stream that resumes later but still behind the
  // clock (after a gap, a reset, a new base) is a gap, not a glitch.
  const bool jumps = newest_ && seconds(stamp - *newest_) > policy.backward_jump;
  if (!jumps || !lag_ || stamp <= clock || seconds(stamp - clock) + *lag_ <= policy.backward_jump) {
    ahead_run_ = 0;  // an input where the others are interrupts a run
    ahead_last_.reset();
    return false;
  }
  const bool goes_on =
      ahead_last_ && stamp > *ahead_last_ && seconds(stamp - *ahead_last_) <= policy.max_dt;
  ahead_run_ = goes_on ? ahead_run_ + 1 : 1;
  ahead_last_ = stamp;
  if (ahead_run_ < kJumpConfirmation) return true;
  ahead_run_ = 0;
  ahead_last_.reset();
  lag_.reset();  // the new lead, from this input on
  return false;
}

void SourceTimeline::observeLag(Stamp clock, Stamp stamp) {
  const double lag = seconds(clock - stamp);
  lag_ = lag_ ? *lag_ + kLagWeight * (lag - *lag_) : lag;
}

ClockTimeline::Verdict ClockTimeline::judge(Stamp now, const TimePolicy& policy) {
  if (!now_) {
    now_ = now;
    return Verdict::On;
  }
  if (two_) {
    if (seconds(*now_ - now) > policy.backward_jump) {  // the other timeline
      if (!other_since_) other_since_ = now;
      other_ = now;
      other_seen_at_ = *now_;
      if (seconds(now - *other_since_) <= kClockSettle) return Verdict::OtherTimeline;
      // The followed timeline fell silent while the other went on: time went back for good.
      two_ = false;
      other_.reset();
      other_since_.reset();
      left_ = *now_;
      back_to_ = now;
      now_ = now;
      return Verdict::JumpedBack;
    }
    other_since_.reset();
    if (seconds(now - other_seen_at_) > kClockSettle) {  // settled on the followed timeline
      two_ = false;
      other_.reset();
    }
  }
  if (seconds(*now_ - now) > policy.backward_jump) {
    left_ = *now_;
    back_to_ = now;
    now_ = now;
    return Verdict::JumpedBack;
  }
  if (left_ && seconds(*now_ - *back_to_) > kClockSettle) left_.reset();  // a real jump back
  const double ahead = seconds(now - *now_);
  if (left_ && ahead > policy.backward_jump && seconds(*left_ - now) < policy.backward_jump &&
      seconds(now - *left_) <= seconds(*now_ - *back_to_) + policy.max_dt) {
    // Back on the timeline the last jump back left, where it would be by now: two timelines.
    two_ = true;
    other_ = *now_;
    other_seen_at_ = now;
    other_since_.reset();
    left_.reset();
    now_ = now;
    return Verdict::TwoTimelines;
  }
  if (ahead > policy.max_dt) {
    now_ = now;
    return Verdict::Ahead;
  }
  now_ = std::max(*now_, now);
  return Verdict::On;
}

}  // namespace attitude_propagator
