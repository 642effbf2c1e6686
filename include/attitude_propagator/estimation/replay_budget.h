// How much replaying the engine may do (docs/design.md §6.9): a late fix or measurement is
// applied at its stamp and the states after it are integrated again, so a flood of late ones
// (fixes at 1 kHz, 4 s late) costs thousands of steps each and the rates fall behind. The
// states replayed in any second of stamp time are bounded by a multiple of the states the rates
// themselves recorded in it: what would exceed it is refused before anything changes, and
// counted by its caller. Stamp time, not wall time, so the rule is the same in the node, in
// the bag tools and in a test, and a starved process is not refused more.
#pragma once

#include <cstddef>
#include <cstdint>

#include "attitude_propagator/time/source_timeline.h"  // Stamp

namespace attitude_propagator {

/// States replayed per state recorded, over a second: with fixes 100 ms late at 10 Hz a
/// replay costs one recorded second of states in ten fixes, far below; a flood of late fixes
/// costs no more than twenty times the rates' own integration.
constexpr std::size_t kReplayPerRecorded = 20;
/// States that may always be replayed in a second, whatever the rate (a slow stream with a
/// long fix_history: 50 Hz rates, one fix 10 s late replays 500).
constexpr std::size_t kReplayFloor = 4096;

class ReplayBudget {
 public:
  /// A state the rates recorded at `stamp`.
  void recorded(Stamp stamp);
  /// True when `states` more replayed states fit in the second of `stamp`.
  bool affords(Stamp stamp, std::size_t states);
  /// `states` replayed at `stamp` (counted whether they fit or not: re-applications after an
  /// accepted one are never refused).
  void charge(Stamp stamp, std::size_t states);
  /// The states replayed in the current second (diagnostics, tests).
  std::size_t replayedThisSecond() const { return replayed_; }
  /// What may be replayed in the current second.
  std::size_t allowance() const;
  /// Forgets everything: time starts again (a reset, a jump back, set_state), so a second of
  /// the old timeline never holds the new one's replays back.
  void clear() { *this = ReplayBudget{}; }

 private:
  /// Moves to the second of `stamp`: a later second starts empty, the previous one's recorded
  /// count kept (a second just begun has recorded little).
  void roll(Stamp stamp);

  Stamp second_ = 0;  // the current second: stamp / 1e9
  bool started_ = false;
  std::size_t recorded_ = 0;
  std::size_t recorded_before_ = 0;  // in the second before the current one
  std::size_t replayed_ = 0;
};

}  // namespace attitude_propagator
