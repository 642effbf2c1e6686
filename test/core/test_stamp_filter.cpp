// SensorClockFilter against a simulated sensor clock: sample n taken at t0 + P n, received
// with jitter, lost, delayed, at a new rate, after a restart. The truth is the simulated clock.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <vector>

#include "attitude_propagator/engine.h"
#include "attitude_propagator/models/kinematic_propagator.h"
#include "attitude_propagator/numerics/coning_motion.h"
#include "attitude_propagator/numerics/quaternion.h"
#include "attitude_propagator/time/stamp_filter.h"
#include "rotation_matchers.h"
#include "sampling.h"

namespace ap = attitude_propagator;
using Verdict = ap::SensorClockFilter::Verdict;

namespace {

constexpr double kT0 = 1.7e9;  // epoch-sized stamps
constexpr double kPeriod = 0.005;

}  // namespace

TEST(StampFilterNames, RoundTripAndListTheAcceptedValues) {
  for (const char* name : {"none", "sensor_clock"}) {
    EXPECT_EQ(ap::stampFilterName(ap::stampFilterFromName(name)), name);
  }
  try {
    ap::stampFilterFromName("kalman");
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("none sensor_clock"), std::string::npos);
  }
}

// A clean clock passes through unchanged, to the resolution of epoch-sized doubles.
TEST(SensorClockFilter, LeavesACleanClockAlone) {
  ap::SensorClockFilter filter;
  const double ulp = std::nextafter(kT0, 2 * kT0) - kT0;  // 2.4e-7 s
  for (int n = 0; n < 5000; ++n) {
    const auto r = filter.filter(kT0 + kPeriod * n);
    EXPECT_NEAR(r.t, kT0 + kPeriod * n, 4 * ulp) << n;
  }
  EXPECT_NEAR(filter.period(), kPeriod, 1e-9);
  EXPECT_EQ(filter.rejected(), 0u);
  EXPECT_EQ(filter.missed(), 0u);
}

// Receipt stamps 0.5 ms (a transport delay) plus an exponential latency of 0.1 ms (mean and
// jitter) after the sample at 200 Hz: once settled the filtered stamps are within a fifth of the
// jitter of the sensor clock delayed by the constant part, which no stamp tells (the line rests
// on the stamps' lower envelope, the least latency).
TEST(SensorClockFilter, AveragesOutReceiptJitter) {
  ap::SensorClockFilter filter;
  std::uint64_t state = 3;
  const double sigma = 1e-4, delay = 5e-4;
  double sum2 = 0.0;
  int count = 0;
  for (int n = 0; n < 8000; ++n) {
    const double t = 100.0 + kPeriod * n;
    const auto r = filter.filter(t + delay + latencyRandom(state, sigma));
    if (n < 1000) continue;
    sum2 += (r.t - t - delay) * (r.t - t - delay);
    ++count;
  }
  EXPECT_LE(std::sqrt(sum2 / count), sigma / 5.0);
  EXPECT_NEAR(filter.jitter(), sigma, 0.1 * sigma);
  EXPECT_NEAR(filter.period(), kPeriod, 1e-8);
}

// Lost samples are counted as missed periods and the stamps after them stay on the clock.
TEST(SensorClockFilter, CountsLostSamples) {
  ap::SensorClockFilter filter;
  std::uint64_t lost = 0;
  for (int n = 0; n < 2000; ++n) {
    if (n > 20 && n % 37 == 0) {
      ++lost;
      continue;
    }
    if (n > 50 && n % 101 == 0) {  // two in a row
      lost += 2;
      n += 1;
      continue;
    }
    const auto r = filter.filter(10.0 + kPeriod * n);
    EXPECT_NEAR(r.t, 10.0 + kPeriod * n, 1e-9) << n;
  }
  EXPECT_EQ(filter.missed(), lost);
}

// A stamp delayed by 40 % of a period (a late packet) is rejected, counted, and replaced by
// the clock's stamp for the next index.
TEST(SensorClockFilter, RejectsOutliers) {
  ap::SensorClockFilter filter;
  std::uint64_t state = 5;
  for (int n = 0; n < 500; ++n) {
    const double t = 10.0 + kPeriod * n;
    const double delay = n % 50 == 25 ? 0.4 * kPeriod : 0.0;
    const auto r = filter.filter(t + delay + latencyRandom(state, 1e-6));
    EXPECT_NEAR(r.t, t, 1e-5) << n;
    if (delay > 0.0) {
      EXPECT_EQ(r.verdict, Verdict::Rejected);
    }
  }
  EXPECT_EQ(filter.rejected(), 10u);
}

