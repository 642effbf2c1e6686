// The outcome table (models/outcome_table.h) against the counter table and against the engine:
// every outcome once, every counter it names a counter of engineCounterTable() of the input it
// belongs to, a fix outcome's name its counter's, and the engine counting and noting exactly
// what a row says, for an input and for the clock.
#include <gtest/gtest.h>

#include <set>
#include <string>
#include <vector>

#include "attitude_propagator/engine.h"
#include "attitude_propagator/models/outcome_table.h"
#include "engine_fixtures.h"
#include "wrapped_model.h"

namespace ap = attitude_propagator;
using engine_fixtures::at;
using engine_fixtures::rate;

namespace {

using Field = std::uint64_t ap::EngineCounters::*;

const ap::CounterInfo* infoOf(Field field) {
  for (const ap::CounterInfo& info : ap::engineCounterTable()) {
    if (info.field == field) return &info;
  }
  return nullptr;
}

const std::vector<ap::StampOutcome> kStampOutcomes = {ap::StampOutcome::Anchored,
                                                      ap::StampOutcome::Advanced,
                                                      ap::StampOutcome::DroppedStale,
                                                      ap::StampOutcome::HeldGap,
                                                      ap::StampOutcome::Waiting,
                                                      ap::StampOutcome::RejectedNonFinite,
                                                      ap::StampOutcome::RejectedOutOfRange,
                                                      ap::StampOutcome::FailedStep};

const std::vector<ap::FixOutcome> kFixOutcomes = {
    ap::FixOutcome::Accepted,      ap::FixOutcome::Reset,     ap::FixOutcome::Waiting,
    ap::FixOutcome::RejectedGate,  ap::FixOutcome::TooOld,    ap::FixOutcome::BadQuaternion,
    ap::FixOutcome::BadCovariance, ap::FixOutcome::QueueFull, ap::FixOutcome::Future,
    ap::FixOutcome::OverBudget};

TEST(OutcomeTable, EveryStampOutcomeOnceItsCountersThoseOfRatesAndTorques) {
  ASSERT_EQ(ap::stampOutcomeTable().size(), kStampOutcomes.size());
  std::set<ap::StampOutcome> seen;
  for (const ap::StampOutcomeRow& row : ap::stampOutcomeTable()) {
    EXPECT_TRUE(seen.insert(row.outcome).second) << ap::outcomeName(row.outcome);
    for (const Field field : {row.input, row.event}) {
      if (field == nullptr) continue;
      const ap::CounterInfo* info = infoOf(field);
      ASSERT_NE(info, nullptr) << ap::outcomeName(row.outcome);
      EXPECT_TRUE(info->input == ap::CounterInput::RateOrTorque ||
                  info->input == ap::CounterInput::Any)
          << info->name;
    }
    // What the input's count says agrees with the outcome: it acts (used) exactly when the
    // state holds at its stamp or the input waits to act.
    if (row.input) {
      const bool used = infoOf(row.input)->kind == ap::CounterKind::Used;
      EXPECT_EQ(used,
                ap::stateHoldsAtStamp(row.outcome) || row.outcome == ap::StampOutcome::Waiting)
          << ap::outcomeName(row.outcome);
    }
    // Something counted is something noted, except a step that went as it should.
    const bool normal = row.outcome == ap::StampOutcome::Anchored ||
                        row.outcome == ap::StampOutcome::Advanced ||
                        row.outcome == ap::StampOutcome::Waiting;
    EXPECT_EQ(row.note.has_value(), !normal) << ap::outcomeName(row.outcome);
  }
}

TEST(OutcomeTable, EveryFixOutcomeOnceNamedAfterItsOwnCounter) {
  ASSERT_EQ(ap::fixOutcomeTable().size(), kFixOutcomes.size());
  std::set<ap::FixOutcome> seen;
  std::set<std::string> counted;  // by name: member pointers have no order
  for (const ap::FixOutcomeRow& row : ap::fixOutcomeTable()) {
    SCOPED_TRACE(row.name);
    EXPECT_TRUE(seen.insert(row.outcome).second);
    EXPECT_STREQ(ap::fixOutcomeName(row.outcome), row.name);
    if (row.outcome == ap::FixOutcome::Waiting) {
      EXPECT_TRUE(row.counters.empty());  // counted when the rates reach it
      EXPECT_EQ(row.why, nullptr);
      continue;
    }
    ASSERT_FALSE(row.counters.empty());
    for (const Field field : row.counters) {
      const ap::CounterInfo* info = infoOf(field);
      ASSERT_NE(info, nullptr);
      EXPECT_EQ(info->input, ap::CounterInput::Fix) << info->name;
      counted.insert(info->name);
    }
    // Its own counter is the last: fixes_<name>.
    EXPECT_EQ(infoOf(row.counters.back())->name, std::string("fixes_") + row.name);
    // A reason exactly for a fix not applied: its counter is one fixesNotApplied sums.
    const bool unused = infoOf(row.counters.back())->kind == ap::CounterKind::Unused;
    EXPECT_EQ(row.why != nullptr, unused);
  }
  // Every fix counter of the engine is some outcome's.
  for (const ap::CounterInfo& info : ap::engineCounterTable()) {
    if (info.input == ap::CounterInput::Fix && info.field != nullptr) {
      EXPECT_EQ(counted.count(info.name), 1u) << info.name;
    }
  }
}

TEST(OutcomeTable, EveryRejectionHasACounterOfItsOwnOfAnUnusedInput) {
  std::set<std::string> fields;
  for (const ap::Rejection why :
       {ap::Rejection::NoRate, ap::Rejection::WrongType, ap::Rejection::NoTransform,
        ap::Rejection::NoTime, ap::Rejection::BadCovariance}) {
    const Field field = ap::rejectionCounter(why);
    const ap::CounterInfo* info = infoOf(field);
    ASSERT_NE(info, nullptr);
    EXPECT_EQ(info->kind, ap::CounterKind::Unused) << info->name;
    EXPECT_TRUE(fields.insert(info->name).second) << info->name;
  }
  // The engine counts each where the table says, and as received.
  engine_fixtures::DiscardingSink sink;
  ap::AttitudeEngine engine(engine_fixtures::kinematicConfig(), sink);
  engine.reject(ap::Rejection::NoTransform);
  EXPECT_EQ(engine.counters().received, 1u);
  EXPECT_EQ(engine.counters().dropped_no_tf, 1u);
  EXPECT_EQ(engine.counters().rejected_type, 0u);
}

// A note's "so far" is its outcome's count: the event's where the row has one, else the
// input's; every other note names a counter of the engine's table, each its own.
TEST(OutcomeTable, EveryNoteOnceReportingTheCounterOfItsOutcome) {
  const std::vector<ap::NoteRow>& notes = ap::noteTable();
  ASSERT_EQ(notes.size(), static_cast<std::size_t>(ap::EngineNote::StampFilterMisfit) + 1);
  std::set<std::string> names;
  for (std::size_t i = 0; i < notes.size(); ++i) {
    EXPECT_EQ(static_cast<std::size_t>(notes[i].kind), i);
    EXPECT_EQ(ap::noteCounter(notes[i].kind), notes[i].counter);
    if (notes[i].kind == ap::EngineNote::StampFilterMisfit) {
      EXPECT_EQ(notes[i].counter, nullptr);
      continue;
    }
    const ap::CounterInfo* info = infoOf(notes[i].counter);
    ASSERT_NE(info, nullptr) << i;
    EXPECT_TRUE(names.insert(info->name).second) << info->name;
  }
  for (const ap::StampOutcome outcome : kStampOutcomes) {
    const ap::StampOutcomeRow& row = ap::stampOutcomeRow(outcome);
    if (!row.note) continue;
    EXPECT_EQ(ap::noteCounter(*row.note), row.event ? row.event : row.input)
        << ap::outcomeName(outcome);
  }
}

// The engine counts and notes what the rows say: a stale input (input counter and note), a
// gap (accepted, gaps and a note), and the clock: a gap of the dynamic model's grid (gaps and a
// note, no input counted).
TEST(OutcomeTable, TheEngineCountsAndNotesWhatTheRowsSay) {
  engine_fixtures::Recorder sink;
  ap::EngineConfig c = engine_fixtures::kinematicConfig();
  c.kinematic.time_policy.max_dt = 0.5;
  ap::AttitudeEngine engine(c, sink);
  engine.submit(rate(at(1.0), Eigen::Vector3d::UnitZ()));
  engine.submit(rate(at(1.01), Eigen::Vector3d::UnitZ()));
  const ap::EngineCounters before = engine.counters();
  engine.submit(rate(at(2.0), Eigen::Vector3d::UnitZ()));  // a gap: held
  const ap::StampOutcomeRow& gap = ap::stampOutcomeRow(ap::StampOutcome::HeldGap);
  EXPECT_EQ(engine.counters().*gap.input, before.*gap.input + 1);
  EXPECT_EQ(engine.counters().*gap.event, before.*gap.event + 1);
  ASSERT_FALSE(sink.notes.empty());
  EXPECT_EQ(sink.notes.back().kind, *gap.note);
  EXPECT_EQ(sink.notes.back().stamp, at(2.0));
}

TEST(OutcomeTable, AGridGapOfTheClockCountsItsEventAndNoInput) {
  engine_fixtures::Recorder sink;
  ap::EngineConfig c = engine_fixtures::torqueConfig();
  c.dynamic->time_policy.max_dt = 0.5;
  ap::AttitudeEngine engine(c, sink);
  engine.clockTick(at(1.0));
  engine.clockTick(at(1.02));
  const ap::EngineCounters before = engine.counters();
  engine.clockTick(at(3.0));  // the grid jumps 2 s: a gap of the clock's
  EXPECT_EQ(engine.counters().gaps, before.gaps + 1);
  EXPECT_EQ(engine.counters().accepted, before.accepted);  // no input
  ASSERT_FALSE(sink.notes.empty());
  EXPECT_EQ(sink.notes.back().kind, ap::EngineNote::Gap);
  EXPECT_FALSE(sink.notes.back().source.has_value());  // the clock's
}

// A model that, on each look at the clock, returns one result with the outcome it was given
// and no input (the clock's); everything else is the kinematic model's.
class ClockOutcomeModel final : public wrapped_model::WrappedKinematicModel {
 public:
  using WrappedKinematicModel::WrappedKinematicModel;
  ap::StampOutcome next = ap::StampOutcome::DroppedStale;

