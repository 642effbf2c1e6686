#include "attitude_propagator/numerics/auto_integrator.h"

#include <algorithm>
#include <cmath>

#include "attitude_propagator/numerics/quaternion.h"

namespace attitude_propagator {

namespace {

// An interval this far from the mean one is not jitter but a gap or a new rate: it updates the
// mean interval only.
constexpr double kRegular = 0.25;

void blend(double& mean, double value, double weight) { mean += weight * (value - mean); }
void blend(Eigen::Vector3d& mean, const Eigen::Vector3d& value, double weight) {
  mean += weight * (value - mean);
}

}  // namespace

KinematicAutoRule::KinematicAutoRule(RateSamples kind, bool stamps_filtered)
    : kind_(kind),
      stamps_filtered_(stamps_filtered),
      base_(autoIntegrator(Model::Kinematic, false)),
      choice_(base_) {}

double KinematicAutoRule::jitterMeasure() const {
  if (!(mean_interval_ > 0.0 && mean_w_squared_ > 0.0)) return 0.0;
  const double sigma_t = std::sqrt(mean_d2_squared_ / 6.0);
  return sigma_t * std::sqrt(mean_dw_squared_ / mean_w_squared_) / mean_interval_;
}

void KinematicAutoRule::predictErrors(double interval, const Eigen::Vector3d& w_B, bool filled,
                                      bool regular, double weight) {
  real_run_ = regular && !filled ? real_run_ + 1 : 0;
  for (std::size_t j = 0; j + 1 < recent_.size(); ++j) recent_[j] = recent_[j + 1];
  recent_.back() = w_B;
  for (std::size_t j = 0; j + 1 < starts_.size(); ++j) starts_[j] = starts_[j + 1];
  starts_.back() = frame_;
  frame_ = (frame_ * expMap(interval * w_B)).normalized();
  if (real_run_ >= recent_.size()) estimateErrors(weight);
  // From the first fill on, each step adds the errors per step estimated last (the world-frame
  // means, so that a drift adds up and an oscillation averages out), a filled step its fill's.
  if (filled) filled_before_ = true;
  if (!filled_before_) return;
  if (filled) fills_sum_ += fill_drift_;
  cf4_sum_ += cf4_drift_;
  exp2_sum_ += exp2_drift_;
  cf4_worst_ = std::max(cf4_worst_, (fills_sum_ + cf4_sum_).norm());
  exp2_worst_ = std::max(exp2_worst_, (fills_sum_ + exp2_sum_).norm());
}

void KinematicAutoRule::estimateErrors(double weight) {
  const std::array<Eigen::Vector3d, 5>& m = recent_;
  const double h = mean_interval_;
  // The errors of the middle interval of the five newest means, m[2], in the world frame: the
  // frame of the means integrated at that interval's middle (between its start and its end,
  // the next one's start), not the newest frame, which has turned by about 2 h |w| since (a
  // fast spin would turn a circling error onto the spin axis). Its rotation beyond h m
  // (Bortz): h^3/12 m x (the rate's slope). The
  // slope exact to fourth order: the derivative at the middle of the quartic whose means over
  // the five intervals are the samples. cf4 took it from the quadratic through the middle
  // mean and the two before (one-sided), exp2 from the difference of the last two means (half
  // a step late).
  const Eigen::Vector3d slope = (17.0 / 24.0 * (m[3] - m[1]) - 5.0 / 48.0 * (m[4] - m[0])) / h;
  const Eigen::Vector3d cf4_slope = (1.5 * m[2] - 2.0 * m[1] + 0.5 * m[0]) / h;
  const Eigen::Vector3d exp2_slope = (m[2] - m[1]) / h;
  const double bortz = h * h * h / 12.0;
  const Eigen::Quaterniond middle(starts_[0].coeffs() + starts_[1].coeffs());
  const Eigen::Matrix3d to_world = middle.normalized().toRotationMatrix();
  blend(cf4_drift_, to_world * (bortz * m[2].cross(cf4_slope - slope)), weight);
  blend(exp2_drift_, to_world * (bortz * m[2].cross(exp2_slope - slope)), weight);
  // A fill's error: the mean the fill would put for m[3] from the three before and the one
  // after (the cubic of fillMeans) less the sample, h/4 times the fourth difference, in the
  // frame at the middle of m[3]'s interval.
  const Eigen::Vector3d fourth = m[0] - 4.0 * m[1] + 6.0 * m[2] - 4.0 * m[3] + m[4];
  const Eigen::Quaterniond fill_middle(starts_[1].coeffs() + starts_[2].coeffs());
  blend(fill_drift_, fill_middle.normalized() * (0.25 * h * fourth), weight);
}

Integrator KinematicAutoRule::step(double interval, const Eigen::Vector3d& w_B, bool filled) {
  // The weight of a new sample: 1/n while fewer than kMemory samples were seen (their mean),
  // then 1/kMemory.
  ++samples_;
  const double weight = samples_ >= kMemory ? 1.0 / kMemory : 1.0 / static_cast<double>(samples_);
  const bool averaged = kind_ == RateSamples::IntervalAverage;
  const bool steady =
      have_interval_ && std::abs(interval - mean_interval_) <= kRegular * mean_interval_;
  if (have_interval_) {
    const bool regular = std::abs(interval - mean_interval_) <= kRegular * mean_interval_ &&
                         std::abs(last_interval_ - mean_interval_) <= kRegular * mean_interval_;
    if (regular && !filled) {
      const double d2 = interval - last_interval_;
      blend(mean_d2_squared_, d2 * d2, weight);
    }
    blend(mean_dw_squared_, (w_B - last_w_).squaredNorm(), weight);
  }
  blend(mean_interval_, interval, weight);
  blend(mean_w_squared_, w_B.squaredNorm(), weight);
  mean_w_ += weight * (w_B - mean_w_);
  have_interval_ = true;
  last_interval_ = interval;
  last_w_ = w_B;

  if (averaged) {
    predictErrors(interval, w_B, filled, steady, weight);
    lossy_ = exp2_worst_ < cf4_worst_;
  }
  if (samples_ >= kWarmUp && !stamps_filtered_) {
    // J^2 = noise / (6 scale) against the thresholds squared: no root or division per sample.
    const double noise = mean_d2_squared_ * mean_dw_squared_;
    const double scale = 6.0 * mean_w_squared_ * mean_interval_ * mean_interval_;
    const bool turning = mean_w_.squaredNorm() >= kTurning * kTurning * mean_w_squared_;
    if (scale > 0.0 && turning && noise > kJitterOn * kJitterOn * scale) jittered_ = true;
    if (!(scale > 0.0 && turning && noise >= kJitterOff * kJitterOff * scale)) jittered_ = false;
  }
  if (lossy_) {
    choice_ = Integrator::Exp2;
  } else if (jittered_) {
    choice_ = averaged ? Integrator::Exp2 : Integrator::Rk4;
  } else {
    choice_ = base_;
  }
  return choice_;
}

void KinematicAutoRule::restart() {
  have_interval_ = false;
  real_run_ = 0;
}

void KinematicAutoRule::reset() { *this = KinematicAutoRule(kind_, stamps_filtered_); }

}  // namespace attitude_propagator
