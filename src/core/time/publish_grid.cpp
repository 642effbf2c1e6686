#include "attitude_propagator/time/publish_grid.h"

#include <cmath>

namespace attitude_propagator {

Stamp gridStamp(std::int64_t k, double publish_rate) {
  // long double holds nanoseconds since the epoch exactly (64-bit mantissa on x86).
  return static_cast<Stamp>(
      std::llround(static_cast<long double>(k) * 1e9L / static_cast<long double>(publish_rate)));
}

std::int64_t gridIndexAtOrBefore(Stamp now, double publish_rate) {
  // A guess in double, off by one at most: now's round-off (128 ns at today's epoch) and the
  // grid stamps' own rounding are far below a period at any accepted rate (kMaxPublishRate).
  // The grid stamps themselves then decide. A long double floor here costs an x87 rounding-mode
  // switch and a stalled store per call: a third of a dynamic sample's time in bench_step_costs.
  auto k = static_cast<std::int64_t>(std::floor(static_cast<double>(now) * publish_rate * 1e-9));
  while (gridStamp(k, publish_rate) > now) --k;
  while (gridStamp(k + 1, publish_rate) <= now) ++k;
  return k;
}

}  // namespace attitude_propagator
