// What each outcome counts: the one table from the outcomes of an input or the clock
// (StampOutcome), of a fix (FixOutcome) and of an input the node turned away (Rejection) to the
// fields of EngineCounters, whose names and meanings are engineCounterTable()'s, and the note
// each gives. The engine counts through it; a fix outcome's name, which the node logs, is its
// counter's (test/core/test_outcome_table.cpp holds each row to the counter table).
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include "attitude_propagator/models/counters.h"
#include "attitude_propagator/models/propagator.h"
#include "attitude_propagator/time/time_policy.h"

namespace attitude_propagator {

/// What became of a fix (the counters say the same: EngineCounters::fixes_*).
enum class FixOutcome {
  Accepted,       ///< fused at its stamp, the rates since replayed
  Reset,          ///< the attitude replaced at its stamp, the rates since replayed
  Waiting,        ///< stamped ahead of the newest rate: applied when the rates reach it
  RejectedGate,   ///< fuse: the innovation is beyond the gate
  TooOld,         ///< stamped before the history, the last anchor or an applied fix no longer kept
  BadQuaternion,  ///< non-finite, or |q| not 1 within kFixUnitTolerance
  BadCovariance,  ///< non-finite, asymmetric, a negative variance, a variance above pi^2,
                  ///< a correlation beyond one
  QueueFull,      ///< waiting, and dropped: kMaxPendingFixes were stamped nearer
  Future,         ///< stamped more than max_future ahead of the clock, as every input
  OverBudget,     ///< late: its replay would exceed what its second may replay (replay_budget.h)
};

/// Inputs the node turned away before they reached the engine, counted there with the rest.
enum class Rejection { NoRate, WrongType, NoTransform, NoTime, BadCovariance };

/// What an input's or the clock's StampOutcome counts. `input` is counted for an input only,
/// `event` for an input or the clock; the note is given with the event, or with the input's
/// count when there is no event (a stale input; nothing for the clock).
struct StampOutcomeRow {
  StampOutcome outcome;
  std::uint64_t EngineCounters::*input = nullptr;
  std::uint64_t EngineCounters::*event = nullptr;
  std::optional<EngineNote::Kind> note;
};
/// Every StampOutcome once.
const std::vector<StampOutcomeRow>& stampOutcomeTable();
const StampOutcomeRow& stampOutcomeRow(StampOutcome outcome);

/// What a fix outcome counts: its counters (Reset: fixes_accepted and fixes_reset; Waiting
/// none, counted when the rates reach it), its name (its own counter's, without `fixes_`) and,
/// for a fix not applied, why (the node's warning).
struct FixOutcomeRow {
  FixOutcome outcome;
  const char* name;
  std::vector<std::uint64_t EngineCounters::*> counters;
  const char* why;  ///< nullptr for a fix applied or waiting
};
/// Every FixOutcome once.
const std::vector<FixOutcomeRow>& fixOutcomeTable();
const FixOutcomeRow& fixOutcomeRow(FixOutcome outcome);
/// The row's name: "accepted", "reset", "waiting", "rejected_gate", …
const char* fixOutcomeName(FixOutcome outcome);

/// The counter a Rejection counts in.
std::uint64_t EngineCounters::*rejectionCounter(Rejection why);

/// The counter a note reports with its "so far": the event or input counter of the outcome it
/// comes with (stampOutcomeTable), else the engine's own for it (a jump, a refused future stamp,
/// a full queue, ...); nullptr for StampFilterMisfit (a state, shown in the diagnostics).
struct NoteRow {
  EngineNote::Kind kind;
  std::uint64_t EngineCounters::*counter;
};
/// Every EngineNote::Kind once, in the enum's order.
const std::vector<NoteRow>& noteTable();
std::uint64_t EngineCounters::*noteCounter(EngineNote::Kind kind);

}  // namespace attitude_propagator
