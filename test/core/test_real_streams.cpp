// Kinematic propagation on the streams real gyros deliver: interval-averaged rates, stamps with
// receipt jitter, lost samples, a gyro bias. The truths are the coning motion's closed form
// (include/attitude_propagator/numerics/coning_motion.h) and its interval means by Gauss-Legendre
// quadrature, never a figure of the code under test.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <limits>
#include <vector>

#include "attitude_propagator/models/kinematic_propagator.h"
#include "attitude_propagator/numerics/coning_motion.h"
#include "attitude_propagator/numerics/kinematic_step.h"
#include "attitude_propagator/numerics/quaternion.h"
#include "attitude_propagator/time/stamp_filter.h"
#include "gyro_streams.h"
#include "integrator_cases.h"
#include "rotation_matchers.h"
#include "sampling.h"

namespace ap = attitude_propagator;
using ap::ConingMotion;
using ap::Integrator;
using ap::RateSamples;

namespace {

// One stream: what the gyro delivers, sample by sample.
struct StreamOptions {
  RateSamples kind = RateSamples::Instantaneous;
  double rate_hz = 200.0;
  double duration = 20.0;
  double jitter = 0.0;  // s, standard deviation of the receipt delay about its mean
  double drop = 0.0;    // probability that a sample is lost
  std::uint64_t seed = 1;
};

struct Sample {
  double stamp;  // as received
  Eigen::Vector3d w_B;
};

// Sample k is taken at k / rate; an averaged sample holds the mean over the period it closes.
// The anchor (k = 0) keeps its exact stamp, so every method starts from the truth at t = 0.
std::vector<Sample> coningStream(const StreamOptions& o) {
  const ConingMotion cone;
  auto rate = [&cone](double t) { return cone.bodyRate(t); };
  std::uint64_t state = o.seed;
  const long n = std::lround(o.duration * o.rate_hz);
  std::vector<Sample> samples;
  for (long k = 0; k <= n; ++k) {
    const double t = k / o.rate_hz;
    const Eigen::Vector3d w = o.kind == RateSamples::IntervalAverage
                                  ? intervalMean(rate, t - 1.0 / o.rate_hz, t)
                                  : cone.bodyRate(t);
    const double noise = k > 0 && o.jitter > 0.0 ? o.jitter * normalRandom(state) : 0.0;
    const bool lost = k > 3 && o.drop > 0.0 && uniformRandom(state) < o.drop;
    if (!lost) samples.push_back({t + noise, w});
  }
  return samples;
}

ap::KinematicConfig configFor(Integrator method, RateSamples kind) {
  ap::KinematicConfig config;
  config.integrator = method;
  config.rate_samples = kind;
  config.initial_q_WB = ConingMotion().attitude(0.0);
  return config;
}

// States after the anchor that carry the unavoidable start-up error (see test_kinematic_step).
constexpr int kStartUpSamples = 3;

// Largest error along the path against the closed form at the stamp each state is reported at.
double pathError(const ap::KinematicConfig& config, const std::vector<Sample>& samples) {
  const ConingMotion cone;
  ap::KinematicPropagator propagator(config);
  double worst = 0.0;
  for (std::size_t k = 0; k < samples.size(); ++k) {
    propagator.addSample(samples[k].stamp, samples[k].w_B);
    if (k < kStartUpSamples) continue;
    worst = std::max(worst,
                     ap::rotationAngle(propagator.orientation(), cone.attitude(propagator.time())));
  }
  return worst;
}

double coningError(Integrator method, const StreamOptions& o) {
  return pathError(configFor(method, o.kind), coningStream(o));
}

}  // namespace

TEST(RateSamplesNames, RoundTripAndListTheAcceptedValues) {
  for (const char* name : {"instantaneous", "interval_average"}) {
    EXPECT_EQ(ap::rateSamplesName(ap::rateSamplesFromName(name)), name);
  }
  try {
    ap::rateSamplesFromName("average");
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("instantaneous interval_average"), std::string::npos);
  }
}

