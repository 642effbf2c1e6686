#include "attitude_propagator/numerics/auto_integrator.h"

#include <cmath>

namespace attitude_propagator {

namespace {

// An interval this far from the mean one is not jitter but a gap or a new rate: it updates the
// mean interval only.
constexpr double kRegular = 0.25;

void blend(double& mean, double value, double weight) { mean += weight * (value - mean); }

}  // namespace

KinematicAutoRule::KinematicAutoRule(RateSamples kind, bool stamps_filtered)
    : kind_(kind),
      stamps_filtered_(stamps_filtered),
      base_(autoIntegrator(Model::Kinematic, false)),
      choice_(base_),
      steps_since_fill_(kFillWindow) {}

double KinematicAutoRule::jitterMeasure() const {
  if (!(mean_interval_ > 0.0 && mean_w_squared_ > 0.0)) return 0.0;
  const double sigma_t = std::sqrt(mean_d2_squared_ / 6.0);
  return sigma_t * std::sqrt(mean_dw_squared_ / mean_w_squared_) / mean_interval_;
}

Integrator KinematicAutoRule::step(double interval, const Eigen::Vector3d& w_B, bool filled) {
  // The weight of a new sample: 1/n while fewer than kMemory samples were seen (their mean),
  // then 1/kMemory.
  ++samples_;
  const double weight = samples_ >= kMemory ? 1.0 / kMemory : 1.0 / static_cast<double>(samples_);
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

  steps_since_fill_ = filled ? 0 : steps_since_fill_ + 1;
  if (samples_ >= kWarmUp && !stamps_filtered_) {
    // J^2 = noise / (6 scale) against the thresholds squared: no root or division per sample.
    const double noise = mean_d2_squared_ * mean_dw_squared_;
    const double scale = 6.0 * mean_w_squared_ * mean_interval_ * mean_interval_;
    const bool turning = mean_w_.squaredNorm() >= kTurning * kTurning * mean_w_squared_;
    if (scale > 0.0 && turning && noise > kJitterOn * kJitterOn * scale) jittered_ = true;
    if (!(scale > 0.0 && turning && noise >= kJitterOff * kJitterOff * scale)) jittered_ = false;
  }
  const bool averaged = kind_ == RateSamples::IntervalAverage;
  if (averaged && steps_since_fill_ < kFillWindow) {
    choice_ = Integrator::Exp2;
  } else if (jittered_) {
    choice_ = averaged ? Integrator::Exp2 : Integrator::Rk4;
  } else {
    choice_ = base_;
  }
  return choice_;
}

void KinematicAutoRule::restart() { have_interval_ = false; }

void KinematicAutoRule::reset() { *this = KinematicAutoRule(kind_, stamps_filtered_); }

}  // namespace attitude_propagator
