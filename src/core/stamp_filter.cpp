#include "attitude_propagator/stamp_filter.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace attitude_propagator {

namespace {

// Stamps are never trusted to better than this fraction of a period: an ideal simulated clock
// has zero residuals, and round-off must not look like an outlier there.
constexpr double kJitterFloor = 1e-3;
// More lost periods than this between two stamps is no longer a drop but a restart.
constexpr double kMaxSkip = 1e6;

}  // namespace

StampFilter stampFilterFromName(const std::string& name) {
  if (name == "none") return StampFilter::None;
  if (name == "sensor_clock") return StampFilter::SensorClock;
  throw std::invalid_argument("stamp_filter: unknown value '" + name +
                              "'; accepted: none sensor_clock");
}

std::string stampFilterName(StampFilter filter) {
  return filter == StampFilter::SensorClock ? "sensor_clock" : "none";
}

SensorClockFilter::SensorClockFilter(const Options& options)
    : options_(options), forget_(1.0 - 1.0 / options.memory) {
  if (!(options.memory > 1.0) || !(options.reject_sigmas > 0.0) || options.restart_after < 1 ||
      !(options.restart_jump > 0.0)) {
    throw std::invalid_argument(
        "SensorClockFilter: memory > 1, reject_sigmas > 0, "
        "restart_after >= 1 and restart_jump > 0 required");
  }
}

void SensorClockFilter::reset() {
  samples_ = 0;
  slope_ = 0.0;
  recent_count_ = 0;
}

double SensorClockFilter::jitter() const { return std::sqrt(variance_); }

double SensorClockFilter::after(double t) {
  return std::nextafter(t, std::numeric_limits<double>::infinity());
}

double SensorClockFilter::lineMinus(std::uint64_t index, double t) const {
  // base_t_ - t is exact for nearby stamps; the line's part is relative to base_t_.
  return (base_t_ - t) +
         (origin_t_ + slope_ * (static_cast<double>(index) - static_cast<double>(index_)));
}

SensorClockFilter::Result SensorClockFilter::filter(double t_receipt) {
  recent_[recent_count_++ % recent_.size()] = t_receipt;
  if (samples_ == 0) {
    start(t_receipt);
    return {t_receipt, Verdict::Restarted, 0};
  }
  // Since the line's stamp at the newest index; t_receipt - base_t_ is exact, and origin_t_ is
  // kept relative to base_t_ so that epoch-sized stamps lose nothing step after step.
  const double dt = (t_receipt - base_t_) - origin_t_;
  // Index advance: the nearest whole number of periods, at least one (the sensor never repeats
  // an index, so a stamp that arrives early still belongs to the next sample).
  const double periods = slope_ > 0.0 ? std::round(dt / slope_) : 1.0;
  if (std::abs(dt) > options_.restart_jump + std::max(periods, 1.0) * slope_ ||
      periods > kMaxSkip) {
    ++restarts_;
    start(t_receipt);
    return {t_receipt, Verdict::Restarted, 0};
  }
  const std::uint64_t m = periods > 1.0 ? static_cast<std::uint64_t>(periods) : 1;
  const double predicted = static_cast<double>(m) * slope_;
  const double r = dt - predicted;  // innovation
  const double sigma = std::max(jitter(), kJitterFloor * slope_);
  if (samples_ >= static_cast<std::uint64_t>(options_.warm_up) &&
      std::abs(r) > options_.reject_sigmas * sigma) {
    ++rejected_;
    if (++rejected_in_a_row_ >= options_.restart_after) return restartAfter(t_receipt);
    // Assume it is the next sample (a late stamp, not a drop) and keep the fit. An early stamp
    // (the rate went up) keeps its own: the line's would run ahead of the samples, and the
    // restart that follows would then have to go back.
    shiftOrigin(1, slope_);
    last_output_ = std::max(std::min(base_t_ + origin_t_, t_receipt), after(last_output_));
    return {last_output_, Verdict::Rejected, 0};
  }
  rejected_in_a_row_ = 0;
  skipped_in_a_row_ = m > 1 ? skipped_in_a_row_ + 1 : 0;
  if (skipped_in_a_row_ >= options_.restart_after) {  // the rate fell: a new period
    return restartAfter(t_receipt);
  }
  if (slope_ > 0.0) {
    // Forgetting average once warm; the plain mean of the first innovations before.
    const double weight = std::max(1.0 - forget_, 1.0 / static_cast<double>(samples_));
    variance_ += weight * (r * r - variance_);
  }
  missed_ += m - 1;
  shiftOrigin(m, predicted);
  add(r);
  refit();
  // The line through noisy stamps can move back by a hair while it learns; stamps must not.
  const double out = std::max(base_t_ + origin_t_, last_output_ + 0.5 * slope_);
  last_output_ = out;
  return {out, Verdict::Modelled, m - 1};
}

// A restart where the stamps went on (a new rate): the new line starts no earlier than the last
// stamp returned, so no sample after it is stale. (A jump restarts at the raw stamp: the
// engine's time policy is to see it.)
SensorClockFilter::Result SensorClockFilter::restartAfter(double t_receipt) {
  ++restarts_;
  const double t = std::max(t_receipt, after(last_output_));
  start(t);
  return {t, Verdict::Restarted, 0};
}

