// A late fix's replay against a model of the test's own: a spy around the kinematic model that
// records what the engine asks of it. Replay is the steps kept after the entry the fix acts at,
// handed to Propagator::replay in order as they were received (the bias estimate subtracted as
// it is then), and nothing else: the model's live path is not called, and nothing is counted,
// noted or published on the way (docs/design.md §6.9).
#include <gtest/gtest.h>

#include <memory>
#include <vector>

#include "attitude_propagator/engine.h"
#include "engine_fixtures.h"
#include "wrapped_model.h"

namespace ap = attitude_propagator;
using engine_fixtures::at;
using engine_fixtures::rate;
using engine_fixtures::Recorder;

namespace {

class SpyModel final : public wrapped_model::WrappedKinematicModel {
 public:
  using WrappedKinematicModel::WrappedKinematicModel;

  std::vector<ap::Input> submitted;
  std::vector<ap::ModelStep> replayed;

  ap::ModelResult submit(const ap::Input& input, std::optional<ap::Stamp> clock) override {
    submitted.push_back(input);
    return inner_.submit(input, clock);
  }
  ap::ModelResult replay(const ap::ModelStep& step) override {
    replayed.push_back(step);
    return inner_.replay(step);
  }
};

ap::EngineConfig replayConfig(bool estimate_bias) {
  ap::EngineConfig c = engine_fixtures::kinematicConfig();
  c.rate_stddev = 0.01;
  c.initial_orientation_stddev = 0.05;
  c.fixes.estimate_gyro_bias = estimate_bias;
  c.fixes.gyro_bias_stddev = 1e-3;
  return c;
}

// 100 Hz rates of a generic turn, a fix at the first sample (the history starts there) and one
// between samples 10 and 11 (0.105 s) handed in after sample 20.
TEST(Replay, ALateFixRepeatsTheStepsAfterItsEntryAsReceivedAndReportsNothing) {
  for (const bool estimate_bias : {false, true}) {
    SCOPED_TRACE(estimate_bias ? "bias estimated" : "attitude alone");
    SpyModel* spy = nullptr;
    Recorder sink;
    ap::AttitudeEngine engine(replayConfig(estimate_bias), sink, wrapped_model::factoryOf(spy));
    ASSERT_NE(spy, nullptr);
    auto w = [](int k) { return Eigen::Vector3d(0.3, -0.2 + 0.01 * k, 0.5); };
    for (int k = 0; k <= 20; ++k) {
      engine.submit(rate(at(0.01 * k), w(k)));
      if (k == 0) {
        ASSERT_EQ(
            engine.submitFix(at(0.0), Eigen::Quaterniond::Identity(), Eigen::Matrix3d::Zero()),
            ap::FixOutcome::Accepted);
      }
    }
    spy->replayed.clear();
    const std::size_t states = sink.states.size();
    const std::size_t applied = sink.applied.size();
    const std::size_t notes = sink.notes.size();
    const std::size_t submitted = spy->submitted.size();
    const ap::EngineCounters before = engine.counters();
    const Eigen::Vector3d bias_before = engine.gyroBiasEstimate();
    ASSERT_NE(sink.stateAt(at(0.1)), nullptr);
    const Eigen::Quaterniond q_fix =
        sink.stateAt(at(0.1))->q_WB * engine_fixtures::aboutAxis(Eigen::Vector3d(1, -2, 3), 0.01);

    ASSERT_EQ(engine.submitFix(at(0.105), q_fix, engine_fixtures::correlatedFixCovariance()),
              ap::FixOutcome::Accepted);

    // The step to sample 11 once for the geodesic's other end, then samples 11..20 in order.
    ASSERT_EQ(spy->replayed.size(), 11u);
    for (std::size_t i = 0; i < spy->replayed.size(); ++i) {
      const int k = i == 0 ? 11 : 10 + static_cast<int>(i);
      const ap::ModelStep& step = spy->replayed[i];
      EXPECT_FALSE(step.advance) << i;
      EXPECT_EQ(step.input.stamp, at(0.01 * k)) << i;
      // As received, or less the estimate: the fix moved it, so the replay uses the new one.
      const Eigen::Vector3d expected = estimate_bias ? w(k) - engine.gyroBiasEstimate() : w(k);
      if (i > 0) {
        EXPECT_LE((step.input.value - expected).norm(), 1e-15) << i;
      }
    }
    if (estimate_bias) {
      EXPECT_GT((engine.gyroBiasEstimate() - bias_before).norm(), 0.0);
    }
    EXPECT_EQ(spy->submitted.size(), submitted);
    EXPECT_EQ(sink.states.size(), states);  // the corrected state goes out with the next output
    EXPECT_EQ(sink.applied.size(), applied);
    EXPECT_EQ(sink.notes.size(), notes);
    const ap::EngineCounters& after = engine.counters();
    EXPECT_EQ(after.accepted, before.accepted);
    EXPECT_EQ(after.gaps, before.gaps);
    EXPECT_EQ(after.fixes_accepted, before.fixes_accepted + 1);
  }
}

}  // namespace
