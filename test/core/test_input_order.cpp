// time/input_order.h: each source's order, with the inputs of a run from an earlier time held.
// Truths: the documented rules (docs/design.md §6.5, the header's comments): an input at or
// before its source's newest is a straggler, dropped; a run more than backward_jump back is
// held and is a jump at its kJumpConfirmation-th input (checked one short of it, at it and one
// past it), its held inputs then returned in order to go first; a run that breaks hands its
// inputs back as stale; one input far ahead of its source's lead is held ahead; each source is
// judged against its own inputs only.
#include <gtest/gtest.h>

#include <optional>
#include <vector>

#include "attitude_propagator/time/input_order.h"

namespace ap = attitude_propagator;

namespace {

using Order = ap::InputOrder<int>;
using ap::OrderVerdict;

constexpr ap::Stamp kSecond = 1'000'000'000;
constexpr ap::Stamp kMs = 1'000'000;
const ap::TimePolicy kPolicy{};  // max_dt 1 s, backward_jump 1 s

// Judges input `id` of source 0 at `stamp` without a clock.
Order::Judged judge(Order& order, ap::Stamp stamp, int id,
                    std::optional<ap::Stamp> clock = std::nullopt, std::size_t source = 0) {
  return order.judge(source, stamp, id, clock, kPolicy);
}

// Source 0's newest at 100 s, then `n` inputs of a run from 50 s (10 ms apart, going on from one
// another), ids 1..n; returns the verdicts of the run.
std::vector<OrderVerdict> runFromEarlierTime(Order& order, int n) {
  EXPECT_EQ(judge(order, 100 * kSecond, 0).verdict, OrderVerdict::Use);
  std::vector<OrderVerdict> verdicts;
  for (int i = 1; i <= n; ++i)
    verdicts.push_back(judge(order, 50 * kSecond + i * 10 * kMs, i).verdict);
  return verdicts;
}

}  // namespace

TEST(InputOrder, UsesInputsInOrderAndHoldsNothing) {
  Order order(3);
  for (int i = 0; i < 5; ++i) {
    const Order::Judged judged = judge(order, 10 * kSecond + i * 10 * kMs, i);
    EXPECT_EQ(judged.verdict, OrderVerdict::Use);
    EXPECT_TRUE(judged.released.empty());
    EXPECT_TRUE(judged.confirming.empty());
  }
  EXPECT_EQ(order.held(0), 0u);
}

TEST(InputOrder, DropsAStragglerAtOrBeforeTheNewestWithinTheThreshold) {
  Order order(3);
  ASSERT_EQ(judge(order, 10 * kSecond, 1).verdict, OrderVerdict::Use);
  EXPECT_EQ(judge(order, 10 * kSecond, 2).verdict, OrderVerdict::Stale);  // at the newest
  EXPECT_EQ(judge(order, 9 * kSecond + 500 * kMs, 3).verdict, OrderVerdict::Stale);
  EXPECT_EQ(judge(order, 9 * kSecond, 4).verdict, OrderVerdict::Stale);  // exactly 1 s back
  EXPECT_EQ(order.held(0), 0u);
  // The straggler changed nothing: the next input after the newest is in order.
  EXPECT_EQ(judge(order, 10 * kSecond + 1, 5).verdict, OrderVerdict::Use);
}

TEST(InputOrder, ATimelineAllowingRepeatedStampsTakesAnEqualStampInOrder) {
  Order order(3);
  order.timeline(0).allowRepeatedStamps(true);  // the sensor-clock filter's FIFO reads
  ASSERT_EQ(judge(order, 10 * kSecond, 1).verdict, OrderVerdict::Use);
  EXPECT_EQ(judge(order, 10 * kSecond, 2).verdict, OrderVerdict::Use);
  EXPECT_EQ(judge(order, 10 * kSecond, 3, std::nullopt, 1).verdict, OrderVerdict::Use);
  EXPECT_EQ(judge(order, 10 * kSecond, 4, std::nullopt, 1).verdict, OrderVerdict::Stale);
}

