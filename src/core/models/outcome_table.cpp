#include "attitude_propagator/models/outcome_table.h"

#include <algorithm>

namespace attitude_propagator {

namespace {

using C = EngineCounters;
using Note = EngineNote;

template <class Row, class Outcome>
const Row& rowOf(const std::vector<Row>& table, Outcome outcome) {
  return *std::find_if(table.begin(), table.end(),
                       [outcome](const Row& row) { return row.outcome == outcome; });
}

}  // namespace

const std::vector<StampOutcomeRow>& stampOutcomeTable() {
  static const std::vector<StampOutcomeRow> table = {
      {StampOutcome::Anchored, &C::accepted, nullptr, std::nullopt},
      {StampOutcome::Advanced, &C::accepted, nullptr, std::nullopt},
      // Held: the input acts from the state held at its stamp.
      {StampOutcome::HeldGap, &C::accepted, &C::gaps, Note::Gap},
      // Nothing integrated yet: counted as taken, nothing to publish.
      {StampOutcome::Waiting, &C::accepted, nullptr, std::nullopt},
      {StampOutcome::DroppedStale, &C::dropped_stale, nullptr, Note::Stale},
      {StampOutcome::RejectedNonFinite, nullptr, &C::rejected_non_finite, Note::NonFinite},
      {StampOutcome::RejectedOutOfRange, nullptr, &C::rejected_out_of_range, Note::OutOfRange},
      // Held and re-anchored at the stamp, like a gap: the input acts from the new anchor.
      {StampOutcome::FailedStep, &C::accepted, &C::failed_steps, Note::FailedStep},
  };
  return table;
}

const StampOutcomeRow& stampOutcomeRow(StampOutcome outcome) {
  return rowOf(stampOutcomeTable(), outcome);
}

const std::vector<FixOutcomeRow>& fixOutcomeTable() {
  static const std::vector<FixOutcomeRow> table = {
      {FixOutcome::Accepted, "accepted", {&C::fixes_accepted}, nullptr},
      {FixOutcome::Reset, "reset", {&C::fixes_accepted, &C::fixes_reset}, nullptr},
      {FixOutcome::Waiting, "waiting", {}, nullptr},
      {FixOutcome::RejectedGate,
       "rejected_gate",
       {&C::fixes_rejected_gate},
       "its innovation is beyond fix_gate (5 in a row apply as a reset)"},
      {FixOutcome::TooOld,
       "too_old",
       {&C::fixes_too_old},
       "stamped before the rates kept (fix_history) or before the last anchor"},
      {FixOutcome::BadQuaternion,
       "bad_quaternion",
       {&C::fixes_bad_quaternion},
       "a non-finite quaternion, or not of unit norm"},
      {FixOutcome::BadCovariance,
       "bad_covariance",
       {&C::fixes_bad_covariance},
       "a covariance that is not one (non-finite, asymmetric, a negative variance, a variance "
       "above pi^2)"},
      {FixOutcome::QueueFull,
       "queue_full",
       {&C::fixes_queue_full},
       "stamped ahead of the rates, and too many wait already"},
      {FixOutcome::Future,
       "future",
       {&C::fixes_future},
       "stamped more than max_future ahead of ROS time"},
      {FixOutcome::OverBudget,
       "over_budget",
       {&C::fixes_over_budget},
       "late, and replaying the rates since would exceed the replays one second may cost (too "
       "many late fixes: the rates must not fall behind)"},
  };
  return table;
}

const FixOutcomeRow& fixOutcomeRow(FixOutcome outcome) { return rowOf(fixOutcomeTable(), outcome); }

const char* fixOutcomeName(FixOutcome outcome) { return fixOutcomeRow(outcome).name; }

std::uint64_t EngineCounters::*rejectionCounter(Rejection why) {
  switch (why) {
    case Rejection::NoRate:
      return &C::rejected_no_rate;
    case Rejection::WrongType:
      return &C::rejected_type;
    case Rejection::NoTransform:
      return &C::dropped_no_tf;
    case Rejection::NoTime:
      return &C::dropped_no_time;
    case Rejection::BadCovariance:
      return &C::rejected_covariance;
  }
  return &C::rejected_type;  // unreachable: every Rejection is above
}

namespace {

// The notes a stamp outcome gives report that outcome's counter (its event's, else its input's),
// read from stampOutcomeTable(); the rest report the engine's own counter for what they say.
std::vector<NoteRow> buildNoteTable() {
  std::vector<NoteRow> table = {
      {Note::StampsJumpedBack, &C::jumps_back},  {Note::Future, &C::rejected_future},
      {Note::ClockJumpedBack, &C::resets},       {Note::ClockTwoTimelines, &C::clock_conflicts},
      {Note::PendingFull, &C::pending_overflow}, {Note::Deferred, &C::deferred_ticks},
      {Note::HeldAhead, &C::held_ahead},         {Note::StampFilterMisfit, nullptr},
  };
  for (const StampOutcomeRow& row : stampOutcomeTable()) {
    if (row.note) table.push_back({*row.note, row.event ? row.event : row.input});
  }
  std::sort(table.begin(), table.end(),
            [](const NoteRow& a, const NoteRow& b) { return a.kind < b.kind; });
  return table;
}

}  // namespace

const std::vector<NoteRow>& noteTable() {
  static const std::vector<NoteRow> table = buildNoteTable();
  return table;
}

std::uint64_t EngineCounters::*noteCounter(EngineNote::Kind kind) {
  return noteTable().at(static_cast<std::size_t>(kind)).counter;
}

}  // namespace attitude_propagator
