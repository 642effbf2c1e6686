// Where in its interval an averaged rate sample is stamped (`average_stamp`), and the one rule
// that turns start- and mid-stamped means into the end-stamped ones the integrators read
// (docs/numerics.md §3): a sample's interval ends where the next one's begins.
#pragma once

#include <array>
#include <cstddef>
#include <optional>
#include <string>

#include "attitude_propagator/numerics/kinematic_step.h"
#include "attitude_propagator/time/time_policy.h"

namespace attitude_propagator {

enum class AverageStamp {
  End,    ///< the mean over (previous stamp, stamp]: delta-angle / dt as most drivers stamp it
  Mid,    ///< the mean over the interval whose midpoint is the stamp
  Start,  ///< the mean over the interval that starts at the stamp
};

/// Parses an `average_stamp` value; throws std::invalid_argument naming the accepted values.
AverageStamp averageStampFromName(const std::string& name);
std::string averageStampName(AverageStamp position);

/// Holds each start- or mid-stamped mean until the next sample shows where its interval ends,
/// then hands it on stamped there. Start: the next stamp. Mid: halfway to the next stamp. When
/// the next stamp comes later than 1.5 nominal periods (the median of the last five
/// intervals; a lost sample, a gap), the interval is taken as one nominal period long, so the
/// integrator's gap handling sees the loss where it happened. One sample of latency, exact on
/// a regular stream.
class IntervalEnds {
 public:
  explicit IntervalEnds(AverageStamp position) : position_(position) {}

  /// What push did with a sample.
  struct Pushed {
    /// Stamped at or before the sample waiting (isStale): refused, the waiting one kept.
    bool stale = false;
    /// The sample before it, stamped at its interval's end; nothing for the first sample (it
    /// waits for the next) or a stale one.
    std::optional<RateSample> ended;
  };
  /// Takes the newest sample unless it is stale; hands on the one waiting before it.
  Pushed push(const RateSample& next);
  /// The stamp of the sample waiting, if any.
  std::optional<double> waiting() const {
    return held_ ? std::optional<double>(held_->t) : std::nullopt;
  }
  /// Forgets the sample waiting and the periods (a new anchor: reset, set_state).
  void clear();

 private:
  double nominalPeriod(double interval) const;

  AverageStamp position_;
  std::optional<RateSample> held_;
  std::array<double, 5> intervals_{};
  std::size_t count_ = 0;
};

}  // namespace attitude_propagator
