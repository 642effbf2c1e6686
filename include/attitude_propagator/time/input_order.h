// The order rule of the inputs (docs/design.md §6.5): each source's input judged against its own
// timeline, never against the clock. A straggler is dropped; one input far ahead of its source's
// usual lead is held ahead (a forward glitch); a run from an earlier time is held until it is a
// backward jump (kJumpConfirmation in a row: its inputs are then used first, in order) or breaks
// (its inputs are then stale). The rule decides on stamps alone (SourceOrder, input_order.cpp);
// InputOrder keeps the held inputs beside it, and says what happened instead of counting it: the
// engine counts, notes and restarts the model.
#pragma once

#include <cstddef>
#include <optional>
#include <utility>
#include <vector>

#include "attitude_propagator/time/source_timeline.h"
#include "attitude_propagator/time/time_policy.h"

namespace attitude_propagator {

/// What became of an input judged against its source's order.
enum class OrderVerdict {
  Use,        ///< in order: use it now
  Stale,      ///< a straggler: dropped (and counted) at once
  HeldAhead,  ///< one forward glitch (SourceTimeline::heldAhead): dropped, the run untouched
  HeldInRun,  ///< held in a run from an earlier time, until it is a jump or breaks
  JumpedBack  ///< the kJumpConfirmation-th of a run: a backward jump; the run's inputs go first
};

/// One source's order on stamps alone: its timeline, and what an input does to the run from an
/// earlier time held for it.
class SourceOrder {
 public:
  struct Judged {
    OrderVerdict verdict = OrderVerdict::Use;
    /// The inputs held in the run before this one are stale: it did not go on with them.
    bool run_broke = false;
  };

  /// Judges an input stamped `stamp`, the clock at `clock` (none: no input is held ahead). The
  /// lag of an input in order is observed; a jump's is observeLag's, once the model restarted.
  Judged judge(Stamp stamp, std::optional<Stamp> clock, const TimePolicy& policy);
  /// After every timeline was forgotten (a confirmed jump that restarted the model's time):
  /// `stamp`, the jump's, is the source's first again.
  void startAgainAt(Stamp stamp, const TimePolicy& policy);
  /// Records how far behind `clock` (none: nothing to record) an input stamped `stamp` arrived.
  void observeLag(std::optional<Stamp> clock, Stamp stamp);
  /// Forgets every stamp and the lag (time itself went back).
  void forget();

  SourceTimeline& timeline() { return line_; }
  const SourceTimeline& timeline() const { return line_; }

 private:
  SourceTimeline line_;
};

/// Each source's order (sources numbered from 0) with the inputs of its run from an earlier time
/// held as `T` (the engine's input with its received stamp): fewer than kJumpConfirmation each.
template <class T>
class InputOrder {
 public:
  explicit InputOrder(std::size_t sources) : orders_(sources), held_(sources) {}

  /// What judge decided, with the held inputs it lets go of.
  struct Judged {
    OrderVerdict verdict = OrderVerdict::Use;
    /// The inputs held in a run this one broke, in order: dropped as stale (count each).
    std::vector<T> released;
    /// JumpedBack: the inputs of the run before this one, in order, to use before it.
    std::vector<T> confirming;
  };

  /// Judges `item`, stamped `stamp`, against the order of `source`.
  Judged judge(std::size_t source, Stamp stamp, const T& item, std::optional<Stamp> clock,
               const TimePolicy& policy) {
    const SourceOrder::Judged rule = orders_[source].judge(stamp, clock, policy);
    std::vector<T>& run = held_[source];
    Judged judged;
    judged.verdict = rule.verdict;
    if (rule.verdict == OrderVerdict::JumpedBack) judged.confirming = std::exchange(run, {});
    if (rule.run_broke) judged.released = std::exchange(run, {});
    if (rule.verdict == OrderVerdict::HeldInRun) run.push_back(item);
    return judged;
  }

  /// After forget(), when a confirmed jump restarted the model's time: `stamp`, the jump's, is
  /// the source's first again (SourceOrder::startAgainAt).
  void startAgainAt(std::size_t source, Stamp stamp, const TimePolicy& policy) {
    orders_[source].startAgainAt(stamp, policy);
  }
  /// A jump's lag, observed once the model has restarted (SourceOrder::observeLag).
  void observeLag(std::size_t source, std::optional<Stamp> clock, Stamp stamp) {
    orders_[source].observeLag(clock, stamp);
  }

  /// Forgets every source's stamps and lag (time itself went back) and returns the inputs held,
  /// source by source, in order: stale, as a run from a forgotten time is never a jump now.
  std::vector<T> forget() {
    std::vector<T> released;
    for (SourceOrder& order : orders_) order.forget();
    for (std::vector<T>& run : held_) {
      for (T& item : run) released.push_back(std::move(item));
      run.clear();
    }
    return released;
  }

  /// How many inputs of `source` are held in its run from an earlier time.
  std::size_t held(std::size_t source) const { return held_[source].size(); }
  /// Mean seconds by which `source`'s inputs arrive behind the clock (SourceTimeline::lag).
  std::optional<double> lag(std::size_t source) const { return orders_[source].timeline().lag(); }
  /// The source's timeline, for its settings (SourceTimeline::allowRepeatedStamps); inputs are
  /// judged through judge, which keeps the held runs beside it.
  SourceTimeline& timeline(std::size_t source) { return orders_[source].timeline(); }

 private:
  std::vector<SourceOrder> orders_;
  std::vector<std::vector<T>> held_;  // per source: its run from an earlier time
};

}  // namespace attitude_propagator
