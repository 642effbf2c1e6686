// models/fix_history.h: the ring of states a late fix is applied at. Truths: its documented
// rules (oldest first; a new id per new entry; the entry at or before newest - span kept; the
// oldest dropped at kMaxFixHistorySamples), checked at the bounds and one either side.
#include <gtest/gtest.h>

#include <cstdint>
#include <set>

#include "attitude_propagator/limits.h"
#include "attitude_propagator/models/fix_history.h"

namespace ap = attitude_propagator;

namespace {

void appendAt(ap::FixHistory& h, ap::Stamp stamp) { h.append().stamp = stamp; }

}  // namespace

TEST(FixHistory, KeepsEntriesOldestFirstEachWithAnIdOfItsOwn) {
  ap::FixHistory h;
  EXPECT_TRUE(h.empty());
  std::set<std::uint64_t> ids;
  for (ap::Stamp t = 10; t <= 50; t += 10) appendAt(h, t);
  ASSERT_EQ(h.size(), 5u);
  for (std::size_t i = 0; i < h.size(); ++i) {
    EXPECT_EQ(h[i].stamp, static_cast<ap::Stamp>(10 * (i + 1)));
    EXPECT_TRUE(ids.insert(h[i].id).second);
    EXPECT_EQ(*h.find(h[i].id), i);
  }
  EXPECT_EQ(h.newest().stamp, 50);
  // Cleared, the slots are reused with new ids: no id of before names an entry.
  h.clear();
  EXPECT_TRUE(h.empty());
  appendAt(h, 60);
  EXPECT_EQ(ids.count(h[0].id), 0u);
  for (std::uint64_t id : ids) EXPECT_FALSE(h.find(id));
}

// The entry at or before newest - span is kept (a fix stamped exactly there needs it): with
// entries every 10 ns and the newest at 100, a span of 30 keeps 70 on (exactly there); a span of
// 29 and 31 keep 70 and 60 on (the entries at or before 71 and 69).
TEST(FixHistory, KeepsTheEntryAtOrBeforeTheSpanAndDropsTheOnesBefore) {
  for (const auto& [span, oldest] : {std::pair<ap::Stamp, ap::Stamp>{29, 70}, {30, 70}, {31, 60}}) {
    ap::FixHistory h;
    for (ap::Stamp t = 10; t <= 100; t += 10) appendAt(h, t);
    const std::uint64_t dropped = h[0].id;
    h.keepSpan(100, span);
    EXPECT_EQ(h[0].stamp, oldest) << span;
    EXPECT_EQ(h.newest().stamp, 100);
    EXPECT_FALSE(h.find(dropped));
    appendAt(h, 110);  // the ring goes on after a drop
    EXPECT_EQ(h.newest().stamp, 110);
    EXPECT_EQ(h[0].stamp, oldest);
  }
  ap::FixHistory one;
  appendAt(one, 10);
  one.keepSpan(1000, 1);  // the last entry is never dropped
  EXPECT_EQ(one.size(), 1u);
}

TEST(FixHistory, InsertsAtAPositionWithANewIdTheLaterEntriesMovedUp) {
  ap::FixHistory h;
  for (ap::Stamp t = 10; t <= 40; t += 10) appendAt(h, t);
  h.keepSpan(40, 25);  // the head moves: the ring no longer starts at its first slot
  ASSERT_EQ(h[0].stamp, 10);
  h.keepSpan(40, 15);
  ASSERT_EQ(h[0].stamp, 20);
  const std::uint64_t at_30 = h[1].id;
  std::size_t pos = 1;
  ap::FixHistoryEntry& inserted = h.insert(pos);
  inserted.stamp = 25;
  EXPECT_EQ(pos, 1u);
  ASSERT_EQ(h.size(), 4u);
  EXPECT_EQ(h[0].stamp, 20);
  EXPECT_EQ(h[1].stamp, 25);
  EXPECT_EQ(h[2].stamp, 30);
  EXPECT_EQ(h[3].stamp, 40);
  EXPECT_EQ(*h.find(at_30), 2u);
  EXPECT_NE(h[1].id, at_30);
  EXPECT_EQ(*h.find(h[1].id), 1u);
}

// At kMaxFixHistorySamples entries the oldest goes: appending one more keeps the bound and
// drops the first; inserting one drops the first and moves the position down with it.
TEST(FixHistory, HoldsAtMostTheBoundTheOldestDroppedFirst) {
  ap::FixHistory h;
  const auto n = static_cast<ap::Stamp>(ap::kMaxFixHistorySamples);
  for (ap::Stamp t = 1; t < n; ++t) appendAt(h, t);
  EXPECT_EQ(h.size(), ap::kMaxFixHistorySamples - 1);
  appendAt(h, n);
  EXPECT_EQ(h.size(), ap::kMaxFixHistorySamples);
  EXPECT_EQ(h[0].stamp, 1);
  const std::uint64_t first = h[0].id;
  appendAt(h, n + 1);
  EXPECT_EQ(h.size(), ap::kMaxFixHistorySamples);
  EXPECT_EQ(h[0].stamp, 2);
  EXPECT_EQ(h.newest().stamp, n + 1);
  EXPECT_FALSE(h.find(first));
  std::size_t pos = 10;      // before the entry stamped 12, after the one stamped 11
  h.insert(pos).stamp = 11;  // (a second state at 11: a measurement applied there)
  EXPECT_EQ(pos, 9u);
  EXPECT_EQ(h.size(), ap::kMaxFixHistorySamples);
  EXPECT_EQ(h[0].stamp, 3);
  EXPECT_EQ(h[9].stamp, 11);
  EXPECT_EQ(h[10].stamp, 12);
  EXPECT_EQ(h.newest().stamp, n + 1);
}
