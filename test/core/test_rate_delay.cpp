// rate_delay: a rate older than its stamp (an on-chip filter's group delay, a fixed latency).
// Truths: the coning motion's closed form, and the group delay of a digital filter computed from
// its coefficients (tau = sum k b_k / sum b_k - sum k a_k / sum a_k samples at DC).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "attitude_propagator/engine.h"
#include "attitude_propagator/numerics/coning_motion.h"
#include "engine_fixtures.h"
#include "gyro_streams.h"
#include "rotation_matchers.h"

namespace ap = attitude_propagator;
using namespace engine_fixtures;  // NOLINT: the fixtures are the tests' vocabulary
using gyro_streams::Butterworth2;

namespace {

constexpr double kRate = 200.0;  // Hz, the gyro's output data rate
constexpr double kSeconds = 10.0;

/// The largest angle between a published state and the closed form at its stamp.
double worstError(const Recorder& sink, const ap::ConingMotion& cone) {
  double worst = 0.0;
  for (const ap::EngineState& s : sink.states) {
    const double t = static_cast<double>(s.stamp - at(0.0)) * 1e-9;
    worst = std::max(worst, ap::rotationAngle(s.q_WB, cone.attitude(t)));
  }
  return worst;
}

/// Runs the kinematic engine (cf4) over rates[k] stamped k / kRate, with `rate_delay`.
double runError(const std::vector<Eigen::Vector3d>& rates, double rate_delay, double start_time) {
  const ap::ConingMotion cone;
  ap::EngineConfig config = kinematicConfig();
  config.kinematic.integrator = ap::Integrator::Cf4;
  config.kinematic.initial_q_WB = cone.attitude(start_time);
  config.rate_delay = rate_delay;
  Recorder sink;
  ap::AttitudeEngine engine(config, sink);
  for (std::size_t k = 0; k < rates.size(); ++k) {
    engine.submit(rate(at(static_cast<double>(k) / kRate), rates[k]));
  }
  EXPECT_EQ(engine.counters().accepted, rates.size());
  return worstError(sink, cone);
}

}  // namespace

TEST(RateDelay, APureDelayIsUndoneExactly) {
  // The gyro reports the rate at t - d stamped t (d = 0.9 periods): with rate_delay = d the
  // engine sees the true stream, stamped d earlier.
  const ap::ConingMotion cone;
  const double d = 0.9 / kRate;
  std::vector<Eigen::Vector3d> on_time, delayed;
  for (int k = 0; k <= kSeconds * kRate; ++k) {
    on_time.push_back(cone.bodyRate(k / kRate));
    delayed.push_back(cone.bodyRate(k / kRate - d));
  }
  // cf4's own error on the true stream (the same samples, stamped where they belong).
  const double own = runError(on_time, 0.0, 0.0);
  const double compensated = runError(delayed, d, -d);
  const double ignored = runError(delayed, 0.0, 0.0);
  EXPECT_LT(compensated, 1.1 * own);  // measured: equal, 3.4e-7 rad over 10 s
  // Ignored, the delay is an error of about |w| d, orders above the method's own (6.2e-3 rad).
  EXPECT_GT(ignored, 1e3 * own);
}

TEST(RateDelay, AButterworthFilteredGyroAtItsGroupDelayIsAccurate) {
  // A 2nd-order Butterworth at ODR/4 inside the gyro (a common on-chip setting). Its group
  // delay at DC, digital by the bilinear transform: sqrt2 / (2 K) samples, K = tan(pi fc/fs),
  // 0.71 samples here (the analog prototype's sqrt2 / (2 pi fc / fs) would say 0.90).
  const Butterworth2 lowpass(0.25);
  EXPECT_NEAR(lowpass.dcDelay(), M_SQRT2 / (2.0 * std::tan(M_PI * 0.25)), 1e-12);
  const ap::ConingMotion cone;
  std::vector<Eigen::Vector3d> truth;
  const int preroll = 400;  // two seconds before the first stamp: no start-up transient
  for (int k = -preroll; k <= kSeconds * kRate; ++k) truth.push_back(cone.bodyRate(k / kRate));
  std::vector<Eigen::Vector3d> filtered = lowpass.filter(truth);
  filtered.erase(filtered.begin(), filtered.begin() + preroll);
  const double d = lowpass.dcDelay() / kRate;
  const double compensated = runError(filtered, d, -d);
  const double ignored = runError(filtered, 0.0, 0.0);
  EXPECT_LT(compensated, 1e-5);  // measured 9.7e-7 rad over 10 s
  EXPECT_GT(ignored, 1e-3);      // measured 4.9e-3 rad
}

