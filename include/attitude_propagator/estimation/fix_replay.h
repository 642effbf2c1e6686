// Late corrections (docs/design.md §6.9, §6.10): the fix history, where in it a late fix or
// measurement acts, and the replay of the steps since, so that the newest state is the one the
// correction on time would have given. It owns the history, the applied fixes kept to be
// applied again after an earlier one, the replay budget and the gate's run of fix rejections;
// it drives the engine's model and error state, which it is handed, and follows the covariance
// of a replayed step through StepCovariance, the engine's rule for a live one. Which gravity or
// field sample is used is the engine's: this class places it and replays it.
#pragma once

#include <cstddef>
#include <memory>
#include <optional>
#include <utility>
#include <vector>

#include <Eigen/Geometry>

#include "attitude_propagator/estimation/error_state.h"
#include "attitude_propagator/estimation/fix_config.h"
#include "attitude_propagator/estimation/measurement.h"
#include "attitude_propagator/estimation/replay_budget.h"
#include "attitude_propagator/models/fix_history.h"
#include "attitude_propagator/models/outcome_table.h"
#include "attitude_propagator/models/propagator.h"
#include "attitude_propagator/time/time_base.h"

namespace attitude_propagator {

/// An absolute attitude q_WB measured at `stamp`, with the covariance R_B of its rotation-vector
/// error in the body frame.
struct LateFix {
  Stamp stamp;
  Eigen::Quaterniond q_WB;
  Eigen::Matrix3d R_B;
};

/// What a model's step does to the orientation covariance: propagated over the step, or back
/// to the initial one (ModelResult::covariance). The engine's rule for a live step; a replayed
/// step follows it alike.
class StepCovariance {
 public:
  virtual void followCovariance(const ModelResult& result) = 0;

 protected:
  ~StepCovariance() = default;
};

class FixReplay {
 public:
  /// Drives `model` and `error` (the engine's: the propagator is reconfigured in place, never
  /// replaced), reading core time from `time` and the fixes' rules from `config`.
  FixReplay(const FixConfig& config, const TimeBase& time, Propagator& model, ErrorState& error,
            StepCovariance& covariance);

  /// Entries kept (0 before the history starts).
  std::size_t size() const { return history_.size(); }
  /// Whether the newest entry is at or after `stamp`: a correction stamped there acts now;
  /// one stamped later waits for the rates.
  bool reaches(Stamp stamp) const;
  /// Whether the newest entry is at `stamp` (a measurement there needs no replay).
  bool atNewest(Stamp stamp) const;
  /// Whether the bias estimate is subtracted from this input (a rate, with estimate_gyro_bias),
  /// live and in a replay alike.
  bool takesBiasEstimate(const Input& input) const {
    return config_.estimate_gyro_bias && input.source != Source::Torque;
  }

  /// Appends the model's state after `step` to the history (`base`: a state no step reached),
  /// drops what is older than fix_history.
  void record(const ModelStep& step, bool base = false);
  /// Forgets the history, the applied fixes and the budget: time starts again.
  void clear();

  /// Applies a fix stamped at or before the newest entry, then again the fixes applied earlier
  /// that are stamped after it, in stamp order: the order they would have had on time.
  FixOutcome applyInStampOrder(const LateFix& fix);

  /// Whether a correction at `stamp`, its replay and the re-applications after it fit in the
  /// replay budget of the newest state's second (replay_budget.h).
  bool replayAffordable(Stamp stamp);

  // A late gravity or field sample: place(), then the engine decides at Placed::q and ::e
  // (fuse, align, recover or reject), then applyPlaced() or dropPlaced(). A sample at the newest
  // entry is applied there by the engine and kept with keepAtNewest().
  class Placed;
  /// The model set back to where a measurement stamped at or before the newest entry acts,
  /// the applied fixes after it taken out; empty (nothing touched) when it is too old.
  std::optional<Placed> place(Stamp stamp);
  /// The decision refused it: the newest state and the fixes set aside back.
  void dropPlaced(Placed&& placed);
  /// Applies `m` as decided (placed.q, placed.e; `reset`: applied as a reset), keeps it as an
  /// entry of its own after the one it acts at, replays the steps since and applies the fixes
  /// set aside again.
  void applyPlaced(Placed&& placed, std::shared_ptr<const Measurement> m, Stamp measured,
                   bool reset);
  /// Keeps a measurement the engine applied to the newest state as an entry of its own.
  void keepAtNewest(std::shared_ptr<const Measurement> m, Stamp measured, bool reset);