// One short of kJumpConfirmation: every input of the run is held, none used, none dropped yet.
TEST(InputOrder, HoldsARunFromAnEarlierTimeOneShortOfTheConfirmation) {
  Order order(3);
  const std::vector<OrderVerdict> verdicts = runFromEarlierTime(order, ap::kJumpConfirmation - 1);
  for (OrderVerdict v : verdicts) EXPECT_EQ(v, OrderVerdict::HeldInRun);
  EXPECT_EQ(order.held(0), static_cast<std::size_t>(ap::kJumpConfirmation - 1));
}

// At kJumpConfirmation: a jump back; the run's inputs before it come back in order, to go first.
TEST(InputOrder, ConfirmsAJumpAtTheConfirmationAndReturnsTheRunInOrder) {
  Order order(3);
  runFromEarlierTime(order, ap::kJumpConfirmation - 1);
  const int last = ap::kJumpConfirmation;
  const Order::Judged judged = judge(order, 50 * kSecond + last * 10 * kMs, last);
  EXPECT_EQ(judged.verdict, OrderVerdict::JumpedBack);
  std::vector<int> run;
  for (int i = 1; i < last; ++i) run.push_back(i);
  EXPECT_EQ(judged.confirming, run);
  EXPECT_TRUE(judged.released.empty());
  EXPECT_EQ(order.held(0), 0u);
}

// One past kJumpConfirmation: the new timeline goes on, in order; the old one's stamps are now
// stragglers of it only when at or before its newest.
TEST(InputOrder, GoesOnFromTheJumpOnePastTheConfirmation) {
  Order order(3);
  const std::vector<OrderVerdict> verdicts = runFromEarlierTime(order, ap::kJumpConfirmation + 1);
  EXPECT_EQ(verdicts[ap::kJumpConfirmation - 1], OrderVerdict::JumpedBack);
  EXPECT_EQ(verdicts[ap::kJumpConfirmation], OrderVerdict::Use);
  EXPECT_EQ(order.held(0), 0u);
  EXPECT_EQ(judge(order, 50 * kSecond, 99).verdict, OrderVerdict::Stale);  // behind the jump
}

TEST(InputOrder, ARunBrokenByAnInputInOrderIsReleasedAsStale) {
  Order order(3);
  runFromEarlierTime(order, ap::kJumpConfirmation - 1);
  const Order::Judged judged = judge(order, 100 * kSecond + 10 * kMs, 10);
  EXPECT_EQ(judged.verdict, OrderVerdict::Use);
  EXPECT_EQ(judged.released, (std::vector<int>{1, 2}));
  EXPECT_TRUE(judged.confirming.empty());
  EXPECT_EQ(order.held(0), 0u);
}

TEST(InputOrder, ARunBrokenByAStragglerIsReleasedBeforeIt) {
  Order order(3);
  runFromEarlierTime(order, ap::kJumpConfirmation - 1);
  const Order::Judged judged = judge(order, 99 * kSecond + 500 * kMs, 10);  // within 1 s
  EXPECT_EQ(judged.verdict, OrderVerdict::Stale);
  EXPECT_EQ(judged.released, (std::vector<int>{1, 2}));
  EXPECT_EQ(order.held(0), 0u);
}

// A stamp that does not go on from the run (before its last, or more than max_dt after it)
// starts a run of its own: the one before is released, the new one held.
TEST(InputOrder, ARunThatDoesNotGoOnStartsAfreshReleasingTheOneBefore) {
  Order order(3);
  runFromEarlierTime(order, ap::kJumpConfirmation - 1);
  Order::Judged judged = judge(order, 50 * kSecond, 10);  // before the run's last
  EXPECT_EQ(judged.verdict, OrderVerdict::HeldInRun);
  EXPECT_EQ(judged.released, (std::vector<int>{1, 2}));
  EXPECT_EQ(order.held(0), 1u);
  judged = judge(order, 52 * kSecond, 11);  // 2 s after it: more than max_dt
  EXPECT_EQ(judged.verdict, OrderVerdict::HeldInRun);
  EXPECT_EQ(judged.released, (std::vector<int>{10}));
  EXPECT_EQ(order.held(0), 1u);
}

