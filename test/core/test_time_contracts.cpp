// Time rules of the core at their boundaries, each against a truth the code does not compute:
// the stamp filter's warm-up (docs/numerics.md §3: outliers rejected only after 10 draws, a FIFO
// read one draw, counted again from every start), the interval history at an anchor when the
// rate changes there (average_stamp.h; design.md §6.2: the new period is known three intervals
// on), a late torque's timeout (design.md §4.4, §6.7) and the inputs a grid state sees
// (design.md §5.3: exactly those stamped up to it).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <optional>
#include <vector>

#include "attitude_propagator/engine.h"
#include "attitude_propagator/models/dynamic_propagator.h"
#include "attitude_propagator/models/kinematic_propagator.h"
#include "attitude_propagator/numerics/quaternion.h"
#include "attitude_propagator/time/average_stamp.h"
#include "attitude_propagator/time/stamp_filter.h"
#include "attitude_propagator/time/time_policy.h"
#include "engine_fixtures.h"
#include "rotation_matchers.h"
#include "sampling.h"

namespace ap = attitude_propagator;
using namespace engine_fixtures;  // NOLINT: the fixtures are the tests' vocabulary
using Verdict = ap::SensorClockFilter::Verdict;

// ---------------------------------------------------------------------------------------------
// The stamp filter's warm-up
// ---------------------------------------------------------------------------------------------

namespace {

constexpr double kFilterStart = 3.7;      // s
constexpr double kFilterPeriod = 0.0043;  // s: 233 Hz
// Receipt jitter of 1 us: stamps exactly a period apart would be one FIFO read, a single draw
// (docs/numerics.md §3), so a clock whose stamps are drawn one by one has some.
constexpr double kJitter = 1e-6;  // s
// A stamp this late is an outlier far beyond 6 sigma of that jitter, and still rounds to the next
// index (no lost period); accepted during the warm-up it leaves a jitter well under the quarter
// period of a misfit.
constexpr double kLate = 0.2 * kFilterPeriod;

/// The receipt stamp of sample n of a jittered clock (the same draws for every run).
double jitteredStamp(double t0, int n) {
  std::uint64_t state = 1000 + static_cast<std::uint64_t>(n);
  return t0 + kFilterPeriod * n + kJitter * normalRandom(state);
}

/// The verdict on an outlier that is the `k`-th stamp since the filter's start (the start's own
/// stamp the first), on an otherwise jittered clock.
Verdict verdictOnTheKthStamp(const ap::SensorClockFilter::Options& options, int k) {
  ap::SensorClockFilter filter(options);
  for (int n = 0; n + 1 < k; ++n) filter.filter(jitteredStamp(kFilterStart, n));
  const Verdict verdict = filter.filter(jitteredStamp(kFilterStart, k - 1) + kLate).verdict;
  EXPECT_EQ(filter.rejected(), verdict == Verdict::Rejected ? 1u : 0u) << k;
  // A rejection keeps the model: the stamp after it is modelled on the same line.
  EXPECT_EQ(filter.filter(jitteredStamp(kFilterStart, k)).verdict, Verdict::Modelled) << k;
  EXPECT_EQ(filter.restarts(), 0u) << k;
  return verdict;
}

}  // namespace

// time_policy.h: a stamp at or before the newest one taken is stale, by any amount (one ulp
// before, equal, a year before); one ulp after is not. classifyStamp applies the same rule and,
// past it, tells a gap beyond max_dt (exactly max_dt is still a step forward).
TEST(TimePolicy, AStampAtOrBeforeTheNewestIsStaleByAnyAmount) {
  const double newest = 1500000000.25;
  for (double t : {std::nextafter(newest, 0.0), newest, newest - 3.15e7}) {
    EXPECT_TRUE(ap::isStale(newest, t)) << t - newest;
    EXPECT_EQ(ap::classifyStamp(newest, t, ap::TimePolicy{}), ap::StampClass::Stale);
  }
  const double after = std::nextafter(newest, 2.0 * newest);
  EXPECT_FALSE(ap::isStale(newest, after));
  ap::TimePolicy policy;
  policy.max_dt = 0.5;
  EXPECT_EQ(ap::classifyStamp(newest, after, policy), ap::StampClass::Forward);
  EXPECT_EQ(ap::classifyStamp(1.0, 1.5, policy), ap::StampClass::Forward);
  EXPECT_EQ(ap::classifyStamp(1.0, std::nextafter(1.5, 2.0), policy), ap::StampClass::Gap);
}