// The sensor switches from 200 Hz to 400 Hz, then to 100 Hz: the filter restarts and follows.
TEST(SensorClockFilter, FollowsAChangedRate) {
  ap::SensorClockFilter filter;
  double t = 10.0;
  for (double period : {0.005, 0.0025, 0.01}) {
    for (int n = 0; n < 300; ++n, t += period) filter.filter(t);
    EXPECT_NEAR(filter.period(), period, 1e-9);
    EXPECT_NEAR(filter.filter(t).t, t, 1e-9);
    t += period;
  }
  EXPECT_GE(filter.restarts(), 2u);
}

// The rate goes up fivefold on hardware stamps (200 -> 1000 Hz): the stamps of the change are
// early for the old line and rejected until the restart. Every sample is integrated (none
// stale) and the attitude is the unfiltered one's within 2x (measured: both 1.48e-8 rad).
TEST(SensorClockFilter, ARateChangeDropsNoSampleAndLeavesNoStep) {
  const ap::ConingMotion cone;
  ap::KinematicConfig config;
  config.initial_q_WB = cone.attitude(0.0);
  ap::KinematicPropagator plain(config);
  config.stamp_filter = ap::StampFilter::SensorClock;
  ap::KinematicPropagator filtered(config);
  std::vector<double> stamps;
  for (int k = 0; k < 1000; ++k) stamps.push_back(k * 0.005);
  for (int k = 0; k <= 5000; ++k) stamps.push_back(5.0 + k * 0.001);
  plain.addSample(0.0, cone.bodyRate(0.0));
  filtered.addSample(0.0, cone.bodyRate(0.0));  // the anchor
  for (std::size_t k = 1; k < stamps.size(); ++k) {
    const double t = stamps[k];
    plain.addSample(t, cone.bodyRate(t));
    ASSERT_EQ(filtered.addSample(t, cone.bodyRate(t)), ap::StampOutcome::Advanced) << t;
  }
  EXPECT_GE(filtered.stampFilter()->restarts(), 1u);
  const double unfiltered = ap::rotationAngle(plain.orientation(), cone.attitude(plain.time()));
  const double with_filter =
      ap::rotationAngle(filtered.orientation(), cone.attitude(filtered.time()));
  EXPECT_LT(with_filter, 2.0 * unfiltered);
  EXPECT_NEAR(filtered.time(), stamps.back(), 1e-9);
}

// The restart after a new rate never returns a stamp before one already returned, even when the
// receipt stamp that triggers it came early (jitter): the run of five early stamps here ends
// 0.1 ms before the fourth.
TEST(SensorClockFilter, ARestartAfterANewRateNeverGoesBack) {
  ap::SensorClockFilter filter;
  for (int n = 0; n < 200; ++n) filter.filter(10.0 + kPeriod * n);
  const double last = 10.0 + kPeriod * 199;
  double previous = last;
  for (double ms : {1.0, 2.0, 3.0, 4.0, 3.9}) {
    const auto r = filter.filter(last + 1e-3 * ms);
    EXPECT_GT(r.t, previous) << ms;
    previous = r.t;
  }
  EXPECT_EQ(filter.restarts(), 1u);
}

// A stamp that jumps (a restarted driver, a looped bag) restarts the model at once and is
// returned as it is, so the propagator's own time policy sees the jump.
TEST(SensorClockFilter, RestartsOnAJump) {
  ap::SensorClockFilter filter;
  for (int n = 0; n < 100; ++n) filter.filter(50.0 + kPeriod * n);
  const auto r = filter.filter(20.0);
  EXPECT_EQ(r.verdict, Verdict::Restarted);
  EXPECT_EQ(r.t, 20.0);
  EXPECT_EQ(filter.restarts(), 1u);
  for (int n = 1; n < 100; ++n)
    EXPECT_NEAR(filter.filter(20.0 + kPeriod * n).t, 20.0 + kPeriod * n, 1e-9);
}

// Stamps returned always increase until a restart, whatever the receipt order.
TEST(SensorClockFilter, ReturnsIncreasingStamps) {
  ap::SensorClockFilter filter;
  std::uint64_t state = 11;
  double last = -1.0;
  for (int n = 0; n < 4000; ++n) {
    const auto r = filter.filter(kPeriod * n + 0.4 * kPeriod * normalRandom(state));
    if (r.verdict != Verdict::Restarted) {
      EXPECT_GT(r.t, last) << n;
    }
    last = r.t;
  }
}

