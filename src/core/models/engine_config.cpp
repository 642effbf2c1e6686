#include "attitude_propagator/models/engine_config.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include "attitude_propagator/limits.h"
#include "attitude_propagator/models/propagator.h"

namespace attitude_propagator {

namespace {

void checkMaxFuture(double max_future) {
  if (!(max_future > 0.0 && max_future <= kMaxFuture)) {
    throw std::invalid_argument("max_future: accepted: more than 0 and at most " +
                                std::to_string(kMaxFuture) + " s, got " +
                                std::to_string(max_future));
  }
}

/// A delay longer than the longest gap integrated across would put every sample behind the one
/// before a gap.
void checkRateDelay(const EngineConfig& c) {
  const double max_dt = timePolicyOf(c).max_dt;
  if (!(c.rate_delay >= 0.0 && c.rate_delay <= max_dt)) {
    throw std::invalid_argument("rate_delay: accepted: 0 to max_dt = " + std::to_string(max_dt) +
                                " s, got " + std::to_string(c.rate_delay));
  }
}

void checkFixConfig(const FixConfig& f) {
  auto require = [](bool ok, const std::string& what) {
    if (!ok) throw std::invalid_argument(what);
  };
  require(std::isfinite(f.history) && f.history > 0.0 && f.history <= kMaxFixHistory,
          "fix_history: accepted: more than 0 and at most " + std::to_string(kMaxFixHistory) +
              " s, got " + std::to_string(f.history));
  require(std::isfinite(f.gate) && f.gate > 0.0,
          "fix_gate: accepted: a finite number > 0, got " + std::to_string(f.gate));
  require(std::isfinite(f.stddev) && f.stddev > 0.0 && f.stddev <= M_PI,
          "fix_stddev: accepted: more than 0 and at most pi rad, got " + std::to_string(f.stddev));
  require(std::isfinite(f.gyro_bias_random_walk) && f.gyro_bias_random_walk >= 0.0 &&
              f.gyro_bias_random_walk <= kMaxRateStddev,
          "gyro_bias_random_walk: accepted: 0 to 1000 rad/s/sqrt(s), got " +
              std::to_string(f.gyro_bias_random_walk));
  require(std::isfinite(f.gyro_bias_stddev) && f.gyro_bias_stddev >= 0.0 &&
              f.gyro_bias_stddev <= kMaxGyroBiasStddev,
          "gyro_bias_stddev: accepted: 0 to 10 rad/s, got " + std::to_string(f.gyro_bias_stddev));
}

void checkAidingConfig(const EngineConfig& c) {
  const AidingConfig& a = c.aiding;
  auto require = [](bool ok, const std::string& what) {
    if (!ok) throw std::invalid_argument(what);
  };
  if (a.any()) {
    require(c.model == Model::Kinematic, std::string(a.use_accel ? "use_accel" : "use_mag") +
                                             ": accepted: true with the kinematic model only");
  }
  require(std::isfinite(a.accel_stddev) && a.accel_stddev > 0.0 && a.accel_stddev <= 100.0,
          "accel_stddev: accepted: more than 0 and at most 100 m/s^2, got " +
              std::to_string(a.accel_stddev));
  require(
      std::isfinite(a.mag_stddev) && a.mag_stddev > 0.0 && a.mag_stddev <= 1e-2,
      "mag_stddev: accepted: more than 0 and at most 0.01 T, got " + std::to_string(a.mag_stddev));
  require(std::isfinite(a.declination) && std::abs(a.declination) <= M_PI,
          "declination: accepted: -pi to pi rad (east of north positive), got " +
              std::to_string(a.declination));
  require(a.mag_bias.allFinite() && a.mag_bias.norm() <= kMaxMagBias,
          "mag_bias: accepted: [x, y, z] finite, of size at most 0.01 T, got size " +
              std::to_string(a.mag_bias.norm()));
  require(std::isfinite(a.linear_window) && a.linear_window >= 0.0 && a.linear_window <= 3600.0,
          "linear_window: accepted: 0 (none) to 3600 s, got " + std::to_string(a.linear_window));
  require(std::isfinite(a.accel_gate) && a.accel_gate > 0.0 && std::isfinite(a.mag_gate) &&
              a.mag_gate > 0.0 && std::isfinite(a.accel_recovery) && a.accel_recovery > 0.0 &&
              std::isfinite(a.mag_recovery) && a.mag_recovery > 0.0,
          "accel_gate, mag_gate, accel_recovery, mag_recovery: accepted: finite numbers > 0");
}

}  // namespace

void checkEngineSettings(const EngineConfig& c) {
  checkMaxFuture(c.max_future);
  checkRateDelay(c);
  checkFixConfig(c.fixes);
  checkAidingConfig(c);
  if (c.fixes.estimate_gyro_bias && c.model != Model::Kinematic) {
    throw std::invalid_argument("estimate_gyro_bias: accepted: true with the kinematic model only");
  }
}

void checkEngineConfig(const EngineConfig& c) {
  if (!(c.publish_rate > 0.0) || !std::isfinite(c.publish_rate)) {
    throw std::invalid_argument("publish_rate: must be positive and finite");
  }
  if (!c.gyro_bias_B.allFinite() || c.gyro_bias_B.norm() > kMaxBodyRate) {
    throw std::invalid_argument(
        "gyro_bias: must be finite, each magnitude at most the largest "
        "accepted body rate");
  }
  checkEngineSettings(c);
}

Stamp rateDelayNs(const EngineConfig& c) {
  return static_cast<Stamp>(std::llround(c.rate_delay * 1e9));
}

Eigen::Matrix3d defaultRateCovariance(const EngineConfig& c) {
  const double s = c.aiding.any() && c.rate_stddev == 0.0 ? kAidedRateStddev : c.rate_stddev;
  return s * s * Eigen::Matrix3d::Identity();
}

}  // namespace attitude_propagator