// docs/numerics.md §3: stamps are rejected only after a warm-up of warm_up draws (10 by
// default), a draw being a stamp received on its own. An outlier as the warm_up-th stamp joins
// the fit; as the next one it is rejected. Both the default and another count, so that the
// count is the option's and not a constant.
TEST(StampFilterWarmUp, RejectsAnOutlierFromTheStampAfterTheWarmUpOn) {
  for (const int warm_up : {10, 4}) {
    SCOPED_TRACE(warm_up);
    ap::SensorClockFilter::Options options;
    options.warm_up = warm_up;
    EXPECT_EQ(verdictOnTheKthStamp(options, warm_up - 1), Verdict::Modelled);
    EXPECT_EQ(verdictOnTheKthStamp(options, warm_up), Verdict::Modelled);
    EXPECT_EQ(verdictOnTheKthStamp(options, warm_up + 1), Verdict::Rejected);
  }
}

namespace {

/// The verdict on a FIFO read of four samples received kLate late, the `outlier`-th read since a
/// restart: reads at 233 Hz with 1 us of latency jitter each (one draw per read), in either
/// form, 2 s on, then from 2 s earlier (a looped bag: the first read after the jump restarts the
/// model). The spacing of the reads stays known across the restart (it is the driver's), so
/// every read after it is one draw from its first stamp on (at the stream's very first read the
/// spacing is recognised only once seen twice: its second stamp is a draw of its own). Four
/// samples a read, fewer than restart_after: the stamps of a rejected read a period apart are
/// each counted rejected (they share its verdict), and five of them in a row would restart the
/// model.
Verdict verdictOnTheKthRead(bool repeated, int outlier) {
  constexpr int kRead = 4;
  ap::SensorClockFilter filter;
  std::optional<Verdict> verdict;
  auto reads = [&](double t0, int count, bool after_restart) {
    for (int read = 1; read <= count; ++read) {
      const int newest = read * kRead - 1;  // the read's stamp belongs to its newest sample
      std::uint64_t state = 2000 + static_cast<std::uint64_t>(read);
      const double latency =
          kJitter * normalRandom(state) + (after_restart && read == outlier ? kLate : 0.0);
      for (int k = newest - kRead + 1; k <= newest; ++k) {
        const double receipt = t0 + kFilterPeriod * (repeated ? newest : k) + latency;
        const ap::SensorClockFilter::Result r = filter.filter(receipt);
        if (after_restart && read == 1 && k == 0) {
          EXPECT_EQ(r.verdict, Verdict::Restarted);
        }
        if (after_restart && read == outlier && k == newest - kRead + 1) verdict = r.verdict;
      }
    }
  };
  reads(kFilterStart + 2.0, 20, false);
  reads(kFilterStart, outlier + 2, true);
  EXPECT_EQ(filter.batchSize(), static_cast<std::uint64_t>(kRead));
  EXPECT_EQ(filter.restarts(), 1u);
  EXPECT_EQ(filter.rejected() > 0, verdict == Verdict::Rejected);
  return verdict.value_or(Verdict::Unfiltered);
}

}  // namespace

