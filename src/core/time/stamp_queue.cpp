#include "attitude_propagator/time/stamp_queue.h"

#include <algorithm>

namespace attitude_propagator {

QueuePlace placeInQueue(const std::vector<Stamp>& stamps, Stamp stamp, std::size_t capacity) {
  QueuePlace place;
  // After its equals: they arrived first.
  place.at = static_cast<std::size_t>(std::upper_bound(stamps.begin(), stamps.end(), stamp) -
                                      stamps.begin());
  if (stamps.size() < capacity) return place;
  if (place.at == stamps.size()) {
    place.kept = false;  // the furthest ahead: it would wait longest
    return place;
  }
  place.drop = stamps.size() - 1;
  return place;
}

bool dueBy(Stamp waiting, Stamp now) { return waiting <= now; }

}  // namespace attitude_propagator