// A quadratic rate is recovered exactly (to round-off) from its exact means over four uneven
// intervals: the delta-angle polynomial is then the exact integral, a cubic.
TEST(AveragedRate, RecoversAQuadraticRateFromItsIntervalMeans) {
  auto rate = [](double t) { return Eigen::Vector3d(1.0 - 3.0 * t * t, 2.0 * t, 0.5 + t - t * t); };
  // Exact mean of the quadratic over [a, b] (Simpson's rule is exact for it).
  auto mean = [&rate](double a, double b) -> Eigen::Vector3d {
    return (rate(a) + 4.0 * rate(0.5 * (a + b)) + rate(b)) / 6.0;
  };
  ap::RateWindow window;
  const double stamps[] = {0.0, 0.3, 0.35, 0.9};
  window.push({stamps[0], Eigen::Vector3d::Constant(1e3)});  // its interval precedes the window
  for (int j = 1; j < 4; ++j) window.push({stamps[j], mean(stamps[j - 1], stamps[j])});
  for (double t : {0.0, 0.1, 0.33, 0.6, 0.9}) {
    EXPECT_LE((window.averagedRate(t) - rate(t)).norm(), 1e-12) << "t = " << t;
  }
}

// exp on averaged samples: the sample closing an interval carries that interval's rate, so a
// piecewise-constant rate is integrated exactly.
TEST(IntervalAverage, ExpIsExactOnPiecewiseConstantRates) {
  const Eigen::Vector3d w1(0, 0, 1.0), w2(2.0, 0, 0);
  ap::KinematicConfig config = configFor(Integrator::Exp, RateSamples::IntervalAverage);
  config.initial_q_WB = Eigen::Quaterniond::Identity();
  config.time_policy.max_dt = 10.0;
  ap::KinematicPropagator propagator(config);
  propagator.addSample(0.0, w2);  // the anchor's rate belongs to the time before it
  propagator.addSample(1.5, w1);  // w1 over (0, 1.5]
  propagator.addSample(2.0, w2);  // w2 over (1.5, 2]
  const Eigen::Quaterniond truth(Eigen::AngleAxisd(1.5, Eigen::Vector3d::UnitZ()) *
                                 Eigen::AngleAxisd(1.0, Eigen::Vector3d::UnitX()));
  EXPECT_ROTATION_NEAR(propagator.orientation(), truth, 4 * std::numeric_limits<double>::epsilon());
}

// The mean of a constant rate is the rate: exp, exp2 and cf4 stay exact on uneven stamps.
TEST(IntervalAverage, LieGroupMethodsIntegrateAConstantRateExactly) {
  const Eigen::Vector3d w(-0.4, 3.0, 1.5);
  const double angle = w.norm();
  for (Integrator method :
       integrator_cases::methodsKeeping(ap::Model::Kinematic, ap::keeps::kConstantRate)) {
    ap::KinematicConfig config = configFor(method, RateSamples::IntervalAverage);
    config.initial_q_WB = Eigen::Quaterniond::Identity();
    ap::KinematicPropagator propagator(config);
    double t = 0.0;
    for (int k = 0; k < 40; ++k) {
      propagator.addSample(t, w);
      t += 0.01 + 0.02 * ((k * 7919) % 13) / 13.0;
    }
    const double T = propagator.time();
    const Eigen::Quaterniond truth(Eigen::AngleAxisd(angle * T, w.normalized()));
    EXPECT_ROTATION_NEAR(propagator.orientation(), truth, 1e-13) << ap::integratorName(method);
  }
}

class AveragedConingOrder : public ::testing::TestWithParam<Integrator> {};

// Measured orders on averaged samples: the mean carries the rotation angle exactly, so euler
// and exp are second order on coning; the two-sample coning correction (exp2) and rk4 on the
// linear rate of two means are third order; cf4 on the delta-angle cubic is fourth order.
TEST_P(AveragedConingOrder, ErrorFallsAtTheDeclaredOrder) {
  const Integrator method = GetParam();
  const int p = ap::integratorInfo(method).averaged_order;
  ASSERT_GT(p, 0) << ap::integratorName(method) << " declares no order on averaged samples";
  const double min_order = p - integrator_cases::kOrderSlack;
  std::vector<double> errors;
  for (double rate : {100.0, 200.0, 400.0}) {
    StreamOptions o;
    o.kind = RateSamples::IntervalAverage;
    o.rate_hz = rate;
    errors.push_back(coningError(method, o));
  }
  for (std::size_t i = 1; i < errors.size(); ++i) {
    EXPECT_GE(std::log2(errors[i - 1] / errors[i]), min_order)
        << ap::integratorName(method) << ": " << errors[i - 1] << " -> " << errors[i];
  }
}