// The warm-up counts latency draws: a FIFO read is one draw, however many samples it brings,
// whether its stamps repeat the read's receipt time or step back a period each (docs/numerics.md
// §3, "the warm-up counts reads"). A read received late as the 9th or 10th read since the
// restart joins the fit (36 or 40 samples on, far past ten), as the 11th it is rejected.
TEST(StampFilterWarmUp, CountsFifoReadsNotSamples) {
  for (const bool repeated : {true, false}) {
    SCOPED_TRACE(repeated ? "repeated stamps" : "stamps a period apart");
    EXPECT_EQ(verdictOnTheKthRead(repeated, 9), Verdict::Modelled);
    EXPECT_EQ(verdictOnTheKthRead(repeated, 10), Verdict::Modelled);
    EXPECT_EQ(verdictOnTheKthRead(repeated, 11), Verdict::Rejected);
  }
}

// "after a (re)start": the stamps jump back 2 s (a looped bag), the model starts again from
// that stamp, and the warm-up is counted again from it: an outlier as the 9th or 10th stamp of
// the new start joins the fit, as the 11th it is rejected, though the filter was warm before.
TEST(StampFilterWarmUp, CountsAgainFromARestart) {
  for (const int k : {9, 10, 11}) {
    SCOPED_TRACE(k);
    ap::SensorClockFilter filter;
    for (int n = 0; n < 60; ++n) filter.filter(jitteredStamp(kFilterStart + 2.0, n));
    ASSERT_EQ(filter.filter(jitteredStamp(kFilterStart, 0)).verdict, Verdict::Restarted);
    for (int n = 1; n + 1 < k; ++n) {
      ASSERT_EQ(filter.filter(jitteredStamp(kFilterStart, n)).verdict, Verdict::Modelled) << n;
    }
    const Verdict verdict = filter.filter(jitteredStamp(kFilterStart, k - 1) + kLate).verdict;
    EXPECT_EQ(verdict, k <= 10 ? Verdict::Modelled : Verdict::Rejected);
    EXPECT_EQ(filter.restarts(), 1u);
  }
}

// ---------------------------------------------------------------------------------------------
// The interval history at an anchor, the rate changing there
// ---------------------------------------------------------------------------------------------

namespace {

const Eigen::Vector3d kRate(0.3, -0.2, 0.5);  // rad/s
constexpr double kFast = 0.005;               // s: 200 Hz before the anchor
constexpr double kSlow = 0.0123;              // s: 81 Hz after it, beyond 1.5 fast periods

/// Where `ends` puts the end of the interval of the sample waiting, given the next stamp.
double endOf(ap::IntervalEnds& ends, double next) {
  const std::optional<ap::RateSample> ended = ends.push({next, kRate}).ended;
  EXPECT_TRUE(ended) << next;
  return ended ? ended->t : -1.0;
}

}  // namespace

// average_stamp.h: clear() forgets the waiting sample and the periods. A start-stamped stream at
// 200 Hz, cleared, then at 81 Hz: each interval ends at the next stamp ("a sample's interval
// ends where the next one's begins"), never one old period on as after a loss. A stamp two slow
// periods on (a lost sample) is a loss only once three intervals at the new rate give a nominal
// period (fewer tell no loss from the period): after two it is taken whole, after three or four
// it is one nominal period long.
TEST(IntervalEndsHistory, ClearForgetsThePeriodsOfTheStreamBefore) {
  for (const int known : {2, 3, 4}) {
    SCOPED_TRACE(known);
    ap::IntervalEnds ends(ap::AverageStamp::Start);
    ends.push({1.0, kRate});
    for (int k = 1; k <= 8; ++k) endOf(ends, 1.0 + kFast * k);
    ends.clear();
    const double t0 = 1.07;
    EXPECT_FALSE(ends.push({t0, kRate}).ended);  // waits again, as the first sample does
    for (int k = 1; k <= known; ++k) {
      EXPECT_NEAR(endOf(ends, t0 + kSlow * k), t0 + kSlow * k, 1e-14) << k;
    }
    const double held = t0 + kSlow * known;
    const double after_loss = held + 2.0 * kSlow;
    EXPECT_NEAR(endOf(ends, after_loss), known < 3 ? after_loss : held + kSlow, 1e-14);
  }
}

