// The models alone, without an engine: each call returns what it did (ModelResult), and the
// model calls nothing back (docs/design.md §5.3). These tests drive KinematicModel and
// DynamicScheduler on a TimeBase of their own and read the results.
#include <gtest/gtest.h>

#include <optional>
#include <vector>

#include "attitude_propagator/models/dynamic_scheduler.h"
#include "attitude_propagator/models/engine_config.h"
#include "attitude_propagator/models/kinematic_model.h"
#include "engine_fixtures.h"

namespace ap = attitude_propagator;
using engine_fixtures::at;
using engine_fixtures::rate;
using engine_fixtures::torque;

namespace {

using Covariance = ap::ModelResult::Covariance;

// Every unit of a pass, in order, until nextDue returns nothing. `last_published` follows the
// states the results publish, as the engine's does. A result's input is valid only until the
// model's next call: its stamp is read at once, into `input_stamps` (0 without an input).
std::vector<ap::ModelResult> wholePass(ap::Propagator& model, ap::Stamp clock,
                                       std::optional<ap::Stamp>& last_published,
                                       std::vector<ap::Stamp>* input_stamps = nullptr) {
  std::vector<ap::ModelResult> units;
  model.beginDue(clock, last_published, false);
  while (const std::optional<ap::ModelResult> r = model.nextDue(last_published)) {
    units.push_back(*r);
    if (input_stamps) input_stamps->push_back(r->input ? r->input->stamp : 0);
    if (r->publish) last_published = r->stamp;
    if (units.size() > 100) break;  // a pass that never ends fails below
  }
  return units;
}

TEST(KinematicModelResults, EachInputReturnsItsOutcomeCovarianceStepAndStateToPublish) {
  ap::TimeBase time;
  time.pin(at(1.0));
  ap::KinematicModel model(engine_fixtures::kinematicConfig(), time);
  const Eigen::Vector3d w(0.3, -0.2, 0.5);

  const ap::Input first = rate(at(1.0), w);
  const ap::ModelResult anchor = model.submit(first, std::nullopt);
  ASSERT_TRUE(anchor.outcome.has_value());
  EXPECT_EQ(*anchor.outcome, ap::StampOutcome::Anchored);
  EXPECT_EQ(anchor.covariance, Covariance::Anchor);  // the initial covariance again
  EXPECT_TRUE(anchor.publish);
  EXPECT_TRUE(anchor.hand_on);
  EXPECT_TRUE(anchor.keep_step);
  EXPECT_EQ(anchor.input, &first);
  EXPECT_EQ(anchor.stamp, first.stamp);

  const ap::Input second = rate(at(1.01), w);
  const ap::ModelResult step = model.submit(second, std::nullopt);
  ASSERT_TRUE(step.outcome.has_value());
  EXPECT_EQ(*step.outcome, ap::StampOutcome::Advanced);
  EXPECT_EQ(step.covariance, Covariance::Step);
  EXPECT_NEAR(step.h, 0.01, 1e-12);
  // A constant rate: the step's own rotation over its length is the rate.
  EXPECT_LT((step.w_step - w).norm(), 1e-9);
  EXPECT_EQ(step.stamp, second.stamp);
  EXPECT_TRUE(step.publish);
  EXPECT_EQ(step.late + step.pending_overflow + step.deferred_ticks, 0u);
  EXPECT_FALSE(step.note.has_value());
  EXPECT_FALSE(step.at.has_value());

  // A stale input: counted by the engine from the outcome, nothing published or handed on.
  const ap::ModelResult stale = model.submit(rate(at(1.005), w), std::nullopt);
  ASSERT_TRUE(stale.outcome.has_value());
  EXPECT_EQ(*stale.outcome, ap::StampOutcome::DroppedStale);
  EXPECT_FALSE(stale.publish);
  EXPECT_FALSE(stale.hand_on);
  EXPECT_EQ(stale.covariance, Covariance::Unchanged);
}

TEST(KinematicModelResults, NothingIsEverDueAndAJumpBackRestartsTime) {
  ap::TimeBase time;
  time.pin(at(1.0));
  ap::KinematicModel model(engine_fixtures::kinematicConfig(), time);
  model.submit(rate(at(1.0), Eigen::Vector3d::UnitZ()), std::nullopt);
  EXPECT_FALSE(model.firstStampFromClock(at(5.0)).has_value());  // the first input starts time
  model.beginDue(at(5.0), std::nullopt, false);
  EXPECT_FALSE(model.nextDue(std::nullopt).has_value());
  const ap::Propagator::InputOrderRestart restart = model.restartInputOrder(ap::Source::Imu);
  EXPECT_TRUE(restart.time_restarts);
  EXPECT_EQ(restart.dropped, 0u);
  EXPECT_EQ(model.reset(), 0u);  // nothing waits in the kinematic model
}

TEST(KinematicModelResults, AReplayReturnsWhatTheLiveStepReturned) {
  ap::TimeBase time;
  time.pin(at(1.0));
  ap::KinematicModel live(engine_fixtures::kinematicConfig(), time);
  live.submit(rate(at(1.0), Eigen::Vector3d(0.1, 0.2, 0.3)), std::nullopt);
  ap::ModelSnapshot saved;
  live.save(saved);
  const ap::Input next = rate(at(1.02), Eigen::Vector3d(0.4, -0.1, 0.2));
  const ap::ModelResult on_time = live.submit(next, std::nullopt);
  live.restore(saved);
  const ap::ModelResult again = live.replay(ap::ModelStep{next, false});
  // Against the step itself: a covariance step over the 0.02 s between the two stamps.
  EXPECT_EQ(again.covariance, Covariance::Step);
  EXPECT_NEAR(again.h, 0.02, 1e-12);
  EXPECT_EQ(again.covariance, on_time.covariance);
  EXPECT_EQ(again.h, on_time.h);
  EXPECT_EQ(again.w_step, on_time.w_step);
}

// A sphere with torque input on a 10 Hz grid; the clock at 1.0 s starts core time on the grid.
ap::EngineConfig tenHertzTorqueConfig(std::size_t grid_budget) {
  ap::EngineConfig c = engine_fixtures::torqueConfig();
  c.publish_rate = 10.0;
  c.grid_budget = grid_budget;
  return c;
}

TEST(DynamicSchedulerResults, FirstStampFromClockIsTheNewestGridStampAtOrBeforeIt) {
  ap::TimeBase time;
  ap::DynamicScheduler model(tenHertzTorqueConfig(1000), time);
  EXPECT_EQ(model.firstStampFromClock(at(1.0)), std::optional<ap::Stamp>(at(1.0)));
  EXPECT_EQ(model.firstStampFromClock(at(1.05)), std::optional<ap::Stamp>(at(1.0)));
  EXPECT_EQ(model.firstStampFromClock(at(1.0999)), std::optional<ap::Stamp>(at(1.0)));
}

TEST(DynamicSchedulerResults, NextDueReturnsOneUnitPerCallWaitingInputsBeforeTheirGridStamp) {
  ap::TimeBase time;
  time.pin(at(1.0));
  ap::DynamicScheduler model(tenHertzTorqueConfig(1000), time);
  std::optional<ap::Stamp> last_published;
  const std::vector<ap::ModelResult> start = wholePass(model, at(1.0), last_published);
  ASSERT_EQ(start.size(), 1u);
  EXPECT_EQ(start[0].stamp, at(1.0));
  EXPECT_TRUE(start[0].publish);
  EXPECT_TRUE(start[0].keep_step);  // the advance to a grid stamp (no input)
  EXPECT_EQ(start[0].input, nullptr);

  // Two torques stamped ahead of the clock wait: nothing acted, nothing kept.
  for (const double t : {1.05, 1.15}) {
    const ap::ModelResult waits = model.submit(torque(at(t), Eigen::Vector3d::UnitZ()), at(1.0));
    EXPECT_EQ(waits.input, nullptr);
    EXPECT_FALSE(waits.keep_step);
    EXPECT_FALSE(waits.outcome.has_value());
  }
  EXPECT_EQ(model.pending(), 2u);

  // The clock at 1.2 s: torque 1.05, grid 1.1, torque 1.15, grid 1.2, one a call.
  std::vector<ap::Stamp> input_stamps;
  const std::vector<ap::ModelResult> units =
      wholePass(model, at(1.2), last_published, &input_stamps);
  ASSERT_EQ(units.size(), 4u);
  const std::vector<ap::Stamp> stamps = {at(1.05), at(1.1), at(1.15), at(1.2)};
  for (std::size_t i = 0; i < units.size(); ++i) {
    SCOPED_TRACE(i);
    const ap::ModelResult& u = units[i];
    const bool input = i % 2 == 0;
    EXPECT_EQ(u.stamp, stamps[i]);
    EXPECT_TRUE(u.keep_step);
    EXPECT_EQ(u.publish, !input);  // the grid publishes
    EXPECT_EQ(u.hand_on, input);   // an input is handed on with the state at its stamp
    EXPECT_EQ(input_stamps[i], input ? stamps[i] : 0);
    if (input) {
      EXPECT_EQ(u.source, std::optional<ap::Source>(ap::Source::Torque));
    } else {
      EXPECT_EQ(u.input, nullptr);
      EXPECT_FALSE(u.source.has_value());  // the clock's
    }
  }
  EXPECT_EQ(model.pending(), 0u);
  EXPECT_EQ(last_published, std::optional<ap::Stamp>(at(1.2)));
}

TEST(DynamicSchedulerResults, APassSpendsItsGridBudgetThenDefersTheRest) {
  for (const std::size_t budget : {1, 2, 3}) {
    SCOPED_TRACE(budget);
    ap::TimeBase time;
    time.pin(at(1.0));
    ap::DynamicScheduler model(tenHertzTorqueConfig(budget), time);
    std::optional<ap::Stamp> last_published;
    wholePass(model, at(1.0), last_published);
    // Three grid stamps due (1.1, 1.2, 1.3): `budget` published, then one deferral (unless the
    // budget covers them all), and the pass is over.
    const std::vector<ap::ModelResult> units = wholePass(model, at(1.3), last_published);
    const std::size_t published = std::min<std::size_t>(budget, 3);
    ASSERT_EQ(units.size(), published + (budget < 3 ? 1 : 0));
    for (std::size_t i = 0; i < published; ++i) EXPECT_TRUE(units[i].publish);
    if (budget < 3) {
      const ap::ModelResult& deferral = units.back();
      EXPECT_FALSE(deferral.publish);
      EXPECT_EQ(deferral.deferred_ticks, 1u);
      ASSERT_TRUE(deferral.note.has_value());
      EXPECT_EQ(deferral.note->kind, ap::EngineNote::Deferred);
      EXPECT_EQ(deferral.note->stamp, at(1.0 + 0.1 * static_cast<double>(budget + 1)));
    }
  }
}

TEST(DynamicSchedulerResults, AJumpBackDropsOnlyThatSourcesWaitingInputsAndTimeGoesOn) {
  ap::TimeBase time;
  time.pin(at(1.0));
  ap::EngineConfig c = tenHertzTorqueConfig(1000);
  ap::DynamicScheduler model(c, time);
  std::optional<ap::Stamp> last_published;
  wholePass(model, at(1.0), last_published);
  model.submit(torque(at(1.05), Eigen::Vector3d::UnitZ()), at(1.0));
  model.submit(torque(at(1.06), Eigen::Vector3d::UnitZ()), at(1.0));
  model.submit(rate(at(1.07), Eigen::Vector3d::UnitX()), at(1.0));
  const ap::Propagator::InputOrderRestart restart = model.restartInputOrder(ap::Source::Torque);
  EXPECT_FALSE(restart.time_restarts);  // the dynamic model's time is the clock's
  EXPECT_EQ(restart.dropped, 2u);
  EXPECT_EQ(model.pending(), 1u);
  EXPECT_EQ(model.reset(), 1u);  // the one still waiting, for the engine to count
  EXPECT_EQ(model.pending(), 0u);
}

TEST(DynamicSchedulerResults, ALateInputReturnsTheStateAtItsOwnStamp) {
  // A sphere keeps its body rate, so the closed form is q(t) = q0 ⊗ exp(ω t / 2); a generic
  // start and axis tell q0 ⊗ exp from exp ⊗ q0 and a rate about z from one about another axis.
  const Eigen::Quaterniond q0(Eigen::AngleAxisd(0.7, Eigen::Vector3d(0.3, -0.5, 0.8).normalized()));
  const Eigen::Vector3d w(0.15, -0.25, 0.1);
  ap::EngineConfig config = engine_fixtures::spinningSphereConfig();
  config.dynamic->initial.q_WB = q0;
  config.dynamic->initial.w_B = w;
  ap::TimeBase time;
  time.pin(at(1.0));
  ap::DynamicScheduler model(config, time);
  std::optional<ap::Stamp> last_published;
  wholePass(model, at(1.0), last_published);
  wholePass(model, at(1.1), last_published);  // the grid at 50 Hz up to 1.1 s
  const ap::ModelResult r = model.submit(rate(at(1.05), w), at(1.1));
  ASSERT_TRUE(r.outcome.has_value());
  EXPECT_EQ(r.late, 1u);
  EXPECT_TRUE(r.hand_on);
  ASSERT_TRUE(r.at.has_value());
  // The closed form at the input's own stamp, 0.05 s after the start.
  const Eigen::Quaterniond expected =
      q0 * Eigen::Quaterniond(Eigen::AngleAxisd(w.norm() * 0.05, w.normalized()));
  EXPECT_LT(r.at->q_WB.angularDistance(expected), 1e-9);
  EXPECT_LT((r.at->w_B - w).norm(), 1e-12);
}

}  // namespace