// Lag 0 at a clock of 100 s, then inputs 5 s ahead of it: the first kJumpConfirmation - 1 are
// held ahead, the next is the source's new lead and used.
TEST(InputOrder, HoldsAheadAForwardGlitchUntilItPersists) {
  Order order(3);
  const ap::Stamp clock = 100 * kSecond;
  ASSERT_EQ(judge(order, clock, 0, clock).verdict, OrderVerdict::Use);
  ASSERT_TRUE(order.lag(0).has_value());
  for (int i = 1; i < ap::kJumpConfirmation; ++i) {
    EXPECT_EQ(judge(order, clock + 5 * kSecond + i * 10 * kMs, i, clock).verdict,
              OrderVerdict::HeldAhead);
  }
  EXPECT_EQ(order.held(0), 0u);  // dropped, not held for later
  const int last = ap::kJumpConfirmation;
  EXPECT_EQ(judge(order, clock + 5 * kSecond + last * 10 * kMs, last, clock).verdict,
            OrderVerdict::Use);
}

TEST(InputOrder, HoldsNothingAheadWithoutAClock) {
  Order order(3);
  ASSERT_EQ(judge(order, 100 * kSecond, 0, 100 * kSecond).verdict, OrderVerdict::Use);
  EXPECT_EQ(judge(order, 105 * kSecond, 1).verdict, OrderVerdict::Use);
}

// An input held ahead neither goes on with a run from an earlier time nor breaks it.
TEST(InputOrder, AnInputHeldAheadLeavesTheHeldRunAsItWas) {
  Order order(3);
  const ap::Stamp clock = 100 * kSecond;
  ASSERT_EQ(judge(order, clock, 0, clock).verdict, OrderVerdict::Use);
  EXPECT_EQ(judge(order, 50 * kSecond, 1, clock).verdict, OrderVerdict::HeldInRun);
  EXPECT_EQ(judge(order, 50 * kSecond + 10 * kMs, 2, clock).verdict, OrderVerdict::HeldInRun);
  const Order::Judged ahead = judge(order, clock + 5 * kSecond, 3, clock);
  EXPECT_EQ(ahead.verdict, OrderVerdict::HeldAhead);
  EXPECT_TRUE(ahead.released.empty());
  EXPECT_EQ(order.held(0), 2u);
  const Order::Judged jump = judge(order, 50 * kSecond + 20 * kMs, 4, clock);
  EXPECT_EQ(jump.verdict, OrderVerdict::JumpedBack);
  EXPECT_EQ(jump.confirming, (std::vector<int>{1, 2}));
}

TEST(InputOrder, JudgesEachSourceAgainstItsOwnInputsOnly) {
  Order order(3);
  ASSERT_EQ(judge(order, 100 * kSecond, 1, std::nullopt, 0).verdict, OrderVerdict::Use);
  // Far behind source 0, yet the first of source 1: in order.
  EXPECT_EQ(judge(order, 10 * kSecond, 2, std::nullopt, 1).verdict, OrderVerdict::Use);
  // Source 0 holds a run; source 1's inputs neither break it nor go on with it.
  EXPECT_EQ(judge(order, 50 * kSecond, 3, std::nullopt, 0).verdict, OrderVerdict::HeldInRun);
  const Order::Judged other = judge(order, 10 * kSecond + 10 * kMs, 4, std::nullopt, 1);
  EXPECT_EQ(other.verdict, OrderVerdict::Use);
  EXPECT_TRUE(other.released.empty());
  EXPECT_EQ(judge(order, 10 * kSecond, 5, std::nullopt, 1).verdict, OrderVerdict::Stale);
  EXPECT_EQ(order.held(0), 1u);
  EXPECT_EQ(order.held(1), 0u);
  EXPECT_EQ(judge(order, 50 * kSecond + 10 * kMs, 6, std::nullopt, 0).verdict,
            OrderVerdict::HeldInRun);
  EXPECT_EQ(order.held(0), 2u);
}

