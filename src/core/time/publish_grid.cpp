#include "attitude_propagator/time/publish_grid.h"

#include <cmath>

namespace attitude_propagator {

Stamp gridStamp(std::int64_t k, double publish_rate) {
  // long double holds nanoseconds since the epoch exactly (64-bit mantissa on x86).
  return static_cast<Stamp>(
      std::llround(static_cast<long double>(k) * 1e9L / static_cast<long double>(publish_rate)));
}

std::int64_t gridIndexAtOrBefore(Stamp now, double publish_rate) {
  auto k = static_cast<std::int64_t>(
      std::floor(static_cast<long double>(now) * static_cast<long double>(publish_rate) / 1e9L));
  // The rounding of the grid stamps themselves moves k by one at most.
  if (gridStamp(k, publish_rate) > now) --k;
  if (gridStamp(k + 1, publish_rate) <= now) ++k;
  return k;
}

}  // namespace attitude_propagator
