#include "attitude_propagator/source_timeline.h"

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

void SourceTimeline::observeLag(Stamp clock, Stamp stamp) {
  const double lag = seconds(clock - stamp);
  lag_ = lag_ ? *lag_ + kLagWeight * (lag - *lag_) : lag;
}

}  // namespace attitude_propagator
