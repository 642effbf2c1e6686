// AttitudeEngine::clockTicksTo, the clock a run without a clock record (a bag with no /clock)
// gets from its inputs' stamps, against its documented rule: steps of at most half grid_budget
// grid periods ending at the stamp, so no grid stamp is ever deferred by the budget; a jump
// longer than max_dt, or back, stays one tick.
#include <gtest/gtest.h>

#include <cstdint>
#include <optional>
#include <vector>

#include "attitude_propagator/engine.h"
#include "engine_fixtures.h"

namespace ap = attitude_propagator;
using namespace engine_fixtures;  // NOLINT: the fixtures are the tests' vocabulary

namespace {

/// torqueConfig (50 Hz grid, max_dt 1 s) with a budget of 10 grid stamps per call: 0.2 s.
ap::EngineConfig smallBudgetConfig() {
  ap::EngineConfig c = torqueConfig();
  c.grid_budget = 10;
  return c;
}

/// Submits a torque at `stamp` and ticks the clock to it as the ticks say; returns them.
std::vector<ap::Stamp> submitAndTick(ap::AttitudeEngine& engine, std::optional<ap::Stamp>& last,
                                     ap::Stamp stamp) {
  engine.submit(torque(stamp, Eigen::Vector3d(0.0, 0.0, 0.1)));
  const std::vector<ap::Stamp> ticks = engine.clockTicksTo(last, stamp);
  for (ap::Stamp t : ticks) engine.clockTick(t);
  last = last ? std::max(*last, stamp) : stamp;
  return ticks;
}

/// Every grid stamp in (from, to] has a published state.
void expectEveryGridStampPublished(const ap::AttitudeEngine& engine, const Recorder& sink,
                                   ap::Stamp from, ap::Stamp to) {
  std::int64_t k = engine.gridIndexAtOrBefore(from) + 1;
  int expected = 0;
  for (; engine.gridStamp(k) <= to; ++k, ++expected) {
    EXPECT_NE(sink.stateAt(engine.gridStamp(k)), nullptr) << "grid stamp " << k << " deferred";
  }
  EXPECT_GT(expected, 10) << "the span must exceed one call's budget to test it";
}

TEST(ClockTicks, TheFirstStampIsOneTick) {
  DiscardingSink sink;
  const ap::AttitudeEngine engine(smallBudgetConfig(), sink);
  EXPECT_EQ(engine.clockTicksTo(std::nullopt, at(3.0)), std::vector<ap::Stamp>{at(3.0)});
}

TEST(ClockTicks, StepsOfHalfTheBudgetEndAtTheStamp) {
  DiscardingSink sink;
  const ap::AttitudeEngine engine(smallBudgetConfig(), sink);
  const std::vector<ap::Stamp> ticks = engine.clockTicksTo(at(1.0), at(1.95));
  // Half of 10 grid periods at 50 Hz: 0.1 s; 1.1, 1.2, ..., 1.9, then 1.95.
  ASSERT_EQ(ticks.size(), 10u);
  for (std::size_t i = 0; i + 1 < ticks.size(); ++i) {
    EXPECT_EQ(ticks[i], at(1.0) + static_cast<ap::Stamp>(i + 1) * kSecond / 10) << i;
  }
  EXPECT_EQ(ticks.back(), at(1.95));
}

TEST(ClockTicks, NoGridStampIsDeferredByTheBudget) {
  Recorder sink;
  ap::AttitudeEngine engine(smallBudgetConfig(), sink);
  std::optional<ap::Stamp> last;
  submitAndTick(engine, last, at(0.0));
  // 0.99 s apart, within max_dt: 49 grid stamps, almost five calls' budget.
  submitAndTick(engine, last, at(0.99));
  submitAndTick(engine, last, at(1.98));
  expectEveryGridStampPublished(engine, sink, at(0.0), at(1.98));
  EXPECT_TRUE(sink.stampsIncrease());
}

// Without the steps, one tick to the stamp leaves grid stamps to a later call: the budget is
// what the steps are for (this test fails when it does not).
TEST(ClockTicks, OneTickToTheStampWouldDeferGridStamps) {
  Recorder sink;
  ap::AttitudeEngine engine(smallBudgetConfig(), sink);
  engine.submit(torque(at(0.0), Eigen::Vector3d(0.0, 0.0, 0.1)));
  engine.clockTick(at(0.0));
  engine.submit(torque(at(0.99), Eigen::Vector3d(0.0, 0.0, 0.1)));
  engine.clockTick(at(0.99));
  EXPECT_EQ(sink.stateAt(engine.gridStamp(engine.gridIndexAtOrBefore(at(0.99)))), nullptr);
}

TEST(ClockTicks, AJumpLongerThanMaxDtStaysOneTick) {
  DiscardingSink sink;
  const ap::AttitudeEngine engine(smallBudgetConfig(), sink);  // max_dt 1 s
  EXPECT_EQ(engine.clockTicksTo(at(1.0), at(2.5)), std::vector<ap::Stamp>{at(2.5)});
  // At max_dt exactly the clock still steps (a gap is longer than max_dt).
  EXPECT_EQ(engine.clockTicksTo(at(1.0), at(2.0)).size(), 10u);
}

TEST(ClockTicks, AStampNotAheadIsOneTick) {
  DiscardingSink sink;
  const ap::AttitudeEngine engine(smallBudgetConfig(), sink);
  EXPECT_EQ(engine.clockTicksTo(at(2.0), at(2.0)), std::vector<ap::Stamp>{at(2.0)});
  EXPECT_EQ(engine.clockTicksTo(at(2.0), at(1.0)), std::vector<ap::Stamp>{at(1.0)});
}

TEST(ClockTicks, AGapIsHeldNotStepped) {
  Recorder sink;
  ap::AttitudeEngine engine(smallBudgetConfig(), sink);
  std::optional<ap::Stamp> last;
  submitAndTick(engine, last, at(0.0));
  const std::size_t before = sink.states.size();
  submitAndTick(engine, last, at(3.0));
  // No grid stamp inside the 3 s gap is published (the node's rule for a clock jumping ahead).
  for (std::size_t i = before; i < sink.states.size(); ++i) {
    EXPECT_FALSE(sink.states[i].stamp > at(0.0) && sink.states[i].stamp < at(3.0))
        << sink.states[i].stamp - at(0.0);
  }
}

}  // namespace