// RestampCorrection against its definition, summed directly: on a clock whose line is exact
// from the start, samples integrated at stamps e_n off the line are owed the world-frame turn
// sum_n e_n R_WB(t_n) (w_{n+1} - w_n), the anchor's own stamp excepted. The forgetting hands
// weight from the live terms to frozen ones at the same line, so the total does not depend
// on the memory. The sums hold stamp offsets up to the run's length T times the terms: each
// of the n steps may round at eps T sum|g|.
TEST(RestampCorrection, SumsTheFirstOrderTurnOfMovedStamps) {
  for (double memory : {50.0, 1e12}) {
    ap::SensorClockFilter clock;
    ap::RestampCorrection correction(memory);
    std::uint64_t state = 17;
    Eigen::Vector3d total = Eigen::Vector3d::Zero(), expected = Eigen::Vector3d::Zero();
    double e_prev = 0.0, sum_g = 0.0;
    Eigen::Vector3d w_prev = Eigen::Vector3d::Zero();
    Eigen::Matrix3d R_prev = Eigen::Matrix3d::Identity();
    for (int n = 0; n < 400; ++n) {
      const ap::SensorClockFilter::Result line = clock.filter(10.0 + kPeriod * n);
      const double e = n == 0 ? 0.0 : 1e-4 * normalRandom(state);
      const Eigen::Vector3d w(std::sin(0.1 * n), 2.0 * std::cos(0.07 * n), 0.5);
      const Eigen::Quaterniond q = randomUnitQuaternion(state);
      total += correction.add(clock, {line.t + e, line.verdict, 0}, w, q, n == 0);
      if (n > 1) expected += e_prev * R_prev * (w - w_prev);
      sum_g += (w - w_prev).norm();
      e_prev = e;
      w_prev = w;
      R_prev = q.toRotationMatrix();
    }
    const double eps = std::numeric_limits<double>::epsilon(), T = 400 * kPeriod;
    EXPECT_LT((total - expected).norm(), 400 * eps * T * sum_g) << memory;
    EXPECT_GT(expected.norm(), 1e-5);  // the terms do not cancel to nothing
  }
}

// On exact stamps the filter's line is the stamps, nothing is moved, and the propagator
// follows the same path with the filter on as with it off.
TEST(SensorClockFilter, ChangesNothingOnAnExactClock) {
  const ap::ConingMotion cone;
  ap::KinematicConfig config;
  config.initial_q_WB = cone.attitude(0.0);
  ap::KinematicPropagator plain(config);
  config.stamp_filter = ap::StampFilter::SensorClock;
  ap::KinematicPropagator filtered(config);
  for (int k = 0; k <= 2000; ++k) {
    plain.addSample(k * kPeriod, cone.bodyRate(k * kPeriod));
    filtered.addSample(k * kPeriod, cone.bodyRate(k * kPeriod));
    ASSERT_LT(ap::rotationAngle(plain.orientation(), filtered.orientation()), 1e-12) << k;
  }
}

// In the propagator: coning at 200 Hz received after exponential latencies of 0.1 ms (mean and
// jitter sigma; latencyRandom), the truth compared at the stamp each state is reported at. Every
// sample's stamp error e moves the orientation by -e R (dw/dt) h, so unfiltered the error walks
// like sigma |dw/dt| sqrt(h t) about the phase of the mean latency. The filter's
// stamps, and its later stamps for the samples already integrated (RestampCorrection), leave
// only the error of its line, about 2 sigma / sqrt(n) after n samples: once the line has
// seen its memory (1000 samples, 5 s), the target of ten times less error is met. Before,
// no causal filter knows the clock much better than the first samples tell it.
// The kinematics are left-invariant: the run started from q0 is q0 times the run started from
// the identity. The filter's correction for moved stamps (RestampCorrection) turns the world side
// of the state, so the filtered run keeps that to round-off: measured 7.9e-15 rad over 2 s of a
// varying rate with 2e-4 s of jitter; bound 5e-14 (the turn on the body side: 3.7e-6 rad).
TEST(SensorClockFilter, KeepsThePropagationLeftInvariant) {
  const ap::ConingMotion cone;
  const Eigen::Quaterniond q0(Eigen::AngleAxisd(2.0, Eigen::Vector3d(1.0, -2.0, 0.5).normalized()));
  ap::KinematicConfig config;
  config.stamp_filter = ap::StampFilter::SensorClock;
  ap::KinematicPropagator from_identity(config);
  config.initial_q_WB = q0;
  ap::KinematicPropagator from_q0(config);
  std::uint64_t state = 7;
  double worst = 0.0;
  for (int k = 0; k <= 400; ++k) {
    const double stamp = k * kPeriod + (k > 0 ? latencyRandom(state, 2e-4) : 0.0);
    const Eigen::Vector3d w = cone.bodyRate(k * kPeriod);
    from_identity.addSample(stamp, w);
    from_q0.addSample(stamp, w);
    worst =
        std::max(worst, ap::rotationAngle(from_q0.orientation(), q0 * from_identity.orientation()));
  }
  EXPECT_LE(worst, 5e-14);
}

