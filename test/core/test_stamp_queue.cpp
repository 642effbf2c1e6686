// time/stamp_queue.h: what waits for the rates. Truths: its documented rules (stamp order,
// equal stamps in arrival order, the furthest ahead dropped when full, the newcomer when it is
// the furthest), checked with the queue one short of full, full, and full with one more.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "attitude_propagator/time/stamp_queue.h"

namespace ap = attitude_propagator;

namespace {

std::vector<int> drain(ap::StampQueue<int>& q, ap::Stamp upto) {
  std::vector<int> out;
  while (q.due(upto)) out.push_back(q.pop());
  return out;
}

}  // namespace

TEST(StampQueue, KeepsStampOrderAndEqualStampsInTheirOrderOfArrival) {
  ap::StampQueue<int> q(8);
  for (const auto& [stamp, id] : std::vector<std::pair<ap::Stamp, int>>{
           {30, 1}, {10, 2}, {20, 3}, {20, 4}, {10, 5}, {40, 6}}) {
    EXPECT_TRUE(q.push(stamp, id).kept);
  }
  EXPECT_EQ(q.frontStamp(), 10);
  EXPECT_FALSE(q.due(9));  // nothing before its stamp
  EXPECT_EQ(drain(q, 10), (std::vector<int>{2, 5}));
  EXPECT_EQ(drain(q, 29), (std::vector<int>{3, 4}));
  EXPECT_EQ(drain(q, 1000), (std::vector<int>{1, 6}));
  EXPECT_TRUE(q.empty());
  EXPECT_FALSE(q.due(1000));
}

// Capacity 3: a third fits (n - 1 before it); a fourth, nearer than the furthest, drops the
// furthest (n); a fifth, at or beyond the furthest, is itself dropped (n + 1), the queue as it
// was.
TEST(StampQueue, FullItDropsTheFurthestAheadTheNewcomerWhenItIsThatOne) {
  ap::StampQueue<std::string> q(3);
  EXPECT_TRUE(q.push(10, "a").kept);
  EXPECT_TRUE(q.push(30, "c").kept);
  const auto third = q.push(20, "b");
  EXPECT_TRUE(third.kept);
  EXPECT_FALSE(third.dropped);
  EXPECT_EQ(q.size(), 3u);

  const auto nearer = q.push(15, "n");
  EXPECT_TRUE(nearer.kept);
  ASSERT_TRUE(nearer.dropped);
  EXPECT_EQ(*nearer.dropped, "c");
  EXPECT_EQ(q.size(), 3u);

  for (ap::Stamp stamp : {ap::Stamp{20}, ap::Stamp{21}}) {  // at the furthest, and beyond it
    const auto further = q.push(stamp, "x");
    EXPECT_FALSE(further.kept) << stamp;
    EXPECT_FALSE(further.dropped) << stamp;
    EXPECT_EQ(q.size(), 3u);
  }
  std::vector<std::string> order;
  while (!q.empty()) order.push_back(q.pop());
  EXPECT_EQ(order, (std::vector<std::string>{"a", "n", "b"}));
}

TEST(StampQueue, ClearedItHoldsNothingAndKeepsItsCapacity) {
  ap::StampQueue<int> q(2);
  q.push(1, 1);
  q.push(2, 2);
  q.clear();
  EXPECT_TRUE(q.empty());
  EXPECT_EQ(q.capacity(), 2u);
  EXPECT_TRUE(q.push(5, 5).kept);
  EXPECT_TRUE(q.push(6, 6).kept);
  EXPECT_FALSE(q.push(7, 7).kept);
}

// The rules on the stamps alone, as StampQueue asks them: placeInQueue's QueuePlace for a queue of
// capacity 3 holding 2 (n - 1), 3 (n) and, once more, after one dropped; dueBy at or before.
TEST(StampQueue, ThePlaceOfANewcomerAndWhenOneIsDueAreRulesOnTheStampsAlone) {
  const std::vector<ap::Stamp> two{10, 20}, three{10, 20, 20};
  const ap::QueuePlace fits = ap::placeInQueue(two, 20, 3);
  EXPECT_TRUE(fits.kept);
  EXPECT_FALSE(fits.drop);
  EXPECT_EQ(fits.at, 2u);  // after its equal
  const ap::QueuePlace nearer = ap::placeInQueue(three, 15, 3);
  EXPECT_TRUE(nearer.kept);
  ASSERT_TRUE(nearer.drop);
  EXPECT_EQ(*nearer.drop, 2u);  // the furthest ahead, the later of the two at 20
  EXPECT_EQ(nearer.at, 1u);
  for (ap::Stamp stamp : {ap::Stamp{20}, ap::Stamp{25}}) {
    const ap::QueuePlace furthest = ap::placeInQueue(three, stamp, 3);
    EXPECT_FALSE(furthest.kept) << stamp;
    EXPECT_FALSE(furthest.drop) << stamp;
  }
  EXPECT_TRUE(ap::placeInQueue({}, 5, 1).kept);
  EXPECT_FALSE(ap::placeInQueue({}, 5, 0).kept);  // a queue that holds nothing takes nothing
  EXPECT_TRUE(ap::dueBy(10, 10));
  EXPECT_TRUE(ap::dueBy(10, 11));
  EXPECT_FALSE(ap::dueBy(10, 9));
}