void SensorClockFilter::start(double t_receipt) {
  const double guess = medianRecentInterval();
  s0_ = 1.0;
  sx_ = sxx_ = sy_ = sxy_ = 0.0;
  variance_ = 0.0;
  base_t_ = t_receipt;
  origin_t_ = 0.0;
  slope_ = guess;  // 0 when unknown: the second stamp is then taken as the next sample
  index_ = 0;
  samples_ = 1;
  rejected_in_a_row_ = 0;
  skipped_in_a_row_ = 0;
  last_output_ = t_receipt;
}

// Moves the origin to index_ + steps at stamp origin_t_ + dt: x -> x - steps, y -> y - dt.
void SensorClockFilter::shiftOrigin(std::uint64_t steps, double dt) {
  const double m = static_cast<double>(steps);
  sxy_ += -m * sy_ - dt * sx_ + m * dt * s0_;
  sxx_ += -2.0 * m * sx_ + m * m * s0_;
  sx_ -= m * s0_;
  sy_ -= dt * s0_;
  index_ += steps;
  origin_t_ += dt;
}

// Older samples lose weight by the forgetting factor; the new one sits at x = 0.
void SensorClockFilter::add(double y) {
  s0_ = forget_ * s0_ + 1.0;
  sx_ *= forget_;
  sxx_ *= forget_;
  sy_ = forget_ * sy_ + y;
  sxy_ *= forget_;
  ++samples_;
}

// Weighted least squares y = a + b x; the origin then moves onto the line (a = 0).
void SensorClockFilter::refit() {
  const double det = s0_ * sxx_ - sx_ * sx_;
  if (det > 1e-12 * s0_ * sxx_) slope_ = (s0_ * sxy_ - sx_ * sy_) / det;
  const double a = (sy_ - slope_ * sx_) / s0_;
  sy_ -= a * s0_;
  sxy_ -= a * sx_;
  origin_t_ += a;
}

double SensorClockFilter::medianRecentInterval() const {
  const std::size_t n = std::min(recent_count_, recent_.size());
  if (n < 3) return slope_;
  std::array<double, 6> stamps{};
  for (std::size_t k = 0; k < n; ++k) stamps[k] = recent_[(recent_count_ - n + k) % recent_.size()];
  std::array<double, 5> intervals{};
  for (std::size_t k = 0; k + 1 < n; ++k) intervals[k] = stamps[k + 1] - stamps[k];
  std::sort(intervals.begin(), intervals.begin() + (n - 1));
  const double median = intervals[(n - 1) / 2];
  return median > 0.0 ? median : slope_;
}

RestampCorrection::RestampCorrection(double memory) : forget_(1.0 - 1.0 / memory) {
  if (!(memory > 1.0)) throw std::invalid_argument("RestampCorrection: memory > 1 required");
}

Eigen::Vector3d RestampCorrection::add(const SensorClockFilter& clock,
                                       const SensorClockFilter::Result& sample,
                                       const Eigen::Vector3d& w_B, const Eigen::Quaterniond& q_WB,
                                       bool anchor) {
  if (!started_ || sample.verdict != SensorClockFilter::Verdict::Modelled) {
    // A new line numbers the samples again, and a rejected stamp is not on the line: the
    // earlier terms stay as last corrected.
    start(clock, sample.t, w_B, q_WB, anchor);
    return Eigen::Vector3d::Zero();
  }
  // The origin moves to this sample: x -> x - m, y -> y - d; the newest sample's term, whose
  // rate difference is known now, joins at x = -m, y = -d.
  const double m = static_cast<double>(clock.index() - index_);
  const double d = sample.t - t_;
  sx_ -= m * s0_;
  sy_ -= d * s0_;
  if (count_newest_) {
    const Eigen::Vector3d g = R_WB_ * (w_B - w_B_);
    s0_ += g;
    sx_ -= m * g;
    sy_ -= d * g;
  }
  index_ = clock.index();
  t_ = sample.t;
  w_B_ = w_B;
  R_WB_ = q_WB.toRotationMatrix();
  count_newest_ = true;
  // sum e_n g_n with e_n = t_n - t_n* = y - (t*(index_) - t_) - period x, at today's line.
  const Eigen::Vector3d live = sy_ - clock.lineMinus(index_, t_) * s0_ - clock.period() * sx_;
  const Eigen::Vector3d turn = live - applied_;
  // Forgetting: the fraction 1/memory of every term stays frozen at today's line.
  s0_ *= forget_;
  sx_ *= forget_;
  sy_ *= forget_;
  applied_ = forget_ * live;
  return turn;
}

void RestampCorrection::start(const SensorClockFilter& clock, double t, const Eigen::Vector3d& w_B,
                              const Eigen::Quaterniond& q_WB, bool anchor) {
  started_ = true;
  count_newest_ = !anchor;
  index_ = clock.index();
  t_ = t;
  w_B_ = w_B;
  R_WB_ = q_WB.toRotationMatrix();
  s0_.setZero();
  sx_.setZero();
  sy_.setZero();
  applied_.setZero();
}

}  // namespace attitude_propagator