 private:
  /// Where a correction stamped at or before the newest entry acts: the last entry k at or
  /// before its stamp, and the motion D from it to the stamp.
  struct Located {
    std::size_t k;
    Eigen::Quaterniond q_k;
    Eigen::Quaterniond D;
  };
  /// An applied fix, and the entry it changed in place (the one it acted at) as it was before
  /// it; the entries after it are rewritten by every replay.
  struct AppliedFix {
    LateFix fix;
    FixHistoryEntry before;
  };
  /// Applied fixes taken out to be applied again after an earlier fix or measurement, the
  /// entries they had changed set back, and those entries as they were, should nothing be
  /// applied after all.
  struct TakenFixes {
    std::vector<AppliedFix> fixes;
    std::vector<FixHistoryEntry> replaced;
  };

 public:
  /// A measurement placed: the attitude q and error state e at its stamp, for the engine to
  /// decide on; where it acts and the fixes set aside are the FixReplay's.
  class Placed {
   public:
    Eigen::Quaterniond q;
    ErrorState e;

   private:
    friend class FixReplay;
    Placed(const Eigen::Quaterniond& q_at, const ErrorState& e_at, const Located& at_,
           TakenFixes&& again_)
        : q(q_at), e(e_at), at(at_), again(std::move(again_)) {}
    Located at;
    TakenFixes again;
  };

 private:
  double coreTime(Stamp stamp) const { return time_.coreTime(stamp); }
  std::optional<Stamp> stampAt(double t) const { return time_.stampAt(t); }
  Stamp span() const;

  /// Applies a fix stamped at or before the newest entry; when applied, `before` receives the
  /// entry it changed in place (the one it acted at), as it was.
  FixOutcome applyFix(const LateFix& fix, FixHistoryEntry& before);
  /// The first applied fix stamped after `stamp` (fixes of equal stamps keep their order).
  std::vector<AppliedFix>::iterator firstAppliedAfter(Stamp stamp);
  /// The applied fixes stamped after `stamp`, taken out of those kept, in stamp order, and the
  /// entries they changed set back to what they were before them (the latest first), so that
  /// a fix or measurement stamped before them acts without them, and none counts twice.
  TakenFixes takeAppliedAfter(Stamp stamp);
  /// Undoes takeAppliedAfter: the entries as they were, the fixes kept again.
  void putBack(TakenFixes&& taken);
  /// Applies fixes again after an earlier fix or measurement, keeping those applied.
  void applyAgain(const std::vector<AppliedFix>& fixes);
  /// Keeps an applied fix (stamped at or after those kept) to be applied again.
  void keepApplied(AppliedFix&& applied);
  /// The last entry at or before `stamp` (before the measurements of its interval stamped
  /// after it), restored into the model (the newest state saved in live_). Empty (nothing
  /// touched) when it is too old.
  std::optional<Located> locate(Stamp stamp);
  /// The state the step to entry j gives from entry k (the one before it, but for measurements
  /// stamped later): the interval's own motion, without corrections made in it after the stamp.
  Eigen::Quaterniond stepFrom(std::size_t k, std::size_t j);
  /// Repeats the entries from `first` on from the model's state: the steps, and the
  /// measurements as they were applied.
  void replayFrom(std::size_t first);
  /// Repeats a saved step, the current bias estimate subtracted from a rate; of the result
  /// only the covariance is followed.
  void replayStep(const ModelStep& step);
  /// Applies again, as it was applied, the measurement of `entry` to the model's state.
  void reapplyMeasurement(const FixHistoryEntry& entry);
  /// Fills `entry` as a measurement's, after the model's state now, at `stamp`.
  void fillMeasurement(FixHistoryEntry& entry, std::shared_ptr<const Measurement> m,
                       const Eigen::Quaterniond& D, Stamp measured, bool reset, Stamp stamp);
  /// Saves the model's state after a replayed step into its entry.
  void saveReplayed(FixHistoryEntry& entry);
  /// Fills `slot` with the model's state now.
  void fillEntry(FixHistoryEntry& slot);

  const FixConfig& config_;
  const TimeBase& time_;
  Propagator& propagator_;
  ErrorState& error_;
  StepCovariance& covariance_;

  FixHistory history_;                     // a ring, allocated as it grows
  std::vector<AppliedFix> applied_fixes_;  // the newest applied, by stamp, kMaxFixesReapplied
  ReplayBudget replay_budget_;             // states replayed per second of stamp time
  std::optional<Stamp> forgotten_fix_;     // the newest applied fix's stamp no longer kept
  int rejected_in_a_row_ = 0;              // the gate's run of fix rejections
  ModelSnapshot live_;                     // the newest state while a correction is worked out
};

}  // namespace attitude_propagator