namespace {

ap::EngineConfig startStampedConfig() {
  ap::EngineConfig config = kinematicConfig();
  config.kinematic.rate_samples = ap::RateSamples::IntervalAverage;
  config.kinematic.average_stamp = ap::AverageStamp::Start;
  return config;
}

}  // namespace

// set_state pins the state while the stream changes rate (200 Hz before, 81 Hz after): every
// mean after the pin is published at its interval's end, the next sample's stamp, with the
// constant rate's closed form from the pinned state, q_pin (x) Exp(w (t - t_pin)). (The mean
// waiting at the pin, stamped 1.05, is dropped with it.)
TEST(IntervalEndsHistory, SetStateAtANewRateEndsEachMeanAtTheNextStamp) {
  Recorder sink;
  ap::AttitudeEngine engine(startStampedConfig(), sink);
  for (int k = 0; k <= 10; ++k) engine.submit(rate(at(1.0 + kFast * k), kRate));
  const Eigen::Quaterniond q_pin = aboutAxis(Eigen::Vector3d(1.0, 2.0, -0.5), 0.7);
  const double pin = 1.0537;
  ASSERT_EQ(engine.setState(at(pin), q_pin, kRate), "");
  const std::size_t pinned = sink.states.size();
  std::vector<double> starts;
  for (int k = 0; k <= 6; ++k) starts.push_back(1.06 + kSlow * k);
  for (double s : starts) engine.submit(rate(at(s), kRate));
  ASSERT_EQ(sink.states.size(), pinned + starts.size() - 1);
  for (std::size_t k = 1; k < starts.size(); ++k) {
    const ap::EngineState& s = sink.states[pinned + k - 1];
    EXPECT_EQ(s.stamp, at(starts[k])) << k;
    EXPECT_ROTATION_NEAR(s.q_WB, q_pin * ap::expMap(kRate * (starts[k] - pin)), 1e-14);
  }
  EXPECT_EQ(engine.counters().gaps, 0u);
}

// The stamps jump back 5 s (a looped bag) and the stream comes back at 81 Hz instead of 200 Hz:
// the third stamp of the run confirms the jump (design.md §6.5), the propagator starts again
// from the initial state, and each mean of the new timeline is published at the next sample's
// stamp, the first of them the anchor.
TEST(IntervalEndsHistory, AJumpBackAtANewRateEndsEachMeanAtTheNextStamp) {
  Recorder sink;
  ap::AttitudeEngine engine(startStampedConfig(), sink);
  for (int k = 0; k <= 20; ++k) engine.submit(rate(at(10.0 + kFast * k), kRate));
  const std::size_t before = sink.states.size();
  std::vector<double> starts;
  for (int k = 0; k <= 6; ++k) starts.push_back(5.0 + kSlow * k);
  for (double s : starts) engine.submit(rate(at(s), kRate));
  EXPECT_EQ(engine.counters().jumps_back, 1u);
  EXPECT_EQ(engine.counters().resets, 1u);
  ASSERT_EQ(sink.states.size(), before + starts.size() - 1);
  for (std::size_t k = 1; k < starts.size(); ++k) {
    const ap::EngineState& s = sink.states[before + k - 1];
    EXPECT_EQ(s.stamp, at(starts[k])) << k;
    EXPECT_ROTATION_NEAR(s.q_WB, ap::expMap(kRate * (starts[k] - starts[1])), 1e-14);
  }
}