INSTANTIATE_TEST_SUITE_P(Kinematic, AveragedConingOrder,
                         ::testing::ValuesIn(ap::integratorsFor(ap::Model::Kinematic)),
                         integrator_cases::MethodName());

// At 200 Hz cf4 on averaged samples is within 2x of cf4 on point samples of the same motion.
TEST(IntervalAverage, Cf4MatchesPointSamplesAt200Hz) {
  StreamOptions point;
  StreamOptions averaged;
  averaged.kind = RateSamples::IntervalAverage;
  const double on_points = coningError(Integrator::Cf4, point);
  const double on_means = coningError(Integrator::Cf4, averaged);
  EXPECT_LE(on_means, 2.0 * on_points) << on_means << " vs " << on_points;
  // Without the delta-angle fit (means taken as point samples) it is first order: far worse.
  ap::KinematicConfig naive = configFor(Integrator::Cf4, RateSamples::Instantaneous);
  EXPECT_GE(pathError(naive, coningStream(averaged)), 1000.0 * on_means);
}

// cf4 on averaged samples stays fourth order on stamps jittered by up to +-30 % of a period
// (exact stamps: the uneven grid is real, not noise).
TEST(IntervalAverage, Cf4FourthOrderOnUnevenStamps) {
  const ConingMotion cone;
  auto rate = [&cone](double t) { return cone.bodyRate(t); };
  std::vector<double> errors;
  for (double hz : {100.0, 200.0, 400.0}) {
    std::vector<Sample> samples;
    double previous = -1.0 / hz;
    const int n = static_cast<int>(10.0 * hz);
    for (int k = 0; k <= n; ++k) {
      const double t = (k + (k == 0 ? 0.0 : 0.3 * std::sin(12.9898 * k))) / hz;
      samples.push_back({t, intervalMean(rate, previous, t)});
      previous = t;
    }
    errors.push_back(pathError(configFor(Integrator::Cf4, RateSamples::IntervalAverage), samples));
  }
  EXPECT_GE(errors[0] / errors[1], 12.0) << errors[0] << " -> " << errors[1];
  EXPECT_GE(errors[1] / errors[2], 12.0) << errors[1] << " -> " << errors[2];
}

// Property: on receipt-jittered streams (1 ms RMS at 400 Hz: 40 % of a period, so stamps come
// near-coincident and out of order) the default never does worse than 1.5x the best of the
// low-order methods on the same stream, and no method goes beyond 0.1 rad.
TEST(Jitter, DefaultNeverAmplifiesStampNoise) {
  for (RateSamples kind : {RateSamples::Instantaneous, RateSamples::IntervalAverage}) {
    for (std::uint64_t seed = 1; seed <= 12; ++seed) {
      StreamOptions o;
      o.kind = kind;
      o.rate_hz = 400.0;
      o.duration = 10.0;
      o.jitter = 1e-3;
      o.seed = seed;
      const auto samples = coningStream(o);
      double best = std::numeric_limits<double>::infinity();
      for (Integrator m : {Integrator::Euler, Integrator::Exp2, Integrator::Rk4}) {
        const double e = pathError(configFor(m, kind), samples);
        EXPECT_LE(e, 0.1) << ap::integratorName(m);
        best = std::min(best, e);
      }
      const double by_default = pathError(configFor(Integrator::Auto, kind), samples);
      EXPECT_LE(by_default, 1.5 * best)
          << ap::rateSamplesName(kind) << " seed " << seed << ": " << by_default << " vs " << best;
      EXPECT_LE(pathError(configFor(Integrator::Exp, kind), samples), 0.1);
    }
  }
}

