// What waits for the rates to reach its stamp (a gyro bias sample, a fix, a gravity or field
// sample): kept in stamp order, equal stamps in their order of arrival, and bounded. When it is
// full the one stamped furthest ahead goes, the newcomer itself when it is that one (it would
// wait longest, and a stream that runs this far ahead of the rates has stamps that are wrong), so
// nothing ever takes effect before its stamp. One rule for every queue of the engine: the
// placement and the due rule are functions of the stamps alone (stamp_queue.cpp); StampQueue
// keeps the items beside their stamps.
#pragma once

#include <cstddef>
#include <optional>
#include <utility>
#include <vector>

#include "attitude_propagator/time/source_timeline.h"  // Stamp

namespace attitude_propagator {

/// Where a newcomer goes in a queue of `stamps`.
struct QueuePlace {
  bool kept = true;                 ///< false: the newcomer is the one dropped, nothing changes
  std::optional<std::size_t> drop;  ///< the one dropped first to make room for it
  std::size_t at = 0;               ///< where the newcomer goes, in `stamps` as they were
};
/// The place of a newcomer stamped `stamp` in a queue of `stamps` (sorted, equal stamps in their
/// order of arrival) that holds at most `capacity`: after its equals; when full, the furthest
/// ahead dropped, or the newcomer when it is stamped at or beyond the furthest.
QueuePlace placeInQueue(const std::vector<Stamp>& stamps, Stamp stamp, std::size_t capacity);
/// Whether what waits for `waiting` is due once the rates reach `now`: at or before.
bool dueBy(Stamp waiting, Stamp now);

template <class T>
class StampQueue {
 public:
  explicit StampQueue(std::size_t capacity) : capacity_(capacity) {}

  /// What a push did: `kept` false when the newcomer was the one dropped; `dropped` holds the
  /// one dropped to make room for it. At most one of the two says something was lost.
  struct Pushed {
    bool kept = true;
    std::optional<T> dropped;
  };

  Pushed push(Stamp stamp, T item) {
    const QueuePlace place = placeInQueue(stamps_, stamp, capacity_);
    Pushed pushed;
    pushed.kept = place.kept;
    if (!place.kept) return pushed;
    std::size_t at = place.at;
    if (place.drop) {
      pushed.dropped = std::move(items_[*place.drop]);
      stamps_.erase(stamps_.begin() + static_cast<std::ptrdiff_t>(*place.drop));
      items_.erase(items_.begin() + static_cast<std::ptrdiff_t>(*place.drop));
      if (*place.drop < at) --at;
    }
    stamps_.insert(stamps_.begin() + static_cast<std::ptrdiff_t>(at), stamp);
    items_.insert(items_.begin() + static_cast<std::ptrdiff_t>(at), std::move(item));
    return pushed;
  }

  /// Whether the first one waiting is due once the rates reach `now`.
  bool due(Stamp now) const { return !stamps_.empty() && dueBy(stamps_.front(), now); }
  /// Takes out the first one waiting (not empty).
  T pop() {
    T item = std::move(items_.front());
    stamps_.erase(stamps_.begin());
    items_.erase(items_.begin());
    return item;
  }
  const T& front() const { return items_.front(); }
  Stamp frontStamp() const { return stamps_.front(); }
  std::size_t size() const { return items_.size(); }
  bool empty() const { return items_.empty(); }
  std::size_t capacity() const { return capacity_; }
  void clear() {
    stamps_.clear();
    items_.clear();
  }

 private:
  std::size_t capacity_;
  std::vector<Stamp> stamps_;  // sorted, beside items_
  std::vector<T> items_;
};

}  // namespace attitude_propagator
