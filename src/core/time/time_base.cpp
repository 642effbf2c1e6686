#include "attitude_propagator/time/time_base.h"

#include <cmath>

namespace attitude_propagator {

namespace {

constexpr Stamp kNsPerSecond = 1000000000;

Stamp wholeSecond(Stamp stamp) { return stamp - stamp % kNsPerSecond; }

}  // namespace

void TimeBase::pin(Stamp stamp) {
  if (!origin_) origin_ = wholeSecond(stamp);
}

void TimeBase::rebase(Stamp stamp) { origin_ = wholeSecond(stamp); }

double TimeBase::coreTime(Stamp stamp) const {
  const Stamp origin = origin_ ? *origin_ : wholeSecond(stamp);
  return static_cast<double>(stamp - origin) * 1e-9;
}

std::optional<Stamp> TimeBase::stampAt(double t) const {
  if (!origin_) return std::nullopt;
  return *origin_ + static_cast<Stamp>(std::llround(t * 1e9));
}

bool TimeBase::isFar(Stamp stamp) const { return std::abs(coreTime(stamp)) >= kFarFromOrigin; }

}  // namespace attitude_propagator
