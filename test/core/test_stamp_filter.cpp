// SensorClockFilter against a simulated sensor clock: sample n taken at t0 + P n, received
// with jitter, lost, delayed, at a new rate, after a restart. The truth is the simulated clock.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <vector>

#include "attitude_propagator/coning_motion.h"
#include "attitude_propagator/kinematic_propagator.h"
#include "attitude_propagator/quaternion.h"
#include "attitude_propagator/stamp_filter.h"
#include "rotation_matchers.h"

namespace ap = attitude_propagator;
using Verdict = ap::SensorClockFilter::Verdict;

namespace {

double normalRandom(std::uint64_t& state) {
  const double u1 = 1.0 - uniformRandom(state), u2 = uniformRandom(state);
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
}

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

// Gaussian receipt jitter of 0.1 ms at 200 Hz: once settled the filtered stamps are within
// a fifth of the jitter of the sensor clock (the line averages over the filter's memory).
TEST(SensorClockFilter, AveragesOutReceiptJitter) {
  ap::SensorClockFilter filter;
  std::uint64_t state = 3;
  const double sigma = 1e-4;
  double sum2 = 0.0;
  int count = 0;
  for (int n = 0; n < 8000; ++n) {
    const double t = 100.0 + kPeriod * n;
    const auto r = filter.filter(t + sigma * normalRandom(state));
    if (n < 1000) continue;
    sum2 += (r.t - t) * (r.t - t);
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
    const auto r = filter.filter(t + delay + 1e-6 * normalRandom(state));
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

// A stamp that jumps (a restarted driver, a looped bag) restarts the model at once and is
// returned as it is, so the propagator's own time policy sees the jump.
TEST(SensorClockFilter, RestartsOnAJump) {
  ap::SensorClockFilter filter;
  for (int n = 0; n < 100; ++n) filter.filter(50.0 + kPeriod * n);
  const auto r = filter.filter(20.0);
  EXPECT_EQ(r.verdict, Verdict::Restarted);
  EXPECT_EQ(r.t, 20.0);
  EXPECT_EQ(filter.restarts(), 1u);
  for (int n = 1; n < 100; ++n) EXPECT_NEAR(filter.filter(20.0 + kPeriod * n).t, 20.0 + kPeriod * n, 1e-9);
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

// In the propagator: coning at 200 Hz with 0.1 ms receipt jitter. The filter removes most of
// the error the jitter causes (the truth is compared at the stamp each state is reported at).
TEST(SensorClockFilter, LowersTheJitterErrorOfCf4) {
  const ap::ConingMotion cone;
  double ratio_sum = 0.0;
  const int seeds = 6;
  for (int seed = 1; seed <= seeds; ++seed) {
    std::uint64_t state = seed;
    std::vector<double> stamps;
    for (int k = 0; k <= 4000; ++k) stamps.push_back(k / 200.0 + (k ? 1e-4 * normalRandom(state) : 0.0));
    double errors[2] = {0.0, 0.0};
    for (int filtered = 0; filtered < 2; ++filtered) {
      ap::KinematicConfig config;
      config.initial_q_WB = cone.attitude(0.0);
      config.stamp_filter = filtered ? ap::StampFilter::SensorClock : ap::StampFilter::None;
      ap::KinematicPropagator propagator(config);
      for (int k = 0; k <= 4000; ++k) {
        propagator.addSample(stamps[k], cone.bodyRate(k / 200.0));
        if (k < 3) continue;
        errors[filtered] = std::max(errors[filtered], ap::rotationAngle(propagator.orientation(), cone.attitude(propagator.time())));
      }
    }
    ratio_sum += std::log(errors[0] / errors[1]);
  }
  EXPECT_GE(std::exp(ratio_sum / seeds), 3.0);
}