TEST(SensorClockFilter, LowersTheJitterErrorOfCf4TenTimesOnceSettled) {
  const ap::ConingMotion cone;
  const int seeds = 6, settled = 1000;
  double log_ratio = 0.0, log_ratio_settled = 0.0;
  for (int seed = 1; seed <= seeds; ++seed) {
    std::uint64_t state = seed;
    std::vector<double> stamps;
    for (int k = 0; k <= 4000; ++k) {
      stamps.push_back(k * kPeriod + (k > 0 ? latencyRandom(state, 1e-4) : 0.0));
    }
    double whole[2] = {0.0, 0.0}, after[2] = {0.0, 0.0};
    for (int filtered = 0; filtered < 2; ++filtered) {
      ap::KinematicConfig config;
      config.initial_q_WB = cone.attitude(0.0);
      config.stamp_filter = filtered ? ap::StampFilter::SensorClock : ap::StampFilter::None;
      ap::KinematicPropagator propagator(config);
      for (int k = 0; k <= 4000; ++k) {
        propagator.addSample(stamps[k], cone.bodyRate(k * kPeriod));
        if (k < 3) continue;
        const double e =
            ap::rotationAngle(propagator.orientation(), cone.attitude(propagator.time()));
        whole[filtered] = std::max(whole[filtered], e);
        if (k >= settled) after[filtered] = std::max(after[filtered], e);
      }
    }
    log_ratio += std::log(whole[0] / whole[1]);
    log_ratio_settled += std::log(after[0] / after[1]);
  }
  EXPECT_GE(std::exp(log_ratio_settled / seeds), 10.0);
  EXPECT_GE(std::exp(log_ratio / seeds), 4.0);
}

// The same stream, but the sensor slows to 100 Hz after 5 s and the stream jumps back to 0 (a
// looped bag) after 10 s: the filter restarts at both, the later stamps are carried only
// within one model of the clock, and the state stays better than unfiltered.
TEST(SensorClockFilter, CarriesLaterStampsOnlyWithinOneModel) {
  const ap::ConingMotion cone;
  std::vector<double> truth;  // the sensor's sample times
  for (int k = 0; k <= 1000; ++k) truth.push_back(k * kPeriod);
  for (int k = 1; k <= 500; ++k) truth.push_back(5.0 + k * 2.0 * kPeriod);
  for (int k = 0; k <= 2000; ++k) truth.push_back(k * kPeriod);
  for (int seed = 1; seed <= 3; ++seed) {
    std::uint64_t state = seed;
    std::vector<double> stamps;
    for (std::size_t k = 0; k < truth.size(); ++k) {
      stamps.push_back(truth[k] + (k > 0 ? latencyRandom(state, 1e-4) : 0.0));
    }
    double worst[2] = {0.0, 0.0};
    for (int filtered = 0; filtered < 2; ++filtered) {
      ap::KinematicConfig config;
      config.initial_q_WB = cone.attitude(0.0);
      config.stamp_filter = filtered ? ap::StampFilter::SensorClock : ap::StampFilter::None;
      ap::KinematicPropagator propagator(config);
      for (std::size_t k = 0; k < truth.size(); ++k) {
        propagator.addSample(stamps[k], cone.bodyRate(truth[k]));
        const double e =
            ap::rotationAngle(propagator.orientation(), cone.attitude(propagator.time()));
        ASSERT_TRUE(std::isfinite(e)) << k;
        if (k >= 3) worst[filtered] = std::max(worst[filtered], e);
      }
      if (filtered) {
        EXPECT_EQ(propagator.stampFilter()->restarts(), 2u);
      }
    }
    EXPECT_LT(worst[1], worst[0]) << seed;
  }
}

namespace {

// A FIFO read every `batch` samples at the newest sample's time plus `latency(read)`: the
// receipt stamps of the form given (repeated, or less k periods for the k-th newest).
std::vector<double> fifoStamps(int reads, int batch, bool repeated,
                               const std::function<double(int)>& latency) {
  std::vector<double> stamps;
  for (int read = 0; read < reads; ++read) {
    const int newest = (read + 1) * batch - 1;
    const double receipt = kT0 + kPeriod * newest + latency(read);
    for (int k = newest - batch + 1; k <= newest; ++k) {
      stamps.push_back(repeated ? receipt : receipt - kPeriod * (newest - k));
    }
  }
  return stamps;
}

}  // namespace

// Repeated stamps on a clock without latency jitter: from the second read on every sample gets
// its own stamp, the sensor's (the batch's stamp belongs to its newest sample), none is
// counted lost, and the filter sees the batch size.
TEST(SensorClockFilter, GivesEachRepeatedStampItsOwnIndex) {
  for (int batch : {2, 10, 20}) {
    ap::SensorClockFilter filter;
    const auto stamps = fifoStamps(200, batch, true, [](int) { return 0.0; });
    const double ulp = std::nextafter(kT0, 2 * kT0) - kT0;
    for (std::size_t n = 0; n < stamps.size(); ++n) {
      const auto r = filter.filter(stamps[n]);
      if (n >= static_cast<std::size_t>(batch)) {
        EXPECT_NEAR(r.t, kT0 + kPeriod * n, 8 * ulp) << batch << ": " << n;
        EXPECT_EQ(filter.index(), n) << batch << ": " << n;
      }
    }
    EXPECT_EQ(filter.batchSize(), static_cast<std::uint64_t>(batch));
    EXPECT_EQ(filter.missed(), 0u);
    EXPECT_EQ(filter.rejected(), 0u);
    EXPECT_EQ(filter.restarts(), 0u);
    EXPECT_FALSE(filter.unfiltered());
    EXPECT_NEAR(filter.period(), kPeriod, 1e-9);
  }
}

