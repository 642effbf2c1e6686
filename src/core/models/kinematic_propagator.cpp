#include "attitude_propagator/models/kinematic_propagator.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <stdexcept>
#include <string>

#include "attitude_propagator/limits.h"
#include "attitude_propagator/models/sample_door.h"
#include "attitude_propagator/numerics/quaternion.h"

namespace attitude_propagator {

namespace {

Integrator resolveKinematic(Integrator requested) {
  if (requested == Integrator::Auto) return autoIntegrator(Model::Kinematic, false);
  if (!supportsKinematic(requested)) {
    throw std::invalid_argument("integrator: '" + integratorName(requested) +
                                "' does not apply to the kinematic model; accepted: auto " +
                                joinNames(integratorNames(integratorsFor(Model::Kinematic))));
  }
  return requested;
}

void checkPolicy(const TimePolicy& policy) {
  if (!(std::isfinite(policy.max_dt) && policy.max_dt > 0.0)) {
    throw std::invalid_argument("max_dt: must be a positive number of seconds");
  }
  if (!(std::isfinite(policy.backward_jump) && policy.backward_jump > 0.0)) {
    throw std::invalid_argument("backward jump threshold: must be a positive number of seconds");
  }
}

/// q normalised at any finite scale (safeNormalized), or std::invalid_argument.
Eigen::Quaterniond checkedUnit(const Eigen::Quaterniond& q, const std::string& what) {
  const std::optional<Eigen::Quaterniond> unit = safeNormalized(q);
  if (!unit) {
    throw std::invalid_argument(what + ": must be a finite, non-zero quaternion [x, y, z, w]");
  }
  return *unit;
}

// A gap is taken for lost samples only when it is this close to a whole number of periods.
constexpr double kWholePeriods = 0.25;
// ... and only on a stream whose stamps prove it: its last intervals all within this fraction
// of their median. Receipt stamps scattered by more than that make a whole number of periods
// out of jitter (a long interval before a short one), not out of a loss.
constexpr double kRegularIntervals = 0.1;
// The mean period: a plain mean of the first intervals since the anchor, then an exponential
// one over about this many.
constexpr std::uint64_t kMeanIntervals = 16;
// Intervals shorter than this (s) are stamps bunched together, not a stream's period (1 MHz).
constexpr double kShortestInterval = 1e-6;

// Mean over [a, b] of s^p, p = 0..k-1: (b^(p+1) - a^(p+1)) / ((p + 1)(b - a)).
Eigen::RowVector4d powerMeans(double a, double b, int k) {
  Eigen::RowVector4d means = Eigen::RowVector4d::Zero();
  double pa = a, pb = b;
  for (int p = 0; p < k; ++p, pa *= a, pb *= b) means[p] = (pb - pa) / ((p + 1) * (b - a));
  return means;
}

// Means of the rate over the lost intervals (t_last + (j-1) h, t_last + j h], j = 1..lost, from
// the polynomial w(s), s = (t - t_last)/h, whose means over the window's newest intervals and
// over the new sample's interval (t - h, t] are the samples' rates: interpolation across the
// gap, of degree up to three (one condition per known mean).
void fillMeans(const RateWindow& window, const RateSample& next, double h, int lost,
               std::array<Eigen::Vector3d, 8>& means) {
  using Conditions = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 4, 4>;
  using Rates = Eigen::Matrix<double, Eigen::Dynamic, 3, 0, 4, 3>;
  const std::size_t known = std::min<std::size_t>(window.size() - 1, 3);
  const int k = static_cast<int>(known) + 1;
  const double t_last = window.newest().t;
  Conditions m(k, k);
  Rates w(k, 3);
  for (std::size_t j = 0; j < known; ++j) {
    const RateSample& close = window[window.size() - 1 - j];
    const RateSample& open = window[window.size() - 2 - j];
    m.row(j) = powerMeans((open.t - t_last) / h, (close.t - t_last) / h, k).head(k);
    w.row(j) = close.w_B.transpose();
  }
  m.row(k - 1) = powerMeans(lost, lost + 1.0, k).head(k);
  w.row(k - 1) = next.w_B.transpose();
  const Rates coefficients = m.colPivHouseholderQr().solve(w);
  for (int j = 0; j < lost; ++j) {
    means[j] = (powerMeans(j, j + 1.0, k).head(k) * coefficients).transpose();
  }
}

}  // namespace

KinematicPropagator::KinematicPropagator(const KinematicConfig& config)
    : automatic_(config.integrator == Integrator::Auto),
      auto_rule_(config.rate_samples, config.stamp_filter != StampFilter::None),
      integrator_(resolveKinematic(config.integrator)),
      policy_(config.time_policy),
      initial_q_WB_(checkedUnit(config.initial_q_WB, "initial_orientation")),
      q_WB_(initial_q_WB_),
      anchor_q_WB_(initial_q_WB_),
      rate_samples_(config.rate_samples),
      max_gap_fill_(std::clamp(config.max_gap_fill, 0, kMaxGapFill)),
      stamp_filter_(config.stamp_filter),
      restamp_(clock_.memory()),
      average_stamp_(config.average_stamp),
      interval_ends_(config.average_stamp) {
  checkPolicy(policy_);
  if (average_stamp_ != AverageStamp::End && rate_samples_ != RateSamples::IntervalAverage) {
    throw std::invalid_argument("average_stamp: '" + averageStampName(average_stamp_) +
                                "' needs rate_samples: interval_average (a point sample has no "
                                "interval)");
  }
}

StampOutcome KinematicPropagator::addSample(double t, const Eigen::Vector3d& w_B) {
  // The door first (sample_door.h): what passes it is finite and in range all the way down.
  if (const auto refused = refusedSample(t, w_B, doorBound(false))) return *refused;
  if (average_stamp_ == AverageStamp::End) return addFiltered(t, w_B);
  // A start- or mid-stamped mean waits for the next sample, which shows where it ends.
  const IntervalEnds::Pushed pushed = interval_ends_.push({t, w_B});
  if (pushed.stale) return StampOutcome::DroppedStale;
  return pushed.ended ? addFiltered(pushed.ended->t, pushed.ended->w_B) : StampOutcome::Waiting;
}

StampOutcome KinematicPropagator::addFiltered(double t, const Eigen::Vector3d& w_B) {
  if (stamp_filter_ == StampFilter::None) return addStamped(t, w_B);
  const SensorClockFilter::Result clock = clock_.filter(t);
  const StampOutcome outcome = addStamped(clock.t, w_B);
  restamp(clock, w_B, outcome);
  return outcome;
}

// The stamp filter's later stamps for the samples integrated before turn the whole path since
// the anchor (the anchor's state too, for the start-up re-integration from it): a rotation on
// the world side commutes with every body-side step that follows.
void KinematicPropagator::restamp(const SensorClockFilter::Result& clock,
                                  const Eigen::Vector3d& w_B, StampOutcome outcome) {
  const bool anchored = outcome == StampOutcome::Anchored || outcome == StampOutcome::HeldGap;
  if (!anchored && outcome != StampOutcome::Advanced) {  // not integrated
    if (clock.verdict == SensorClockFilter::Verdict::Restarted ||
        clock.verdict == SensorClockFilter::Verdict::Unfiltered) {
      restamp_.reset();
    }
    return;
  }
  const Eigen::Quaterniond turn = expMap(restamp_.add(clock_, clock, w_B, q_WB_, anchored));
  q_WB_ = (turn * q_WB_).normalized();
  anchor_q_WB_ = (turn * anchor_q_WB_).normalized();
}

StampOutcome KinematicPropagator::addStamped(double t, const Eigen::Vector3d& w_B) {
  if (!anchored_) {
    anchor(t, w_B);
    return StampOutcome::Anchored;
  }
  switch (classifyStamp(time(), t, policy_)) {
    case StampClass::Stale:
      return StampOutcome::DroppedStale;
    case StampClass::Gap:
      anchor(t, w_B);  // the orientation is held across the gap
      return StampOutcome::HeldGap;
    case StampClass::Forward:
      break;
  }
  if (dropout(t - time())) {
    anchor(t, w_B);  // held, as across a gap longer than max_dt
    return StampOutcome::HeldGap;
  }
  if (rate_samples_ == RateSamples::IntervalAverage && max_gap_fill_ > 0) {
    return fillAndIntegrate({t, w_B});
  }
  return integrate({t, w_B});
}

void KinematicPropagator::reset() {
  interval_ends_.clear();
  auto_rule_.reset();
  if (automatic_) integrator_ = auto_rule_.choice();
  q_WB_ = initial_q_WB_;
  anchor_q_WB_ = initial_q_WB_;
  window_.clear();
  samples_since_anchor_ = 0;
  anchored_ = false;
  norm_error_ = 0.0;
  steps_ = 0;
  clock_.reset();
  restamp_.reset();
}

void KinematicPropagator::correctOrientation(const Eigen::Quaterniond& q_WB) {
  const std::optional<Eigen::Quaterniond> unit = safeNormalized(q_WB);
  if (!anchored_ || !unit) return;
  // A rotation on the world side commutes with every body-side step from the anchor on, so the
  // anchor turned by it re-integrates to the corrected orientation.
  const Eigen::Quaterniond fix_turn = *unit * q_WB_.conjugate();
  anchor_q_WB_ = (fix_turn * anchor_q_WB_).normalized();
  q_WB_ = *unit;
}

void KinematicPropagator::setState(double t, const Eigen::Quaterniond& q_WB,
                                   const Eigen::Vector3d& w_B) {
  if (!std::isfinite(t) || !w_B.allFinite()) {
    throw std::invalid_argument("set_state: stamp and angular velocity must be finite");
  }
  if (!(w_B.norm() <= kMaxBodyRate)) {
    throw std::invalid_argument("set_state: angular velocity above kMaxBodyRate = 1e5 rad/s");
  }
  q_WB_ = checkedUnit(q_WB, "set_state orientation");
  interval_ends_.clear();  // a mean waiting from before the pinned state is not applied after it
  anchor(t, w_B);
}

void KinematicPropagator::anchor(double t, const Eigen::Vector3d& w_B) {
  window_.clear();
  window_.push({t, w_B});
  anchor_q_WB_ = q_WB_;
  restamp_.reset();  // the anchor's stamp is the state's time: the history starts again
  auto_rule_.restart();
  samples_since_anchor_ = 1;
  anchored_ = true;
  steps_ = 0;
  interval_count_ = 0;
  mean_interval_ = 0.0;
  mean_count_ = 0;
}

// The step is committed only when finite: a finite rate can still overflow (|w| h beyond the
// double range), and the state must never become NaN. The window is restored otherwise.
StampOutcome KinematicPropagator::integrate(const RateSample& sample) {
  if (automatic_) integrator_ = auto_rule_.step(sample.t - time(), sample.w_B, filling_);
  const bool evicted = window_.push(sample);
  const IntegratorInfo& method = integratorInfo(integrator_);
  const bool restart = method.restart_from_anchor &&
                       samples_since_anchor_ + 1 == static_cast<std::uint64_t>(method.samples);
  const Eigen::Quaterniond q =
      restart ? restartFromAnchor(window_)
              : method.kinematic_step(q_WB_, window_, window_.size() - 2, rate_samples_);
  const double n = q.norm();
  if (!std::isfinite(n) || n == 0.0) {
    window_.undoPush(evicted);
    return StampOutcome::RejectedNonFinite;
  }
  ++samples_since_anchor_;
  ++steps_;
  norm_error_ = n - 1.0;
  q_WB_ = Eigen::Quaterniond(q.coeffs() / n);
  rememberInterval(sample.t - window_[window_.size() - 2].t);
  return StampOutcome::Advanced;
}

void KinematicPropagator::rememberInterval(double interval) {
  intervals_[interval_count_++ % intervals_.size()] = interval;
  // The mean period the dropouts are judged by: bursts and pauses of receipt stamps average
  // out in it where a median of a few would follow a burst. Stamps bunched by a FIFO read
  // before the stamp filter knows the period are not periods of the stream.
  if (interval < kShortestInterval) return;
  mean_count_ = std::min<std::uint64_t>(mean_count_ + 1, kMeanIntervals);
  mean_interval_ += (interval - mean_interval_) / static_cast<double>(mean_count_);
}

std::optional<KinematicPropagator::NominalPeriod> KinematicPropagator::nominalPeriod() const {
  const std::size_t n = std::min(interval_count_, intervals_.size());
  if (n < 3) return std::nullopt;
  std::array<double, 5> sorted = intervals_;
  std::sort(sorted.begin(), sorted.begin() + n);
  const double median = sorted[n / 2];
  const bool regular = sorted[0] >= (1.0 - kRegularIntervals) * median &&
                       sorted[n - 1] <= (1.0 + kRegularIntervals) * median;
  return NominalPeriod{median, regular};
}

// A silence of more than kGapPeriods mean periods: a dropout, held rather than bridged.
bool KinematicPropagator::dropout(double interval) const {
  return mean_count_ >= 3 && interval > kGapPeriods * mean_interval_;
}

// Samples lost before one that arrives `interval` after the newest: m - 1 when the interval is
// within kWholePeriods of m nominal periods (the median of the last intervals, which all lie
// within kRegularIntervals of it: the stamps prove the loss), m >= 2, and m - 1 <= max_gap_fill;
// 0 otherwise (no drop, an irregular gap or stream, or too long a gap).
int KinematicPropagator::lostSamples(double interval) const {
  if (interval_count_ < 3) return 0;
  const double shortest = *std::min_element(
      intervals_.begin(), intervals_.begin() + std::min(interval_count_, intervals_.size()));
  if (interval < 1.5 * shortest) return 0;  // the common case: no median needed
  const std::optional<NominalPeriod> nominal = nominalPeriod();
  if (!nominal->regular) return 0;
  const double periods = interval / nominal->period;
  const double m = std::round(periods);
  if (m < 2.0 || m > max_gap_fill_ + 1.0 || std::abs(periods - m) > kWholePeriods) return 0;
  return static_cast<int>(m) - 1;
}

// Interval-averaged samples: a sample after lost ones holds the mean over its own period only,
// so the rotation over the lost periods is filled in first, from the means of the polynomial
// fitted across the gap, as samples of their own.
StampOutcome KinematicPropagator::fillAndIntegrate(const RateSample& sample) {
  const double t_last = time();
  const int lost = lostSamples(sample.t - t_last);
  if (lost > 0) {
    const double h = (sample.t - t_last) / (lost + 1);
    std::array<Eigen::Vector3d, 8> means;
    fillMeans(window_, sample, h, lost, means);
    for (int j = 0; j < lost; ++j) {
      if (!means[j].allFinite()) return integrate(sample);
      filling_ = true;
      const StampOutcome filled = integrate({t_last + (j + 1) * h, means[j]});
      filling_ = false;
      if (filled != StampOutcome::Advanced) break;
      ++filled_samples_;
    }
  }
  return integrate(sample);
}

// The start-up hook of a method whose row asks for it (cf4): the first intervals after an
// anchor had fewer samples than its interpolant needs, so it ran at lower order there; the
// constant error that leaves would dominate the higher-order tail (cf4: global
// order about 3.2). Once the window holds the samples it needs, integrate again from the anchor
// across all of them with the full interpolant.
Eigen::Quaterniond KinematicPropagator::restartFromAnchor(const RateWindow& window) const {
  const KinematicStepFunction step = integratorInfo(integrator_).kinematic_step;
  Eigen::Quaterniond q = anchor_q_WB_;
  for (std::size_t i = 0; i + 2 < window.size(); ++i) {
    q = step(q, window, i, rate_samples_).normalized();
  }
  return step(q, window, window.size() - 2, rate_samples_);
}

}  // namespace attitude_propagator