// Stamps a nanosecond apart: the cubic through them would amplify rate differences by 1e6;
// the guard falls back to the linear interpolant and the state stays finite and close.
TEST(Jitter, NearCoincidentStampsStayBounded) {
  for (RateSamples kind : {RateSamples::Instantaneous, RateSamples::IntervalAverage}) {
    const ConingMotion cone;
    ap::KinematicPropagator propagator(configFor(Integrator::Cf4, kind));
    for (int k = 0; k <= 2000; ++k) {
      const double t = k / 200.0;
      propagator.addSample(t, cone.bodyRate(t));
      // A second sample 1 ns later with the rate of 2.5 ms later: a stamp error of 2.5 ms.
      propagator.addSample(t + 1e-9, cone.bodyRate(t + 2.5e-3));
      ASSERT_TRUE(propagator.orientation().coeffs().allFinite());
    }
    EXPECT_LE(ap::rotationAngle(propagator.orientation(), cone.attitude(propagator.time())), 0.01)
        << ap::rateSamplesName(kind);
  }
}

// Averaged samples with 5 % lost: the rotation over a lost period is filled from the
// polynomial fitted across the gap.
TEST(GapFill, RecoversTheRotationOfLostAveragedSamples) {
  StreamOptions o;
  o.kind = RateSamples::IntervalAverage;
  o.drop = 0.05;
  o.seed = 7;
  const auto samples = coningStream(o);
  ap::KinematicConfig with = configFor(Integrator::Cf4, RateSamples::IntervalAverage);
  ap::KinematicConfig without = with;
  without.max_gap_fill = 0;
  const double filled = pathError(with, samples);
  const double lost = pathError(without, samples);
  EXPECT_GE(lost / filled, 100.0) << lost << " -> " << filled;
  // Every lost sample was filled in: the count equals what the stream lacks.
  ap::KinematicPropagator propagator(with);
  for (const Sample& s : samples) propagator.addSample(s.stamp, s.w_B);
  EXPECT_EQ(propagator.filledSamples() + samples.size(), 4001u);
}

// A gap of more lost samples than max_gap_fill is integrated as one interval (or held beyond
// max_dt), never filled.
TEST(GapFill, LongGapsAreNotFilled) {
  ap::KinematicConfig config = configFor(Integrator::Cf4, RateSamples::IntervalAverage);
  config.max_gap_fill = 2;
  ap::KinematicPropagator propagator(config);
  const Eigen::Vector3d w(0.0, 0.0, 1.0);
  for (int k = 0; k <= 10; ++k) propagator.addSample(0.01 * k, w);
  propagator.addSample(0.13, w);  // two lost: filled
  EXPECT_EQ(propagator.filledSamples(), 2u);
  propagator.addSample(0.17, w);  // three lost: not filled
  EXPECT_EQ(propagator.filledSamples(), 2u);
  propagator.addSample(0.195, w);  // 2.5 periods: not a whole number, not filled
  EXPECT_EQ(propagator.filledSamples(), 2u);
}

// A loss is filled only where the stamps prove it: the last intervals within kRegularIntervals
// (10 %) of their median. Intervals 9 % off the period still prove a loss of one sample two
// periods on; 11 % off, the same interval is taken for jitter and not filled.
TEST(GapFill, OnlyWhereTheStampsProveTheLoss) {
  for (const double spread : {0.09, 0.11}) {
    ap::KinematicPropagator propagator(configFor(Integrator::Cf4, RateSamples::IntervalAverage));
    const Eigen::Vector3d w(0.0, 0.0, 1.0);
    double t = 0.0;
    propagator.addSample(t, w);
    for (int k = 1; k <= 5; ++k) {
      t += 0.01 * (k == 3 ? 1.0 + spread : 1.0);
      propagator.addSample(t, w);
    }
    propagator.addSample(t + 0.02, w);  // one lost, two periods on
    EXPECT_EQ(propagator.filledSamples(), spread < 0.1 ? 1u : 0u) << spread;
  }
}

// Receipt stamps of a 180 Hz stream of means scattered by a third of the period: their long
// intervals (before a short one) come close to whole numbers of periods by chance; none is a
// loss, none is filled, and the rotation of a constant rate is kept exactly.
TEST(GapFill, JitterIsNeverFilled) {
  ap::KinematicPropagator propagator(configFor(Integrator::Exp, RateSamples::IntervalAverage));
  const Eigen::Vector3d w(0.3, -0.2, 1.0);
  std::uint64_t state = 11;
  double last = 0.0;
  for (int k = 0; k < 20000; ++k) {
    const double t = std::max(k / 180.0 + 0.33 / 180.0 * normalRandom(state), last + 1e-6);
    propagator.addSample(t, w);
    last = t;
  }
  EXPECT_EQ(propagator.filledSamples(), 0u);
}

