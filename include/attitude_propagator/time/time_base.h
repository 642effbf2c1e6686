// The one time base of the core: core time is a double of seconds since an origin, a stamp's
// whole second. The engine pins the origin where time starts (the first input handed to the
// model, or the first grid stamp the dynamic model publishes, or a pinned state), moves it to
// a state held far away (rebase) and forgets it when time starts again; the models only read
// it (docs/design.md §2.4).
#pragma once

#include <optional>

#include "attitude_propagator/time/source_timeline.h"

namespace attitude_propagator {

/// Core time's resolution stays below 1e-10 s within this many seconds of the origin; a state
/// held further away moves the origin to it (TimeBase::isFar).
constexpr double kFarFromOrigin = 1e6;

class TimeBase {
 public:
  /// Sets the origin at `stamp`'s whole second, unless one is set.
  void pin(Stamp stamp);
  /// Moves the origin to `stamp`'s whole second.
  void rebase(Stamp stamp);
  void forget() { origin_.reset(); }
  bool pinned() const { return origin_.has_value(); }
  /// Seconds from the origin to `stamp` (whole seconds keep the publish grid exact in core
  /// time). Before an origin is pinned, from `stamp`'s own second.
  double coreTime(Stamp stamp) const;
  /// The stamp of core time t (rounded to the nanosecond); empty before an origin is pinned.
  std::optional<Stamp> stampAt(double t) const;
  /// Whether `stamp` lies kFarFromOrigin or more from the origin.
  bool isFar(Stamp stamp) const;

 private:
  std::optional<Stamp> origin_;
};

}  // namespace attitude_propagator