// A gap anchors while the rate halves (a sensor back at 102 Hz after more than a second of
// silence at 204 Hz). numerics.md §3: a loss is filled only when the last intervals since the
// anchor prove it, and design.md §6.2: the new period is known three intervals on. So no interval
// at the new rate, a whole two old periods, is taken for a loss; a sample lost after two
// intervals is not filled (integrated across), after three or four it is (one sample filled).
TEST(KinematicAnchorHistory, ALossAtANewRateIsFilledOnlyOnceThreeIntervalsSinceTheGapProveIt) {
  constexpr double kOld = 0.0049, kNew = 2.0 * kOld;
  for (const int known : {2, 3, 4}) {
    SCOPED_TRACE(known);
    ap::KinematicConfig config;
    config.rate_samples = ap::RateSamples::IntervalAverage;
    ap::KinematicPropagator p(config);
    double t = 2.0;
    for (int k = 0; k <= 30; ++k, t += kOld) p.addSample(t, kRate);
    t += 1.2;  // beyond max_dt = 1 s
    ASSERT_EQ(p.addSample(t, kRate), ap::StampOutcome::HeldGap);
    for (int k = 1; k <= known; ++k) {
      ASSERT_EQ(p.addSample(t + kNew * k, kRate), ap::StampOutcome::Advanced) << k;
      EXPECT_EQ(p.filledSamples(), 0u) << k;
    }
    EXPECT_EQ(p.addSample(t + kNew * (known + 2), kRate), ap::StampOutcome::Advanced);
    EXPECT_EQ(p.filledSamples(), known < 3 ? 0u : 1u);
  }
}

// ---------------------------------------------------------------------------------------------
// A late torque's timeout
// ---------------------------------------------------------------------------------------------

namespace {

// A sphere: I dw/dt = (I w) x w + T = T, so w grows by T / I over the time the torque is in
// force, whatever w and T (rk4 integrates a constant derivative exactly).
constexpr double kInertia = 2.0;
constexpr double kTimeout = 0.137;  // s
const Eigen::Vector3d kW0(0.3, -0.1, 0.2);
const Eigen::Vector3d kTorque(0.4, 0.25, -0.3);

ap::DynamicConfig timedTorqueSphere() {
  ap::DynamicConfig config;
  config.body = ap::RigidBody::fromPrincipalMoments(Eigen::Vector3d::Constant(kInertia));
  config.integrator = ap::Integrator::Rk4;
  config.torque_input = true;
  config.max_step = 0.1;  // grid points at 0.1, 0.2, ... from the anchor at 0
  config.torque_timeout = kTimeout;
  config.initial.w_B = kW0;
  return config;
}

}  // namespace

// design.md §4.4: a torque stamped s is in force on [s, s + torque_timeout); §6.7: a late one
// acts from its stamp if no grid point was committed since, else from the last grid point, and
// its timeout runs from where it took effect (dynamic_propagator.cpp), never from where the
// clock was when it arrived. The truth: w = w0 + T / I min(t - effect, timeout), checked just
// before the expiry, at it, just after it, and long after.
TEST(DynamicLateTorque, TimesOutATimeoutAfterWhereItTookEffect) {
  struct Case {
    const char* name;
    double clock;  // time() when the torque arrives
    double stamp;
    double effect;
  };
  for (const Case& c :
       {Case{"in time", 0.2, 0.23, 0.23}, Case{"late within the grid step", 0.25, 0.23, 0.23},
        Case{"late behind a grid point", 0.25, 0.15, 0.2}}) {
    SCOPED_TRACE(c.name);
    ap::DynamicPropagator p(timedTorqueSphere());
    ASSERT_EQ(p.advanceTo(0.0), ap::StampOutcome::Anchored);
    ASSERT_EQ(p.advanceTo(c.clock), ap::StampOutcome::Advanced);
    ASSERT_EQ(p.setTorque(c.stamp, kTorque, ap::TorqueFrame::Body), ap::StampOutcome::Advanced);
    const double expiry = c.effect + kTimeout;
    for (const double t : {expiry - 0.01, expiry, expiry + 0.01, 1.0}) {
      ASSERT_EQ(p.advanceTo(t), ap::StampOutcome::Advanced) << t;
      const double in_force = std::min(t - c.effect, kTimeout);
      EXPECT_LE((p.state().w_B - (kW0 + kTorque / kInertia * in_force)).norm(), 1e-14) << t;
    }
  }
}

// ---------------------------------------------------------------------------------------------
// The inputs a grid state sees
// ---------------------------------------------------------------------------------------------