TEST(RateDelay, ASincCubedDecimatorAtItsGroupDelayIsAccurate) {
  // A sinc^3 decimator by R = 8 from 1600 Hz to the 200 Hz ODR: its taps (the three-fold
  // convolution of 8 equal weights) are symmetric, so its group delay is N (R - 1) / 2 = 10.5
  // input samples at every frequency, 6.6 ms.
  const gyro_streams::SincDecimator sinc(3, 8);
  EXPECT_EQ(sinc.taps.size(), 22u);
  EXPECT_NEAR(sinc.delay(), 3.0 * 7.0 / 2.0, 1e-12);
  const ap::ConingMotion cone;
  auto rate = [&cone](double t) { return cone.bodyRate(t); };
  std::vector<Eigen::Vector3d> decimated;
  for (int k = 0; k <= kSeconds * kRate; ++k) {
    decimated.push_back(sinc.output(rate, k / kRate, sinc.ratio * kRate));
  }
  const double d = sinc.delay() / (sinc.ratio * kRate);
  const double compensated = runError(decimated, d, -d);
  const double ignored = runError(decimated, 0.0, 0.0);
  std::printf("[ sinc3    ] rate_delay %.3g s: %.3g rad, none: %.3g rad\n", d, compensated,
              ignored);
  // What remains is the decimator's smoothing (1.5e-4 of the rate at the coning's 1.1 Hz).
  EXPECT_LT(compensated, 2e-4);            // measured 1.0e-4 rad over 10 s
  EXPECT_GT(ignored, 20.0 * compensated);  // measured 9.1e-3 rad
}

TEST(RateDelay, ABiasStampedAtAMessagesStampAppliesToIt) {
  // The bias and the rate message carry stamps of the same clock: the delay moves the instant
  // the rate describes, not which bias was in force when it was stamped.
  ap::EngineConfig config = kinematicConfig();
  config.rate_delay = 0.05;
  Recorder sink;
  ap::AttitudeEngine engine(config, sink);
  const Eigen::Vector3d w(0.0, 0.0, 0.3), bias(0.0, 0.0, 0.1);
  engine.submit(rate(at(1.0), w));
  ASSERT_TRUE(engine.submitBias(at(1.01), bias));
  engine.submit(rate(at(1.01), w));  // moved to 0.96, stamped 1.01: the bias applies
  ASSERT_EQ(sink.states.size(), 2u);
  EXPECT_EQ(sink.states[1].stamp, at(0.96));
  EXPECT_NEAR(sink.states[1].w_B.z(), 0.2, 1e-15);
}

TEST(RateDelay, TorquesAreNotMovedAndTheDelayIsBoundedByMaxDt) {
  Recorder sink;
  ap::EngineConfig config = torqueConfig();
  config.rate_delay = 0.25;
  ap::AttitudeEngine engine(config, sink);
  engine.poll(at(0.0));
  engine.submit(torque(at(0.5), Eigen::Vector3d::UnitX()));
  engine.submit(rate(at(0.5), Eigen::Vector3d::UnitX()));
  ASSERT_EQ(engine.pending(), 2u);
  engine.poll(at(0.3));  // the rate (at 0.25 once moved) is due, the torque is not
  EXPECT_EQ(engine.pending(), 1u);
  ASSERT_EQ(sink.applied.size(), 1u);
  EXPECT_EQ(sink.applied[0].source, ap::Source::Imu);
  EXPECT_EQ(sink.applied[0].stamp, at(0.25));

  for (double bad : {-1e-9, 1.0 + 1e-9, double(NAN)}) {  // max_dt = 1 s
    ap::EngineConfig c = kinematicConfig();
    c.rate_delay = bad;
    EXPECT_THROW(ap::AttitudeEngine(c, sink), std::invalid_argument) << bad;
  }
  ap::EngineConfig at_max = kinematicConfig();
  at_max.rate_delay = 1.0;
  EXPECT_NO_THROW(ap::AttitudeEngine(at_max, sink));
}