TEST(InputOrder, ForgetReleasesEveryHeldRunSourceBySourceAndStartsEveryTimelineAfresh) {
  Order order(3);
  for (std::size_t source : {0u, 2u}) {
    ASSERT_EQ(judge(order, 100 * kSecond, 0, 100 * kSecond, source).verdict, OrderVerdict::Use);
  }
  judge(order, 50 * kSecond, 21, std::nullopt, 2);
  judge(order, 50 * kSecond, 1, std::nullopt, 0);
  judge(order, 50 * kSecond + 10 * kMs, 2, std::nullopt, 0);
  EXPECT_EQ(order.forget(), (std::vector<int>{1, 2, 21}));
  EXPECT_EQ(order.held(0), 0u);
  EXPECT_EQ(order.held(2), 0u);
  EXPECT_FALSE(order.lag(0).has_value());
  // Every stamp forgotten: an earlier one is the first of its source again.
  EXPECT_EQ(judge(order, 10 * kSecond, 3, std::nullopt, 0).verdict, OrderVerdict::Use);
  EXPECT_EQ(judge(order, 10 * kSecond, 4, std::nullopt, 2).verdict, OrderVerdict::Use);
}

// After a jump that restarted the model's time the engine forgets every timeline; the jump's
// stamp is then the source's first again, so what follows is judged against it.
TEST(InputOrder, StartAgainAtMakesTheJumpsStampTheNewestAfterForget) {
  Order order(3);
  runFromEarlierTime(order, ap::kJumpConfirmation);
  order.forget();
  const ap::Stamp jump = 50 * kSecond + ap::kJumpConfirmation * 10 * kMs;
  order.startAgainAt(0, jump, kPolicy);
  EXPECT_EQ(judge(order, jump, 1).verdict, OrderVerdict::Stale);
  EXPECT_EQ(judge(order, jump + 10 * kMs, 2).verdict, OrderVerdict::Use);
}

// The lag is observed for an input used in order; a jump's only through observeLag, once the
// engine has restarted the model (which may forget it).
TEST(InputOrder, ObservesTheLagOfInputsInOrderAndAJumpsThroughObserveLag) {
  Order order(3);
  const ap::Stamp clock = 100 * kSecond;
  ASSERT_EQ(judge(order, clock - 250 * kMs, 0, clock).verdict, OrderVerdict::Use);
  ASSERT_TRUE(order.lag(0).has_value());
  EXPECT_NEAR(*order.lag(0), 0.25, 1e-12);  // the first lag, as it is
  for (int i = 1; i < ap::kJumpConfirmation; ++i) judge(order, 50 * kSecond + i * kMs, i, clock);
  const ap::Stamp jump = 50 * kSecond + ap::kJumpConfirmation * kMs;
  ASSERT_EQ(judge(order, jump, 9, clock).verdict, OrderVerdict::JumpedBack);
  EXPECT_NEAR(*order.lag(0), 0.25, 1e-12);  // not yet
  order.forget();
  order.observeLag(0, clock, jump);
  ASSERT_TRUE(order.lag(0).has_value());
  EXPECT_NEAR(*order.lag(0), 1e-9 * static_cast<double>(clock - jump), 1e-12);
  order.observeLag(1, std::nullopt, jump);  // no clock: nothing to record
  EXPECT_FALSE(order.lag(1).has_value());
}

// The rule on stamps alone: it says when a held run broke; InputOrder hands its inputs back.
TEST(SourceOrder, SaysWhenTheRunBeforeAnInputBroke) {
  ap::SourceOrder order;
  ASSERT_EQ(order.judge(100 * kSecond, std::nullopt, kPolicy).verdict, OrderVerdict::Use);
  ap::SourceOrder::Judged judged = order.judge(50 * kSecond, std::nullopt, kPolicy);
  EXPECT_EQ(judged.verdict, OrderVerdict::HeldInRun);
  EXPECT_TRUE(judged.run_broke);  // nothing was held before it: nothing to release
  judged = order.judge(50 * kSecond + 10 * kMs, std::nullopt, kPolicy);
  EXPECT_EQ(judged.verdict, OrderVerdict::HeldInRun);
  EXPECT_FALSE(judged.run_broke);  // it goes on with the run
  judged = order.judge(100 * kSecond + 10 * kMs, std::nullopt, kPolicy);
  EXPECT_EQ(judged.verdict, OrderVerdict::Use);
  EXPECT_TRUE(judged.run_broke);
  EXPECT_EQ(order.timeline().newest(), 100 * kSecond + 10 * kMs);
}