// A read that brings fewer samples than the periods its stamp counts lost the rest.
TEST(SensorClockFilter, CountsTheSamplesARepeatedBatchLacks) {
  ap::SensorClockFilter filter;
  auto stamps = fifoStamps(100, 10, true, [](int) { return 0.0; });
  stamps.erase(stamps.begin() + 503, stamps.begin() + 506);  // three of read 50
  for (double t : stamps) filter.filter(t);
  EXPECT_EQ(filter.missed(), 3u);
  EXPECT_EQ(filter.restarts(), 0u);
}

// Stamps exactly a period apart inside a read, 0.1 ms of latency jitter per read: the jitter is
// measured at the reads (not collapsed by the exact spacing), no read is rejected, nothing
// restarts, and the filtered stamps stay within the jitter of the sensor clock.
TEST(SensorClockFilter, KeepsItsJitterOnStampsAPeriodApart) {
  for (int batch : {10, 20}) {
    ap::SensorClockFilter filter;
    std::uint64_t state = 9;
    const double sigma = 1e-4;
    const auto stamps =
        fifoStamps(6000 / batch, batch, false, [&](int) { return latencyRandom(state, sigma); });
    for (std::size_t n = 0; n < stamps.size(); ++n) {
      const auto r = filter.filter(stamps[n]);
      if (n > 2000) {
        EXPECT_NEAR(r.t, kT0 + kPeriod * n, 3 * sigma) << n;
      }
    }
    EXPECT_EQ(filter.batchSize(), static_cast<std::uint64_t>(batch));
    EXPECT_GT(filter.jitter(), 0.5 * sigma) << batch;
    EXPECT_LT(filter.jitter(), 2.0 * sigma) << batch;
    EXPECT_EQ(filter.rejected(), 0u) << batch;
    EXPECT_EQ(filter.restarts(), 0u) << batch;
  }
}

// The boundary: a batch of max_batch repeated stamps is modelled; one more sample and the
// stamps are returned unfiltered and flagged, until a batch of a usable size has been seen
// whole, after which the model starts again.
TEST(SensorClockFilter, FallsBackToUnfilteredStampsOnBatchesTooLarge) {
  ap::SensorClockFilter::Options options;
  options.max_batch = 20;
  for (int batch : {20, 21}) {
    ap::SensorClockFilter filter(options);
    const auto stamps = fifoStamps(10, batch, true, [](int) { return 0.0; });
    std::uint64_t unfiltered = 0;
    for (double t : stamps) {
      const auto r = filter.filter(t);
      if (r.verdict == Verdict::Unfiltered) {
        ++unfiltered;
        EXPECT_EQ(r.t, t);
      }
    }
    EXPECT_EQ(filter.unfiltered(), batch > 20) << batch;
    // The first read's 21st sample, then every sample of the nine reads after it.
    EXPECT_EQ(unfiltered, batch > 20 ? 1u + 9u * 21u : 0u) << batch;
    // Smaller batches again: back to the model after the first one seen whole.
    const double t0 = stamps.back() + 0.5;
    for (int read = 0; read < 5; ++read) {
      for (int k = 0; k < 10; ++k) filter.filter(t0 + read * 10 * kPeriod);
    }
    EXPECT_FALSE(filter.unfiltered()) << batch;
    EXPECT_EQ(filter.batchSize(), 10u);
  }
}

namespace {

// 50 Hz, received after a latency whose spread is `sigma` periods (absolute normal draws, so
// that no sample is received before it is taken), in order.
std::vector<double> latentStamps(double sigma, int count, std::uint64_t seed, double t0) {
  const double period = 0.02;
  std::uint64_t state = seed;
  std::vector<double> stamps;
  for (int n = 0; n < count; ++n) {
    const double t = t0 + period * n + std::abs(sigma * period * normalRandom(state));
    stamps.push_back(stamps.empty() ? t : std::max(t, stamps.back() + 1e-6));
  }
  return stamps;
}

}  // namespace

