// The refusal table (refusal_table.h) against what its readers do: each refusal of an input is
// counted once, under the engine's counter the table names, and under no other; each refusal of
// a fix has the fix counter the table names; FixRefusals counts every field the table points
// to, and the table points to every field its total adds.
#include <gtest/gtest.h>

#include <cstdint>
#include <set>
#include <string>

#include "../core/engine_fixtures.h"
#include "attitude_propagator/messages/refusal_table.h"

namespace ap = attitude_propagator;

namespace {

constexpr int kRefusedCount = static_cast<int>(ap::Refused::FixBodyFrame) + 1;

TEST(RefusalTable, HoldsEveryRefusalOnceInTheEnumsOrder) {
  ASSERT_EQ(ap::refusalTable().size(), static_cast<std::size_t>(kRefusedCount));
  for (int i = 0; i < kRefusedCount; ++i) {
    const auto why = static_cast<ap::Refused>(i);
    EXPECT_EQ(ap::refusalTable()[i].why, why);
    EXPECT_EQ(&ap::refusalRow(why), &ap::refusalTable()[i]);
  }
}

// An input's refusal counts `received` and the one counter named, nothing else; a fix's
// refusal counts nothing in the engine (the fix input counts it).
TEST(RefusalTable, CountRefusalCountsTheNamedCounterOnceAndNoOther) {
  for (const ap::RefusalRow& row : ap::refusalTable()) {
    SCOPED_TRACE(ap::refusedCounter(row.why));
    engine_fixtures::DiscardingSink sink;
    ap::AttitudeEngine engine(ap::engineConfig(ap::validateParameters(ap::Parameters())), sink);
    ap::countRefusal(engine, row.why);
    for (const ap::CounterInfo& info : ap::engineCounterTable()) {
      const std::uint64_t value = ap::counterValue(engine.counters(), info);
      const bool named = row.input_counter && info.name == row.input_counter;
      const bool received = info.name == "received" && row.rejection;
      EXPECT_EQ(value, named || received ? 1u : 0u) << info.name;
    }
    if (row.input_counter) {
      EXPECT_STREQ(ap::refusedCounter(row.why), row.input_counter);
    }
  }
}

TEST(RefusalTable, EveryInputCounterIsTheEnginesAndEveryRowCountsSomewhere) {
  std::set<std::string> engine_names;
  for (const ap::CounterInfo& info : ap::engineCounterTable()) engine_names.insert(info.name);
  for (const ap::RefusalRow& row : ap::refusalTable()) {
    EXPECT_TRUE(row.input_counter || row.fix_counter) << static_cast<int>(row.why);
    if (row.input_counter) {
      EXPECT_EQ(engine_names.count(row.input_counter), 1u);
    }
    EXPECT_EQ(row.input_counter != nullptr, row.rejection.has_value() || row.bias);
    EXPECT_EQ(row.fix_counter != nullptr, row.fix_count != nullptr);
    if (row.fix_counter) {
      EXPECT_STREQ(ap::fixRefusedCounter(row.why), row.fix_counter);
    }
  }
}

// Distinct powers of two in each field the table points to: the total is their sum exactly
// when the table reaches every field total() adds, each once.
TEST(RefusalTable, ReachesEveryFieldOfFixRefusalsOnce) {
  ap::FixRefusals r;
  std::uint64_t expected = 0;
  std::uint64_t bit = 1;
  for (const ap::RefusalRow& row : ap::refusalTable()) {
    if (!row.fix_count) continue;
    r.*row.fix_count += bit;
    expected += bit;
    bit <<= 1;
  }
  EXPECT_EQ(r.total(), expected);
  EXPECT_EQ(bit, std::uint64_t{1} << 5);  // five fix refusals
}

// The tools' summaries: each fix counter of the table once, in its order, by its short name with
// its own field's count (distinct counts: a field read for another's name shows).
TEST(RefusalTable, TheSummariesCountEachFixRefusalByItsShortName) {
  ap::FixRefusals r;
  r.no_tf = 11;
  r.type = 12;
  r.no_time = 13;
  r.no_orientation = 14;
  r.body_frame = 15;
  EXPECT_EQ(ap::fixRefusalCounts(r),
            "type 12, no_tf 11, no_time 13, no_orientation 14, body_frame 15");
  EXPECT_EQ(ap::fixRefusalCounts(ap::FixRefusals{}),
            "type 0, no_tf 0, no_time 0, no_orientation 0, body_frame 0");
}

}  // namespace
