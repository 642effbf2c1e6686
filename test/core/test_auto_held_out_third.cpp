// `integrator: auto` on a third held-out set, written before the rule for means with lost
// samples was extended to consider rk4 and not looked at while it was tuned (docs/real_streams.md,
// "How the `auto` rule was validated"): the first two sets (test_auto_held_out.cpp,
// test_auto_held_out_second.cpp) had been looked at, so they were no longer clean. Other motions,
// rates, loss patterns and seeds than the sweep's and the first two sets': an elliptic coning
// (roll 0.3 rad and pitch 0.12 rad in quadrature at 3.3 Hz on a slow yaw turn), a swing tracing
// a Lissajous figure in roll and pitch with 41 Hz yaw vibration (both sums of sinusoids in yaw,
// pitch and roll), a rod-like body tumbling end over end while it rolls, and a triaxial body
// at 15 rad/s (both exact, torque_free_motion.h); means with lost samples at 64, 140, 210, 300,
// 560 and 900 Hz: 4 %, 8 % and 20 % lost one by one, bursts of one to four, every eleventh lost,
// and start-stamped means with 7 % lost; as controls point samples and means at 64, 300 and
// 900 Hz, point samples with bursts lost, jitter, means with jitter and a rate change at those
// rates; seeds 301-305.
//
// The criterion is the first set's: `auto`'s error within 1.5x of the best fixed kinematic
// method's on the same samples against the closed form (held_out_streams.h).
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "held_out_streams.h"

using namespace held_out;

namespace {

/// An elliptic coning: roll 0.3 rad and pitch 0.12 rad at 3.3 Hz a quarter period apart, on a
/// yaw turn of 0.2 rad/s (|w| up to 6.4 rad/s, turning at 3.3 Hz).
Motion ellipticCone() {
  EulerSines m;
  m.offset = Eigen::AngleAxisd(-0.8, Eigen::Vector3d(0.4, 1.0, -0.2).normalized());
  m.yaw.drift = 0.2;
  m.roll.terms = {{0.3, 3.3, 0.0}};
  m.pitch.terms = {{0.12, 3.3, 0.5 * M_PI}};
  return {"ellipse", [m](double t) { return m.attitude(t); },
          [m](double t) { return m.bodyRate(t); }, 2.0 * M_PI * 3.3};
}

/// A swing: roll 1.0 rad at 0.9 Hz and pitch 0.35 rad at 1.8 Hz (a figure of eight), a yaw sway
/// of 0.2 rad at 0.3 Hz, and yaw vibration of 2 mrad at 41 Hz.
Motion swing() {
  EulerSines m;
  m.offset = Eigen::AngleAxisd(1.7, Eigen::Vector3d(0.1, -0.6, 0.8).normalized());
  m.yaw.terms = {{0.2, 0.3, 1.1}, {0.002, 41.0, 0.3}};
  m.pitch.terms = {{0.35, 1.8, 0.5}};
  m.roll.terms = {{1.0, 0.9, 2.4}};
  return {"swing", [m](double t) { return m.attitude(t); }, [m](double t) { return m.bodyRate(t); },
          2.0 * M_PI * 41.0};
}

/// A rod-like body (moments 0.25, 3.0, 3.1 kg m^2) tumbling end over end at about 6 rad/s while
/// it rolls at 1.5 rad/s about its long axis.
Motion rod() {
  return freeBody(
      "rod", Eigen::Vector3d(0.25, 3.0, 3.1), Eigen::Vector3d(1.5, 6.0, 0.8),
      Eigen::Quaterniond(Eigen::AngleAxisd(2.6, Eigen::Vector3d(0.5, 0.5, -0.7).normalized())));
}

/// A triaxial body (3, 4, 6 kg m^2) at 15 rad/s.
Motion fastBody() {
  return freeBody(
      "fast", Eigen::Vector3d(3.0, 4.0, 6.0), Eigen::Vector3d(12.0, 2.0, -9.0),
      Eigen::Quaterniond(Eigen::AngleAxisd(-0.5, Eigen::Vector3d(-0.9, 0.2, 0.3).normalized())));
}

std::vector<StreamSpec> streamSpecs() {
  std::vector<StreamSpec> specs;
  auto add = [&specs](const std::string& name, double hz) -> StreamSpec& {
    return addStream(specs, name, hz);
  };
  // The kind the rule was extended for: means with lost samples, filled (max_gap_fill 4).
  asMeans(add("means_4pct_lost", 64.0)).drop = 0.04;
  asMeans(add("means_8pct_lost", 300.0)).drop = 0.08;
  asMeans(add("means_20pct_lost", 900.0)).drop = 0.20;
  StreamSpec& bursts = asMeans(add("means_bursts_2pct", 210.0));
  bursts.drop = 0.02;
  bursts.burst = 4;
  asMeans(add("means_every_11th_lost", 560.0)).drop_every = 11;
  StreamSpec& start = asMeans(add("means_start_7pct_lost", 140.0));
  start.drop = 0.07;
  start.stamped = AverageStamp::Start;
  start.average_stamp = AverageStamp::Start;
  // Controls.
  for (double hz : {64.0, 300.0, 900.0}) {
    add("point", hz);
    asMeans(add("means_end", hz));
  }
  StreamSpec& point_bursts = add("point_bursts_2pct", 210.0);
  point_bursts.drop = 0.02;
  point_bursts.burst = 4;
  add("jitter_0.2ms", 560.0).jitter = 2e-4;
  asMeans(add("means_jitter_0.15ms", 300.0)).jitter = 1.5e-4;
  add("rate_change_140_560Hz", 140.0).rate_after_hz = 560.0;
  return specs;
}

constexpr std::uint64_t kSeed0 = 301;  // seeds kSeed0 .. kSeed0 + kSeeds - 1

void judgeMotion(const Motion& motion) {
  held_out::judgeMotion(motion, streamSpecs(), kSeed0, "[ held-out-3 ]");
}

}  // namespace