// A stream the model does not fit (latency spread 0.6 periods: the quadrotor's receipt stamps)
// gets its receipt stamps back once the jitter is measured (warm-up), says so once (misfit,
// one fallback), and the moves before that are counted; the same stream with a spread of 0.02
// periods fits and never falls back. Stamps that fit again are modelled again.
TEST(SensorClockFilter, FallsBackToReceiptStampsWhenTheStreamDoesNotFit) {
  ap::SensorClockFilter filter;
  const std::vector<double> stamps = latentStamps(0.6, 3000, 5, kT0);
  std::size_t first_unfiltered = stamps.size();
  for (std::size_t n = 0; n < stamps.size(); ++n) {
    const auto r = filter.filter(stamps[n]);
    if (r.verdict == Verdict::Unfiltered && first_unfiltered == stamps.size()) {
      first_unfiltered = n;
    }
    if (n > first_unfiltered) {
      EXPECT_EQ(r.verdict, Verdict::Unfiltered) << n;
      EXPECT_EQ(r.t, stamps[n]) << n;
    }
  }
  EXPECT_LE(first_unfiltered, 50u);
  EXPECT_TRUE(filter.misfit());
  EXPECT_EQ(filter.fallbacks(), 1u);
  EXPECT_GT(filter.jitter(), ap::kMisfitJitter * filter.period());
  EXPECT_LE(filter.moved(), first_unfiltered);
  // The same sensor, received with little spread, after a second: modelled again.
  for (double t : latentStamps(0.02, 3000, 6, stamps.back() + 1.0)) filter.filter(t);
  EXPECT_FALSE(filter.misfit());
  EXPECT_EQ(filter.fallbacks(), 1u);
  EXPECT_EQ(filter.filter(stamps.back() + 1.0 + 3000 * 0.02).verdict, Verdict::Modelled);

  ap::SensorClockFilter fitting;
  for (double t : latentStamps(0.02, 3000, 7, kT0)) fitting.filter(t);
  EXPECT_FALSE(fitting.misfit());
  EXPECT_EQ(fitting.fallbacks(), 0u);
  EXPECT_LT(fitting.jitter(), ap::kFitAgainJitter * fitting.period());
}

// The account of moves: a stamp returned as it came is not moved; the largest moves later and
// earlier are the largest differences seen, each on its own side (later: none, the rule).
TEST(SensorClockFilter, CountsItsMovesOnEachSide) {
  ap::SensorClockFilter filter;
  std::uint64_t moved = 0;
  double later = 0.0, earlier = 0.0;
  for (double t : latentStamps(0.05, 2000, 8, kT0)) {
    const double d = filter.filter(t).t - t;
    moved += d != 0.0;
    later = std::max(later, d);
    earlier = std::max(earlier, -d);
  }
  EXPECT_EQ(filter.moved(), moved);
  EXPECT_EQ(filter.largestLater(), later);
  EXPECT_EQ(filter.largestEarlier(), earlier);
  EXPECT_EQ(later, 0.0);
  EXPECT_GT(earlier, 0.0);
}

// reset() forgets the batches with the model: single samples after it are batches of one.
TEST(SensorClockFilter, ResetForgetsTheBatchSize) {
  ap::SensorClockFilter filter;
  for (double t : fifoStamps(20, 10, true, [](int) { return 0.0; })) filter.filter(t);
  EXPECT_EQ(filter.batchSize(), 10u);
  filter.reset();
  EXPECT_EQ(filter.batchSize(), 1u);
  for (int n = 0; n < 5; ++n) filter.filter(100.0 + kPeriod * n + (n % 2) * 1e-5);
  EXPECT_EQ(filter.batchSize(), 1u);
}

// The node's rule "no stamp is published twice" (docs/node.md) through rate changes: 100 Hz, then
// 5 kHz, then 100 Hz again, received with a latency and a jitter of up to several 5 kHz periods,
// in order (the engine drops a receipt stamp before its source's newest before the filter), and
// with bursts whose receipt stamps are a nanosecond apart. No jump of time happens: every stamp
// returned, rounded to the nanosecond of a published stamp, is later than the one before.
class RateChanges : public ::testing::TestWithParam<double> {};

TEST_P(RateChanges, NeverRepeatAPublishedStamp) {
  const double jitter = GetParam();
  ap::SensorClockFilter filter;
  std::uint64_t state = 5;
  double t = 1000.0;  // core time: seconds since the origin
  double receipt = 0.0;
  long long published = std::numeric_limits<long long>::min();
  int repeated = 0, in_a_row = 0, longest = 0;
  auto run = [&](double period, double seconds) {
    const long n = std::lround(seconds / period);
    for (long k = 0; k < n; ++k) {
      t += period;
      receipt = std::max(receipt + 1e-9, t + 5e-4 + jitter * std::abs(normalRandom(state)));
      const ap::SensorClockFilter::Result r = filter.filter(receipt);
      const long long ns = std::llround(r.t * 1e9);
      if (ns <= published) {
        ++repeated;
        longest = std::max(longest, ++in_a_row);
      } else {
        in_a_row = 0;
      }
      published = std::max(published, ns);
    }
  };
  run(0.01, 5.0);
  run(0.0002, 2.0);
  run(0.01, 5.0);
  EXPECT_EQ(repeated, 0) << "longest run " << longest << ", restarts " << filter.restarts();
}