namespace {

const Eigen::Vector3d kGridW0(0.2, -0.1, 0.15);  // rad/s, the sphere's rate before the input
const Eigen::Vector3d kGridW1(0.3, -0.7, 0.5);   // the rate sample's

/// A torque-free sphere, exact: q(t) = Exp(w0 t) while w0 holds (body rates compose on the
/// right), 50 Hz grid.
ap::EngineConfig gridSphereConfig() {
  ap::EngineConfig config = spinningSphereConfig();
  config.dynamic->initial.w_B = kGridW0;
  return config;
}

/// The sphere's orientation at t with the rate sample stamped s: Exp(w0 min(t, s)) (x)
/// Exp(w1 max(t - s, 0)).
Eigen::Quaterniond sphereAt(double t, double s) {
  return ap::expMap(kGridW0 * std::min(t, s)) * ap::expMap(kGridW1 * std::max(t - s, 0.0));
}

}  // namespace

class GridStampInputs : public ::testing::TestWithParam<int> {};

// design.md §5.3: "the state at a grid stamp includes exactly the inputs stamped up to it".
// A rate sample stamped a nanosecond before the grid stamp 0.2 s, at it, or a nanosecond after
// it, submitted while the clock is at 0 (it waits), the clock then ticking off the grid (every
// 7 ms: the grid stamp 0.2 is published at the tick 0.203). The state at 0.2 carries the new rate
// when the sample is stamped at or before it, the old one otherwise; the orientations at 0.2
// and 0.24 are the closed form's with the rate switched at the sample's own stamp. Nothing is
// late, and every grid stamp is published once.
TEST_P(GridStampInputs, TheStateAtAGridStampSeesExactlyTheInputsStampedUpToIt) {
  const int offset_ns = GetParam();
  const ap::Stamp grid = at(0.2);
  const ap::Stamp stamp = grid + offset_ns;
  const double s = 0.2 + offset_ns * 1e-9;
  Recorder sink;
  ap::AttitudeEngine engine(gridSphereConfig(), sink);
  engine.clockTick(at(0.0));  // anchors at the grid stamp 0
  engine.submit(rate(stamp, kGridW1));
  EXPECT_EQ(engine.pending(), 1u);
  EXPECT_TRUE(sink.applied.empty());
  runClock(engine, 0.0, 0.196, 0.007);  // the tick before the one that passes 0.2
  EXPECT_EQ(engine.pending(), 1u);
  runClock(engine, 0.196, 0.252, 0.007);
  EXPECT_EQ(engine.pending(), 0u);
  ASSERT_EQ(sink.applied.size(), 1u);
  EXPECT_EQ(sink.applied_states[0].stamp, stamp);

  const ap::EngineState* at_grid = sink.stateAt(grid);
  ASSERT_NE(at_grid, nullptr);
  EXPECT_LE((at_grid->w_B - (offset_ns <= 0 ? kGridW1 : kGridW0)).norm(), 1e-15);
  EXPECT_ROTATION_NEAR(at_grid->q_WB, sphereAt(0.2, s), 1e-14);
  const ap::EngineState* next = sink.stateAt(at(0.24));
  ASSERT_NE(next, nullptr);
  EXPECT_LE((next->w_B - kGridW1).norm(), 1e-15);
  EXPECT_ROTATION_NEAR(next->q_WB, sphereAt(0.24, s), 1e-14);

  EXPECT_EQ(engine.counters().late, 0u);
  EXPECT_TRUE(sink.stampsIncrease());
  ASSERT_EQ(sink.states.size(), 13u);  // 0, 0.02, ..., 0.24
  for (std::size_t k = 0; k < sink.states.size(); ++k) {
    EXPECT_EQ(sink.states[k].stamp, at(0.02 * static_cast<double>(k))) << k;
  }
}

INSTANTIATE_TEST_SUITE_P(NanosecondsFromTheGridStamp, GridStampInputs, ::testing::Values(-1, 0, 1));