  void beginDue(ap::Stamp clock, std::optional<ap::Stamp>, bool) override { due_ = clock; }
  std::optional<ap::ModelResult> nextDue(std::optional<ap::Stamp>) override {
    if (!due_) return std::nullopt;
    ap::ModelResult r;
    r.outcome = next;
    r.stamp = *due_;
    due_.reset();
    return r;
  }

 private:
  std::optional<ap::Stamp> due_;
};

// Each outcome as the clock's (no input): only the event counter moves, and a note comes with
// an event only; a stale outcome of the clock counts and notes nothing.
TEST(OutcomeTable, AnOutcomeOfTheClockCountsItsEventOnlyAndNotesOnlyWithIt) {
  for (const ap::StampOutcome outcome : kStampOutcomes) {
    SCOPED_TRACE(ap::outcomeName(outcome));
    ClockOutcomeModel* model = nullptr;
    engine_fixtures::Recorder sink;
    ap::AttitudeEngine engine(engine_fixtures::kinematicConfig(), sink,
                              wrapped_model::factoryOf(model));
    model->next = outcome;
    engine.clockTick(at(1.0));
    const ap::StampOutcomeRow& row = ap::stampOutcomeRow(outcome);
    const ap::EngineCounters& c = engine.counters();
    for (const ap::CounterInfo& info : ap::engineCounterTable()) {
      if (info.field == nullptr) continue;
      EXPECT_EQ(c.*info.field, info.field == row.event ? 1u : 0u) << info.name;
    }
    EXPECT_EQ(sink.notes.size(), row.event != nullptr && row.note ? 1u : 0u);
  }
}

}  // namespace