INSTANTIATE_TEST_SUITE_P(Jitters, RateChanges, ::testing::Values(0.0, 2e-4, 1e-3, 3e-3, 1e-2));

// The same through the engine (kinematic, stamp_filter sensor_clock): the states handed on with
// each applied rate (imu/data's stamps) never repeat a stamp.
TEST(SensorClockFilter, RateChangesRepeatNoStampOfTheAppliedRates) {
  struct Stamps : ap::EngineSink {
    std::vector<ap::Stamp> applied;
    void publishState(const ap::EngineState&) override {}
    void inputApplied(const ap::Input&, const ap::EngineState& s) override {
      applied.push_back(s.stamp);
    }
    void note(const ap::EngineNote&) override {}
  } sink;
  ap::EngineConfig config;
  config.kinematic.stamp_filter = ap::StampFilter::SensorClock;
  ap::AttitudeEngine engine(config, sink);
  std::uint64_t state = 9;
  const ap::Stamp epoch = 1780000000LL * 1000000000LL;
  ap::Stamp receipt = 0;
  double t = 0.0;
  auto run = [&](double period, double seconds) {
    const long n = std::lround(seconds / period);
    for (long k = 0; k < n; ++k) {
      t += period;
      const double late = 5e-4 + 3e-3 * std::abs(normalRandom(state));
      receipt = std::max<ap::Stamp>(receipt + 1, epoch + std::llround((t + late) * 1e9));
      ap::Input in;
      in.source = ap::Source::Imu;
      in.stamp = receipt;
      in.value = Eigen::Vector3d(0.0, 0.0, 0.3);
      engine.submit(in);
    }
  };
  run(0.01, 5.0);
  run(0.0002, 2.0);
  run(0.01, 5.0);
  ASSERT_GT(sink.applied.size(), 10000u);
  std::size_t repeated = 0;
  for (std::size_t i = 1; i < sink.applied.size(); ++i)
    repeated += sink.applied[i] <= sink.applied[i - 1];
  EXPECT_EQ(repeated, 0u);
}

namespace {

// The causal rule against the receipt stamps: a returned stamp is no later than its receipt
// stamp, except where that stamp is less than kMinStampStep after the stamp returned before (the
// receipt stamps themselves do not advance by that, e.g. a FIFO read's repeated stamp before a
// period is known); there it is the smallest stamp that follows the one before. Returns the
// number of stamps returned later than received (which must be the exempt ones).
struct CausalCheck {
  ap::SensorClockFilter filter;
  double previous = -std::numeric_limits<double>::infinity();
  std::size_t later = 0, exempt = 0, count = 0;

  ap::SensorClockFilter::Result operator()(double receipt) {
    const auto r = filter.filter(receipt);
    const double next = std::max(std::nextafter(previous, INFINITY), previous + ap::kMinStampStep);
    if (r.t > receipt) {
      ++later;
      if (receipt < next && r.t == next) {
        ++exempt;
      } else {
        ADD_FAILURE() << "stamp " << count << ": " << (r.t - receipt) * 1e9
                      << " ns later than received (verdict " << static_cast<int>(r.verdict) << ")";
      }
    }
    previous = r.t;
    ++count;
    return r;
  }
};

// Sample n of a 200 Hz clock at kT0 + P n, received `delay` plus an exponential latency of mean
// and jitter `sigma` later.
std::vector<double> delayedStamps(int count, double delay, double sigma, std::uint64_t seed) {
  std::uint64_t state = seed;
  std::vector<double> stamps;
  for (int n = 0; n < count; ++n) {
    stamps.push_back(kT0 + kPeriod * n + delay + latencyRandom(state, sigma));
  }
  return stamps;
}

}  // namespace