// Dropouts are relative to the stream: with three intervals known, a silence of more than
// kGapPeriods (5.5) nominal periods is held (HeldGap: the state at the new stamp is the one
// before the silence), a silence of 5.4 periods is bridged (integrated across); with two
// intervals known, no period is known yet and the silence is bridged. max_dt (1 s) is far.
TEST(Dropouts, ASilenceOfMoreThanFiveAndAHalfPeriodsIsHeld) {
  for (const int known : {2, 3}) {
    for (const double periods : {5.4, 5.6}) {
      ap::KinematicPropagator propagator(configFor(Integrator::Exp, RateSamples::Instantaneous));
      const Eigen::Vector3d w(0.0, 0.0, 1.0);
      const Eigen::Quaterniond q0 = ConingMotion().attitude(0.0);
      double t = 0.0;
      for (int k = 0; k <= known; ++k, t += 0.01) propagator.addSample(t, w);
      t -= 0.01;
      const double after = t + periods * 0.01;
      const bool held = known >= 3 && periods > ap::kGapPeriods;
      EXPECT_EQ(propagator.addSample(after, w),
                held ? ap::StampOutcome::HeldGap : ap::StampOutcome::Advanced)
          << known << " intervals, " << periods << " periods";
      // exp holds the rate of the sample opening the interval: a constant rate exactly.
      const double turned = held ? t : after;
      EXPECT_LT(ap::rotationAngle(propagator.orientation(),
                                  q0 * ap::expMap(Eigen::Vector3d(0.0, 0.0, turned))),
                1e-12)
          << known << " intervals, " << periods << " periods";
    }
  }
}

// After a dropout the stream's period is learned afresh: a sensor that resumes at a tenth of its
// rate loses the dropout only, and its new intervals (ten old periods each) are integrated.
TEST(Dropouts, ThePeriodIsLearnedAfreshAfterOne) {
  ap::KinematicPropagator propagator(configFor(Integrator::Exp, RateSamples::Instantaneous));
  const Eigen::Vector3d w(0.0, 0.0, 1.0);
  double t = 0.0;
  for (int k = 0; k < 50; ++k, t += 0.01) propagator.addSample(t, w);
  EXPECT_EQ(propagator.addSample(t + 0.2, w), ap::StampOutcome::HeldGap);
  t += 0.2;
  for (int k = 1; k <= 10; ++k) {
    EXPECT_EQ(propagator.addSample(t + 0.1 * k, w), ap::StampOutcome::Advanced) << k;
  }
}

// The quadrotor's case (47 Hz, a dropout of 0.999 s, under max_dt): held, not integrated
// across with the rate after it; the intervals after the dropout are learned afresh.
TEST(Dropouts, ASecondLongDropoutUnderMaxDtIsHeld) {
  ap::KinematicPropagator propagator(configFor(Integrator::Cf4, RateSamples::Instantaneous));
  const Eigen::Vector3d w(0.0, 0.0, 0.5);
  double t = 0.0;
  for (int k = 0; k < 100; ++k, t += 1.0 / 47) propagator.addSample(t, w);
  const Eigen::Quaterniond before = propagator.orientation();
  EXPECT_EQ(propagator.addSample(t - 1.0 / 47 + 0.999, Eigen::Vector3d(0.0, 0.0, 5.0)),
            ap::StampOutcome::HeldGap);
  EXPECT_LT(ap::rotationAngle(propagator.orientation(), before), 1e-15);
  EXPECT_EQ(propagator.steps(), 0u);
}

