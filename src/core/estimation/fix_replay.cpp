#include "attitude_propagator/estimation/fix_replay.h"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <utility>

#include "attitude_propagator/estimation/attitude_fix.h"
#include "attitude_propagator/limits.h"
#include "attitude_propagator/numerics/quaternion.h"

namespace attitude_propagator {

FixReplay::FixReplay(const FixConfig& config, const TimeBase& time, Propagator& model,
                     ErrorState& error, StepCovariance& covariance)
    : config_(config), time_(time), propagator_(model), error_(error), covariance_(covariance) {}

Stamp FixReplay::span() const { return static_cast<Stamp>(std::llround(config_.history * 1e9)); }

bool FixReplay::reaches(Stamp stamp) const {
  return !history_.empty() && stamp <= history_.newest().stamp;
}

bool FixReplay::atNewest(Stamp stamp) const {
  return !history_.empty() && history_.newest().stamp == stamp;
}

void FixReplay::clear() {
  history_.clear();
  applied_fixes_.clear();
  forgotten_fix_.reset();
  replay_budget_.clear();
}

void FixReplay::record(const ModelStep& step, bool base) {
  const std::optional<double> t = propagator_.savedTime();
  if (!t) return;
  const std::optional<Stamp> stamp = stampAt(*t);
  if (!stamp) return;
  replay_budget_.recorded(*stamp);
  FixHistoryEntry* slot = &history_.append();
  slot->step = step;
  slot->step.input.payload.reset();  // the message is not kept
  slot->measurement.reset();
  fillEntry(*slot);
  slot->stamp = *stamp;
  slot->base = base;
  history_.keepSpan(*stamp, span());
}

// ---------------------------------------------------------------------------------------------
// Fixes
// ---------------------------------------------------------------------------------------------

// A fix stamped before fixes already applied (an earlier fix that arrived later) is applied at
// its stamp, and the later ones again after it, each with its replay, so that the newest state
// is the one all of them on time would have given (docs/design.md §6.9). Fixes of equal stamps
// keep their order of arrival. The re-applications are not counted again; one the gate now
// rejects is dropped, and the gate's run of rejections is the arrivals'.
FixOutcome FixReplay::applyInStampOrder(const LateFix& fix) {
  if (forgotten_fix_ && fix.stamp < *forgotten_fix_) return FixOutcome::TooOld;
  if (!replayAffordable(fix.stamp)) return FixOutcome::OverBudget;
  TakenFixes again = takeAppliedAfter(fix.stamp);
  FixHistoryEntry before;
  const FixOutcome outcome = applyFix(fix, before);
  if (outcome != FixOutcome::Accepted && outcome != FixOutcome::Reset) {
    putBack(std::move(again));  // untouched
    return outcome;
  }
  keepApplied({fix, std::move(before)});
  applyAgain(again.fixes);
  return outcome;
}

FixOutcome FixReplay::applyFix(const LateFix& fix, FixHistoryEntry& before) {
  const std::optional<Located> at = locate(fix.stamp);
  if (!at) return FixOutcome::TooOld;
  const AttitudeFix measurement(fix.q_WB, fix.R_B, config_.gate);
  Eigen::Quaterniond q = at->q_k * at->D;  // at the fix's stamp
  ErrorState e = moveErrorState(history_[at->k].error, at->D);
  bool reset = config_.mode == FixMode::Reset;
  if (!reset && !fuseMeasurement(measurement, q, e).accepted) {
    if (rejected_in_a_row_ < kFixRejectionRun) {
      ++rejected_in_a_row_;
      propagator_.restore(live_);
      return FixOutcome::RejectedGate;
    }
    reset = true;  // a run of rejections: the estimate is what is wrong
  }
  if (reset) measurement.reset(q, e);
  rejected_in_a_row_ = 0;

  // The corrected state replaces the saved one (moved to the fix's stamp when the model moved
  // there), and the steps since are repeated from it. The entry as it was is kept with the fix,
  // for a fix or measurement stamped before it that arrives later (takeAppliedAfter); the ones
  // after it are rewritten by every replay.
  before = history_[at->k];
  propagator_.correctOrientation(q * at->D.conjugate());
  error_ = moveErrorState(e, at->D.conjugate());
  saveReplayed(history_[at->k]);
  replayFrom(at->k + 1);
  return reset ? FixOutcome::Reset : FixOutcome::Accepted;
}

std::vector<FixReplay::AppliedFix>::iterator FixReplay::firstAppliedAfter(Stamp stamp) {
  return std::upper_bound(applied_fixes_.begin(), applied_fixes_.end(), stamp,
                          [](Stamp t, const AppliedFix& other) { return t < other.fix.stamp; });
}

// A fix corrects the entry it acts at in place (and the replay rewrites the ones after it). A
// fix or measurement stamped before it that acts at the same entry must find that entry as it
// was without it, or the later fix, applied again after it, would count twice.
FixReplay::TakenFixes FixReplay::takeAppliedAfter(Stamp stamp) {
  const auto later = firstAppliedAfter(stamp);
  TakenFixes taken;
  taken.fixes.assign(std::make_move_iterator(later), std::make_move_iterator(applied_fixes_.end()));
  applied_fixes_.erase(later, applied_fixes_.end());
  for (auto g = taken.fixes.rbegin(); g != taken.fixes.rend(); ++g) {
    const FixHistoryEntry& was = g->before;
    if (const std::optional<std::size_t> i = history_.find(was.id)) {
      taken.replaced.push_back(history_[*i]);
      history_[*i] = was;
    }
  }
  return taken;
}

void FixReplay::putBack(TakenFixes&& taken) {
  for (auto e = taken.replaced.rbegin(); e != taken.replaced.rend(); ++e) {
    if (const std::optional<std::size_t> i = history_.find(e->id)) history_[*i] = *e;
  }
  applied_fixes_.insert(applied_fixes_.end(), std::make_move_iterator(taken.fixes.begin()),
                        std::make_move_iterator(taken.fixes.end()));
}

void FixReplay::applyAgain(const std::vector<AppliedFix>& fixes) {
  // Not counted again; one the gate now rejects is dropped; the gate's run of rejections is the
  // arrivals'.
  const int rejected_in_a_row = rejected_in_a_row_;
  for (const AppliedFix& g : fixes) {
    FixHistoryEntry before;
    const FixOutcome o = applyFix(g.fix, before);
    if (o == FixOutcome::Accepted || o == FixOutcome::Reset)
      keepApplied({g.fix, std::move(before)});
  }
  rejected_in_a_row_ = rejected_in_a_row;
}

void FixReplay::keepApplied(AppliedFix&& applied) {
  applied_fixes_.push_back(std::move(applied));
  if (applied_fixes_.size() > kMaxFixesReapplied) {
    forgotten_fix_ = applied_fixes_.front().fix.stamp;
    applied_fixes_.erase(applied_fixes_.begin());
  }
}

// ---------------------------------------------------------------------------------------------
// Gravity and field samples (docs/design.md §6.10)
// ---------------------------------------------------------------------------------------------

// Late: applied where it belongs, the steps since repeated, and the fixes applied after its
// stamp applied again after it (as a late fix does).
std::optional<FixReplay::Placed> FixReplay::place(Stamp stamp) {
  TakenFixes again = takeAppliedAfter(stamp);
  const std::optional<Located> at = locate(stamp);
  if (!at) {
    putBack(std::move(again));
    return std::nullopt;
  }
  return Placed(at->q_k * at->D, moveErrorState(history_[at->k].error, at->D), *at,
                std::move(again));
}

void FixReplay::dropPlaced(Placed&& placed) {
  propagator_.restore(live_);
  putBack(std::move(placed.again));
}

void FixReplay::applyPlaced(Placed&& placed, std::shared_ptr<const Measurement> m, Stamp measured,
                            bool reset) {
  const Located& at = placed.at;
  const Stamp base_stamp = history_[at.k].stamp;
  propagator_.correctOrientation(placed.q * at.D.conjugate());
  error_ = moveErrorState(placed.e, at.D.conjugate());
  std::size_t pos = at.k + 1;
  fillMeasurement(history_.insert(pos), std::move(m), at.D, measured, reset, base_stamp);
  replayFrom(pos + 1);
  applyAgain(placed.again.fixes);
}

void FixReplay::keepAtNewest(std::shared_ptr<const Measurement> m, Stamp measured, bool reset) {
  if (history_.empty()) return;
  const Stamp state_stamp = history_.newest().stamp;
  fillMeasurement(history_.append(), std::move(m), Eigen::Quaterniond::Identity(), measured, reset,
                  state_stamp);
}

void FixReplay::fillMeasurement(FixHistoryEntry& entry, std::shared_ptr<const Measurement> m,
                                const Eigen::Quaterniond& D, Stamp measured, bool reset,
                                Stamp stamp) {
  entry.step = ModelStep{};
  entry.measurement = std::move(m);
  entry.D = D;
  entry.measurement_reset = reset;
  entry.measured = measured;
  entry.base = false;
  fillEntry(entry);
  entry.stamp = stamp;
}

void FixReplay::reapplyMeasurement(const FixHistoryEntry& entry) {
  Eigen::Quaterniond q = propagator_.state().q_WB * entry.D;
  ErrorState e = moveErrorState(error_, entry.D);
  if (entry.measurement_reset) {
    entry.measurement->reset(q, e);
  } else {
    fuseMeasurement(*entry.measurement, q, e, true);
  }
  propagator_.correctOrientation(q * entry.D.conjugate());
  error_ = moveErrorState(e, entry.D.conjugate());
}

// ---------------------------------------------------------------------------------------------
// Where a correction acts, and the replay
// ---------------------------------------------------------------------------------------------

// The correction is applied at the last saved state at or before its stamp, k (docs/design.md
// §6.9), but before the measurements applied in the same interval and stamped after it (they
// are applied again in the replay). A model that can move on from k to the stamp (dynamic: the
// knot advanced to t_f) is corrected there. Otherwise the estimate at the stamp is interpolated
// along the geodesic to the next state, q_f = q_k (x) D, D = Exp(a Log(q_k^-1 q_k+1)), a = (t_f -
// t_k) / (t_k+1 - t_k), q_k+1 the step taken again from k (what it gives without the
// corrections in the interval after t_f); an error at t_f is the error at t_k seen through D
// (dtheta_k = C(D) dtheta_f), so the error state is carried to t_f (moveErrorState), the update
// made there, and the result carried back to t_k.
std::optional<FixReplay::Located> FixReplay::locate(Stamp stamp) {
  const std::size_t n = history_.size();
  if (n == 0) return std::nullopt;
  const Stamp newest = history_[n - 1].stamp;
  if (newest - stamp > span()) return std::nullopt;
  std::size_t k = n;
  while (k > 0 && history_[k - 1].stamp > stamp) --k;
  while (k > 0 && history_[k - 1].measurement && history_[k - 1].measured > stamp) --k;
  if (k == 0) return std::nullopt;  // before the oldest state kept (or the anchor)
  --k;
  const FixHistoryEntry& base = history_[k];
  propagator_.save(live_);  // the newest state, kept should the correction not be applied
  propagator_.restore(base.model);
  Located at{k, base.q_WB, Eigen::Quaterniond::Identity()};
  std::size_t next = k + 1;
  while (next < n && history_[next].stamp <= base.stamp) ++next;
  if (base.stamp < stamp && next < n) {
    if (propagator_.advanceForFix(coreTime(stamp))) {
      at.q_k = propagator_.state().q_WB;  // the model's own state at the stamp
    } else {
      const double a = static_cast<double>(stamp - base.stamp) /
                       static_cast<double>(history_[next].stamp - base.stamp);
      at.D = expMap(a * logMap(at.q_k.conjugate() * stepFrom(k, next)));
    }
  }
  return at;
}

Eigen::Quaterniond FixReplay::stepFrom(std::size_t k, std::size_t j) {
  const FixHistoryEntry& next = history_[j];
  if (next.base || next.measurement) return next.q_WB;  // not reached by a step: as kept
  const ErrorState kept = error_;
  error_ = history_[k].error;  // the bias estimate the step is taken with
  replayStep(next.step);
  const Eigen::Quaterniond q = propagator_.state().q_WB;
  error_ = kept;
  propagator_.restore(history_[k].model);
  return q;
}

bool FixReplay::replayAffordable(Stamp stamp) {
  if (history_.empty()) return true;
  // The states after the stamp are replayed once, and once more for each applied fix after it
  // (applied again): an upper bound of the work, known before anything changes.
  std::size_t after = 0;
  for (std::size_t i = history_.size(); i > 0 && history_[i - 1].stamp > stamp; --i) ++after;
  const auto again = static_cast<std::size_t>(applied_fixes_.end() - firstAppliedAfter(stamp));
  return replay_budget_.affords(history_.newest().stamp, after * (1 + again));
}

void FixReplay::replayFrom(std::size_t first) {
  if (first < history_.size()) {
    replay_budget_.charge(history_.newest().stamp, history_.size() - first);
  }
  for (std::size_t i = first; i < history_.size(); ++i) {
    FixHistoryEntry& entry = history_[i];
    if (entry.measurement) {
      reapplyMeasurement(entry);
    } else if (!entry.base) {
      replayStep(entry.step);
    }
    saveReplayed(entry);
  }
}

void FixReplay::replayStep(const ModelStep& step) {
  const ModelStep* given = &step;
  ModelStep corrected;
  if (!step.advance && takesBiasEstimate(step.input)) {
    corrected = step;
    corrected.input.value -= error_.bias_B;  // the estimate as it is now, after the correction
    given = &corrected;
  }
  // Of the result only the covariance: what was counted, noted, kept and published stays.
  covariance_.followCovariance(propagator_.replay(*given));
}

void FixReplay::fillEntry(FixHistoryEntry& slot) {
  propagator_.save(slot.model);
  slot.q_WB = propagator_.state().q_WB;
  slot.error = error_;
}

void FixReplay::saveReplayed(FixHistoryEntry& entry) {
  fillEntry(entry);
  if (const std::optional<double> t = propagator_.savedTime()) entry.stamp = *stampAt(*t);
}

}  // namespace attitude_propagator