// A receipt stamp is the sample's time plus a latency >= 0, so a stamp later than received is
// later than the sample too: no returned stamp is, on streams that fit (with and without a
// constant transport delay), on a stream that does not (latency spread 0.6 periods), on FIFO
// reads of repeated and of spaced stamps, and across restarts (a jump back, a new rate, a run of
// early stamps). Only a repeated stamp before the period is known follows the one before by
// kMinStampStep, later than received (the first read's, here).
TEST(SensorClockFilter, NeverReturnsAStampLaterThanItsReceipt) {
  for (double delay : {0.0, 3e-3}) {
    CausalCheck check;
    for (double t : delayedStamps(5000, delay, 1e-4, 21)) check(t);
    EXPECT_EQ(check.later, 0u) << delay;
    EXPECT_EQ(check.filter.fallbacks(), 0u);
  }
  {
    CausalCheck check;
    for (double t : latentStamps(0.6, 3000, 5, kT0)) check(t);
    EXPECT_EQ(check.later, 0u);
    EXPECT_EQ(check.filter.fallbacks(), 1u);
  }
  for (bool repeated : {true, false}) {
    for (int batch : {2, 10, 20}) {
      CausalCheck check;
      std::uint64_t state = 23;
      for (double t : fifoStamps(4000 / batch, batch, repeated,
                                 [&](int) { return 2e-3 + latencyRandom(state, 2e-4); })) {
        check(t);
      }
      // The first read's repeated stamps only, each after the one before.
      EXPECT_EQ(check.later, check.exempt) << batch;
      EXPECT_EQ(check.later, repeated ? static_cast<std::size_t>(batch - 1) : 0u) << batch;
      EXPECT_EQ(check.filter.restarts(), 0u) << batch;
    }
  }
  {
    CausalCheck check;
    std::uint64_t state = 29;
    double t = 50.0;
    auto run = [&](double period, int samples) {
      for (int n = 0; n < samples; ++n, t += period) check(t + latencyRandom(state, 1e-4));
    };
    run(kPeriod, 2000);
    t = 20.0;  // a jump back: restarted at the stamp as it came
    run(kPeriod, 500);
    run(kPeriod / 4, 1000);  // a new rate: early stamps rejected, then restarted
    run(kPeriod * 2, 500);   // and slower: lost periods, then restarted
    EXPECT_EQ(check.later, 0u);
    EXPECT_GE(check.filter.restarts(), 3u);
    EXPECT_GT(check.filter.rejected(), 0u);
  }
}

// The constant part of a latency is no stamp's to tell: the filtered stamps sit on the sensor
// clock delayed by it (within a fifth of the jitter once settled, the line on the lower envelope),
// never on the clock itself; `rate_delay` is the setting that removes a known delay.
TEST(SensorClockFilter, KeepsTheConstantPartOfTheLatency) {
  const double delay = 3e-3, sigma = 1e-4;
  ap::SensorClockFilter filter;
  const auto stamps = delayedStamps(6000, delay, sigma, 31);
  double sum = 0.0, sum2 = 0.0;
  int count = 0;
  for (int n = 0; n < 6000; ++n) {
    const double e = filter.filter(stamps[n]).t - (kT0 + kPeriod * n) - delay;
    if (n < 1000) continue;
    sum += e;
    sum2 += e * e;
    ++count;
  }
  EXPECT_LE(std::sqrt(sum2 / count), sigma / 5.0);
  EXPECT_LE(std::abs(sum / count), sigma / 20.0);  // the least of 100 draws: sigma / 100 above
}

// The envelope forgets: when the latencies' spread shrinks tenfold (0.2 -> 0.02 ms, floor 0), the
// filtered stamps come back onto the sensor clock within the filter's memory, rather than staying
// below it by the old spread's least latency.
TEST(SensorClockFilter, LowerEnvelopeFollowsAShrinkingSpread) {
  ap::SensorClockFilter filter;
  std::uint64_t state = 37;
  const int before = 2000, after = 6000;
  double sum2 = 0.0;
  int count = 0;
  for (int n = 0; n < before + after; ++n) {
    const double t = kT0 + kPeriod * n;
    const double sigma = n < before ? 2e-4 : 2e-5;
    const double e = filter.filter(t + latencyRandom(state, sigma)).t - t;
    if (n < before + after - 1000) continue;
    sum2 += e * e;
    ++count;
  }
  EXPECT_LE(std::sqrt(sum2 / count), 2e-5 / 2.0);
  EXPECT_EQ(filter.restarts(), 0u);
}

// At the warm-up's boundary (Options::warm_up draws): a stamp received with no latency, 1 ms
// earlier than the others (1 ms plus 20 us of exponential spread: each its own draw), as the
// (warm_up - 1)-th and the warm_up-th stamp (it joins the fit) and as the next (rejected as an
// outlier once warm) is returned no later than received, whichever the verdict.
TEST(SensorClockFilter, AnEarlyStampAtTheWarmUpBoundaryIsNotReturnedLate) {
  const ap::SensorClockFilter::Options options;
  for (int early : {options.warm_up - 2, options.warm_up - 1, options.warm_up}) {
    CausalCheck check;
    Verdict verdict = Verdict::Restarted;
    std::uint64_t state = 41;
    for (int n = 0; n < 100; ++n) {
      const double latency = 1e-3 + latencyRandom(state, 2e-5);
      const double receipt = kT0 + kPeriod * n + (n == early ? 0.0 : latency);
      const auto r = check(receipt);
      if (n == early) {
        verdict = r.verdict;
        EXPECT_LE(r.t, receipt) << early;
      }
    }
    EXPECT_EQ(check.later, 0u) << early;
    EXPECT_EQ(verdict, early < options.warm_up ? Verdict::Modelled : Verdict::Rejected) << early;
    EXPECT_EQ(check.filter.restarts(), 0u) << early;
  }
}
