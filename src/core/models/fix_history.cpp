#include "attitude_propagator/models/fix_history.h"

#include <algorithm>
#include <iterator>

#include "attitude_propagator/limits.h"

namespace attitude_propagator {

void FixHistory::clear() {
  head_ = 0;
  size_ = 0;
}

FixHistoryEntry& FixHistory::append() {
  FixHistoryEntry& slot = appendSlot();
  slot.id = ++last_id_;  // a new entry, whatever the slot held before
  return slot;
}

FixHistoryEntry& FixHistory::appendSlot() {
  if (size_ < ring_.size()) return (*this)[size_++];
  if (ring_.size() < kMaxFixHistorySamples) {
    // Grow the ring: oldest first again, then one more slot at the end.
    std::rotate(ring_.begin(), ring_.begin() + static_cast<std::ptrdiff_t>(head_), ring_.end());
    head_ = 0;
    ring_.emplace_back();
    ++size_;
    return ring_.back();
  }
  FixHistoryEntry& slot = ring_[head_];  // full: the oldest goes (limits.h)
  head_ = (head_ + 1) % ring_.size();
  return slot;
}

FixHistoryEntry& FixHistory::insert(std::size_t& pos) {
  // Oldest first again; at the memory bound the oldest goes.
  std::rotate(ring_.begin(), ring_.begin() + static_cast<std::ptrdiff_t>(head_), ring_.end());
  head_ = 0;
  if (size_ >= kMaxFixHistorySamples && pos > 0) {
    std::move(ring_.begin() + 1, ring_.begin() + static_cast<std::ptrdiff_t>(size_), ring_.begin());
    --size_;
    --pos;
  }
  if (size_ == ring_.size()) ring_.emplace_back();
  std::move_backward(ring_.begin() + static_cast<std::ptrdiff_t>(pos),
                     ring_.begin() + static_cast<std::ptrdiff_t>(size_),
                     ring_.begin() + static_cast<std::ptrdiff_t>(size_) + 1);
  ++size_;
  ring_[pos].id = ++last_id_;
  return ring_[pos];
}

std::optional<std::size_t> FixHistory::find(std::uint64_t id) const {
  for (std::size_t i = size_; i > 0; --i) {
    if ((*this)[i - 1].id == id) return i - 1;
  }
  return std::nullopt;
}

void FixHistory::keepSpan(Stamp newest, Stamp span) {
  while (size_ > 1 && newest - (*this)[1].stamp >= span) {
    head_ = (head_ + 1) % ring_.size();
    --size_;
  }
}

}  // namespace attitude_propagator