// The truths: each motion's rate generates its attitude, dq/dt = 1/2 q (x) (0, w_B), checked by
// central differences; the interval means over the longest period (64 Hz) agree with those of
// eight times as many parts.
TEST(AutoHeldOutThird, MotionsRatesGenerateTheirAttitudes) {
  for (const Motion& m : {ellipticCone(), swing(), rod(), fastBody()})
    expectRatesGenerateAttitudes(m, 1.0 / 64.0);
}

// The loss patterns lose what they say: bursts about 5 % of the samples, every eleventh sample
// exactly (one at a time).
TEST(AutoHeldOutThird, LossPatterns) {
  const Motion m = rod();
  for (const StreamSpec& spec : streamSpecs()) {
    if (spec.burst == 1 && spec.drop_every == 0) continue;
    const std::vector<Sample> samples = makeStream(m, spec, kSeed0);
    const double h = 1.0 / spec.rate_hz;
    long lost = 0;
    for (std::size_t k = 1; k < samples.size(); ++k) {
      const long periods = std::lround((samples[k].stamp - samples[k - 1].stamp) / h);
      EXPECT_GE(periods, 1) << spec.name;
      if (spec.drop_every > 0) {
        EXPECT_LE(periods, 2) << spec.name;
      }
      lost += periods - 1;
    }
    const long n = std::lround(kDuration * spec.rate_hz);
    if (spec.drop_every > 0) {
      EXPECT_EQ(lost, n / spec.drop_every) << spec.name;
    } else {
      // 2 % of the samples start a burst of 1 to 4 (2.5 on average): about 5 % lost.
      EXPECT_GT(lost, 0.03 * n) << spec.name;
      EXPECT_LT(lost, 0.08 * n) << spec.name;
    }
  }
}

TEST(AutoHeldOutThird, EllipticConing) { judgeMotion(ellipticCone()); }
TEST(AutoHeldOutThird, LissajousSwingWithVibration) { judgeMotion(swing()); }
TEST(AutoHeldOutThird, RodTumblingEndOverEnd) { judgeMotion(rod()); }
TEST(AutoHeldOutThird, FastTriaxialBody) { judgeMotion(fastBody()); }
