// The fix history: the model's states after each step over the last fix_history seconds, oldest
// first, that a late fix or measurement is applied at and replayed from (docs/design.md §6.9).
// A ring allocated as it grows, up to kMaxFixHistorySamples entries (limits.h); each entry
// carries an id that names it while it is kept, wherever insertions and drops move it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include <Eigen/Geometry>

#include "attitude_propagator/estimation/error_state.h"
#include "attitude_propagator/estimation/measurement.h"
#include "attitude_propagator/models/propagator.h"

namespace attitude_propagator {

/// One entry of the fix history: a step of the model (a rate input as the model received it,
/// after rate_delay and the configured bias, the bias estimate subtracted when it is applied;
/// a torque; an advance of the dynamic model to a grid stamp) or a gravity or field measurement
/// applied, and the model, its orientation and the error state after it, at the stamp the state
/// then held at.
struct FixHistoryEntry {
  ModelStep step;
  /// A measurement applied after the state before it (a replay applies it again, as it was
  /// applied: fused or as a reset), stamped D further along the motion: q_f = q (x) D.
  std::shared_ptr<const Measurement> measurement;
  Eigen::Quaterniond D = Eigen::Quaterniond::Identity();
  bool measurement_reset = false;
  /// A measurement's own stamp (`stamp` is that of the state it was applied after): a
  /// correction stamped before it, arriving later, goes before it.
  Stamp measured = 0;
  ModelSnapshot model;
  Eigen::Quaterniond q_WB = Eigen::Quaterniond::Identity();
  ErrorState error;
  Stamp stamp = 0;
  /// The state was not reached by a step (the newest one when the history started, a pinned
  /// state): restored, never replayed.
  bool base = false;
  /// Names the entry while it is kept, wherever insertions and drops move it.
  std::uint64_t id = 0;
};

class FixHistory {
 public:
  std::size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }
  /// Entry i, oldest first (i < size()).
  FixHistoryEntry& operator[](std::size_t i) { return ring_[(head_ + i) % ring_.size()]; }
  const FixHistoryEntry& operator[](std::size_t i) const {
    return ring_[(head_ + i) % ring_.size()];
  }
  /// The newest entry (not empty()).
  const FixHistoryEntry& newest() const { return (*this)[size_ - 1]; }
  /// Forgets every entry; their storage stays for reuse.
  void clear();
  /// A new entry after the newest, with an id of its own: the next slot, grown or, at
  /// kMaxFixHistorySamples, the oldest.
  FixHistoryEntry& append();
  /// A new entry at position `pos` (oldest first), with an id of its own, the entries from it
  /// on moved up by one; at kMaxFixHistorySamples the oldest goes first (and `pos` with it).
  FixHistoryEntry& insert(std::size_t& pos);
  /// Where the entry named `id` is; empty when it is no longer kept.
  std::optional<std::size_t> find(std::uint64_t id) const;
  /// Keeps the newest entry at or before `newest - span` (a fix stamped exactly there needs
  /// it), drops the ones before it.
  void keepSpan(Stamp newest, Stamp span);

 private:
  FixHistoryEntry& appendSlot();

  std::vector<FixHistoryEntry> ring_;
  std::size_t head_ = 0;
  std::size_t size_ = 0;
  std::uint64_t last_id_ = 0;  // the id of the newest entry appended or inserted
};

}  // namespace attitude_propagator