namespace {

// FIFO batches (gyro_streams.h): the anchor (k = 0) comes alone with its exact stamp, as in
// coningStream, then reads of `batch` samples stamped at receipt.
using gyro_streams::Fifo;

std::vector<Sample> fifoStream(double hz, int batch, Fifo form, double sigma, std::uint64_t seed,
                               double duration) {
  const ConingMotion cone;
  const std::vector<double> stamps =
      gyro_streams::fifoStamps(hz, batch, form, sigma, seed, std::lround(duration * hz));
  std::vector<Sample> samples;
  for (std::size_t k = 0; k < stamps.size(); ++k) {
    samples.push_back({stamps[k], cone.bodyRate(k / hz)});
  }
  return samples;
}

struct FifoRun {
  double worst = 0.0;    // along the whole path
  double settled = 0.0;  // of the rotation from the state after `settle` samples on
  std::size_t advanced = 0;
  std::uint64_t batch = 0, restarts = 0, rejected = 0;
};

// The error once settled is that of the rotation since the state after `settle` samples: the
// start-up's error (the first batch of repeated stamps before any period is known) stays in
// the attitude, and is measured along the whole path.
FifoRun runFifo(const std::vector<Sample>& samples, std::size_t settle) {
  const ConingMotion cone;
  ap::KinematicConfig config;
  config.initial_q_WB = cone.attitude(0.0);
  config.stamp_filter = ap::StampFilter::SensorClock;
  ap::KinematicPropagator propagator(config);
  FifoRun run;
  Eigen::Quaterniond q_settled = Eigen::Quaterniond::Identity(), truth_settled = q_settled;
  for (std::size_t k = 0; k < samples.size(); ++k) {
    const ap::StampOutcome outcome = propagator.addSample(samples[k].stamp, samples[k].w_B);
    if (outcome == ap::StampOutcome::Advanced) ++run.advanced;
    if (k < kStartUpSamples) continue;
    const Eigen::Quaterniond q = propagator.orientation(), truth = cone.attitude(propagator.time());
    run.worst = std::max(run.worst, ap::rotationAngle(q, truth));
    if (k == settle) {
      q_settled = q;
      truth_settled = truth;
    } else if (k > settle) {
      run.settled = std::max(run.settled, ap::rotationAngle(q_settled.conjugate() * q,
                                                            truth_settled.conjugate() * truth));
    }
  }
  run.batch = propagator.stampFilter()->batchSize();
  run.restarts = propagator.stampFilter()->restarts();
  run.rejected = propagator.stampFilter()->rejected();
  return run;
}

}  // namespace

// FIFO batches of 10, 20 and 24 at 200 and 400 Hz, stamps repeated or spaced by the period, 0.2 ms
// of latency jitter per read: every sample is integrated (none stale), the filter neither
// rejects nor restarts at the batch boundaries, and once settled (the filter's memory, 1000
// samples) the error is within 2 sqrt(N) of the per-sample stream's with the same latency
// distribution: a batch is one latency draw, so the line rests on N times fewer.
TEST(FifoBatches, EverySampleIntegratedAndTheErrorWithinTwoRootNOfPerSampleJitter) {
  const double sigma = 2e-4;
  for (double hz : {200.0, 400.0}) {
    for (int batch : {10, 20, 24}) {
      for (Fifo form : {Fifo::Repeated, Fifo::Spaced}) {
        const char* name = form == Fifo::Repeated ? "repeated" : "spaced";
        double log_ratio = 0.0;
        const int seeds = 3;
        for (std::uint64_t seed = 1; seed <= seeds; ++seed) {
          const auto per_sample = fifoStream(hz, 1, form, sigma, seed, 30.0);
          const auto fifo = fifoStream(hz, batch, form, sigma, seed, 30.0);
          const FifoRun alone = runFifo(per_sample, 1000), batched = runFifo(fifo, 1000);
          EXPECT_EQ(batched.advanced, fifo.size() - 1) << hz << " Hz, " << batch << " " << name;
          EXPECT_EQ(batched.batch, static_cast<std::uint64_t>(batch));
          EXPECT_EQ(batched.restarts, 0u) << hz << " Hz, " << batch << " " << name;
          EXPECT_EQ(batched.rejected, 0u) << hz << " Hz, " << batch << " " << name;
          EXPECT_EQ(alone.batch, 1u);
          log_ratio += std::log(batched.settled / alone.settled);
          std::printf(
              "[ fifo     ] %3.0f Hz batch %2d %-8s seed %d: settled %.3g vs %.3g (x%.2f), "
              "whole path %.3g vs %.3g\n",
              hz, batch, name, static_cast<int>(seed), batched.settled, alone.settled,
              batched.settled / alone.settled, batched.worst, alone.worst);
        }
        EXPECT_LE(std::exp(log_ratio / seeds), 2.0 * std::sqrt(batch))
            << hz << " Hz, " << batch << " " << name;
      }
    }
  }
}
