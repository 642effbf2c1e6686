#include "attitude_propagator/time/average_stamp.h"

#include <algorithm>
#include <stdexcept>

#include "attitude_propagator/quoted_text.h"
#include "attitude_propagator/time/time_policy.h"

namespace attitude_propagator {

AverageStamp averageStampFromName(const std::string& name) {
  if (name == "end") return AverageStamp::End;
  if (name == "mid") return AverageStamp::Mid;
  if (name == "start") return AverageStamp::Start;
  throw std::invalid_argument("average_stamp: unknown value '" + logText(name) +
                              "'; accepted: end mid start");
}

std::string averageStampName(AverageStamp position) {
  switch (position) {
    case AverageStamp::Mid:
      return "mid";
    case AverageStamp::Start:
      return "start";
    case AverageStamp::End:
      break;
  }
  return "end";
}

double IntervalEnds::nominalPeriod(double interval) const {
  const std::size_t n = std::min(count_, intervals_.size());
  if (n < 3) return interval;  // too few to tell a loss from the period
  std::array<double, 5> sorted = intervals_;
  std::nth_element(sorted.begin(), sorted.begin() + n / 2, sorted.begin() + n);
  return sorted[n / 2];
}

IntervalEnds::Pushed IntervalEnds::push(const RateSample& next) {
  Pushed pushed;
  if (held_ && isStale(held_->t, next.t)) {
    pushed.stale = true;
    return pushed;
  }
  if (held_) {
    const double interval = next.t - held_->t;
    const double period = nominalPeriod(interval);
    // Regular: the interval reaches the next stamp (start) or the boundary halfway to it (mid).
    const double length = interval <= 1.5 * period ? interval : period;
    pushed.ended =
        RateSample{held_->t + (position_ == AverageStamp::Mid ? 0.5 : 1.0) * length, held_->w_B};
    intervals_[count_++ % intervals_.size()] = interval;
  }
  held_ = next;
  return pushed;
}

void IntervalEnds::clear() {
  held_.reset();
  count_ = 0;
}

}  // namespace attitude_propagator
