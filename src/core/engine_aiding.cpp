// The engine's side of gravity and the magnetic field as measurements (docs/design.md §6.10):
// whether a sample is used, and what is counted; it acts at its stamp, placed and replayed by
// FixReplay. What a sample does to the state is the estimation room's (estimation/).
#include <algorithm>
#include <cmath>
#include <memory>
#include <optional>
#include <utility>

#include "attitude_propagator/engine.h"
#include "attitude_propagator/estimation/gravity_direction.h"
#include "attitude_propagator/estimation/magnetic_heading.h"
#include "attitude_propagator/estimation/orientation_covariance.h"
#include "attitude_propagator/limits.h"

namespace attitude_propagator {

namespace {

/// A sensor's covariance from a message: finite, symmetric, variances at least 0,
/// correlations at most one (the rate covariance's rules); zero: none given.
bool validSensorCovariance(const Eigen::Matrix3d& R) {
  return checkRateCovariance(R) == RateCovarianceCheck::Ok;
}

Eigen::Matrix3d orDefault(const Eigen::Matrix3d& covariance, double stddev) {
  if (!covariance.isZero(0.0)) return 0.5 * (covariance + covariance.transpose());
  return stddev * stddev * Eigen::Matrix3d::Identity();
}

/// The covariance a sample is taken to give: its own, or none when the settings say its
/// driver's is not to be used (then it is not judged either: the setting's stddev stands).
Eigen::Matrix3d givenCovariance(const Eigen::Matrix3d& covariance, bool use_message_covariance) {
  return use_message_covariance ? covariance : Eigen::Matrix3d::Zero();
}

}  // namespace

AidingOutcome AttitudeEngine::submitAcceleration(Stamp stamp, const Eigen::Vector3d& f_B,
                                                 const Eigen::Matrix3d& message_covariance_B) {
  if (!config_.aiding.use_accel) return AidingOutcome::Off;
  const Eigen::Matrix3d covariance_B =
      givenCovariance(message_covariance_B, config_.aiding.use_accel_covariance);
  AidingOutcome outcome = AidingOutcome::Waiting;
  if (!f_B.allFinite() || !validSensorCovariance(covariance_B) || !(f_B.norm() > 0.0)) {
    outcome = AidingOutcome::Invalid;
  } else if (std::abs(f_B.norm() / kStandardGravity - 1.0) > kAccelMagnitudeTolerance) {
    outcome = AidingOutcome::RejectedMagnitude;  // a bump, a launch, free fall
  }
  if (outcome != AidingOutcome::Waiting) {
    counters_.accel.count(outcome);
    return outcome;
  }
  const Eigen::Matrix3d R = orDefault(covariance_B, config_.aiding.accel_stddev);
  const LinearVariance seen = linear_acceleration_.observe(
      stamp, f_B - kStandardGravity * bodyUp(propagator_->state().q_WB), R.trace(),
      config_.aiding.linear_window, f_B.norm());
  linear_variance_ = tilt_known_ ? seen : LinearVariance{};
  // The linear acceleration's published share too, taken like its noise where the sample
  // arrives; off with it (linear_window 0: the acceleration taken as not there).
  if (tilt_known_ && config_.aiding.linear_window > 0.0) {
    tilt_disagreement_.observe(stamp, propagator_->state().q_WB * f_B.normalized());
  }
  const GravityDirection measurement(f_B, R, config_.aiding.accel_gate, linear_variance_.direction);
  if (last_imu_stamp_ && stamp == *last_imu_stamp_) {
    // With its own rate (the same message): where that rate took effect. Nothing to keep unless
    // the history is on (fixes, the field, a late sample started it).
    const AidingOutcome o = applyAtNewest(
        measurement, stamp, f_B,
        keep_history_ ? std::make_shared<const GravityDirection>(measurement) : nullptr);
    counters_.accel.count(o);
    return o;
  }
  // The IMU's accelerometer shares its gyro's filter and latency: moved back by rate_delay too.
  return placeMeasurement(
      {stamp - rate_delay_ns_, std::make_shared<const GravityDirection>(measurement), f_B});
}

AidingOutcome AttitudeEngine::submitMagneticField(Stamp stamp, const Eigen::Vector3d& read_B,
                                                  const Eigen::Matrix3d& message_covariance_B) {
  if (!config_.aiding.use_mag) return AidingOutcome::Off;
  field_fit_.add(read_B);  // as read; the fit takes no non-finite, zero or absurd read
  // The sensor's own field (hard iron) is no part of the earth's: taken off before anything.
  const Eigen::Vector3d m_B = read_B - config_.aiding.mag_bias;
  const Eigen::Matrix3d covariance_B =
      givenCovariance(message_covariance_B, config_.aiding.use_mag_covariance);
  AidingOutcome outcome = AidingOutcome::Waiting;
  if (!m_B.allFinite() || !validSensorCovariance(covariance_B) || !(m_B.norm() > 0.0)) {
    outcome = AidingOutcome::Invalid;
  } else if (!tilt_known_) {
    outcome = AidingOutcome::NotAligned;  // a heading needs the vertical
  } else if (!mag_reference_.matches(m_B, propagator_->state().q_WB)) {
    // Off the learned field: a disturbance, unless it lasts; then the field is what changed
    // (a new place, a calibration) and the reference starts again from it.
    if (!mag_off_since_ || stamp < *mag_off_since_) mag_off_since_ = stamp;
    if (static_cast<double>(stamp - *mag_off_since_) * 1e-9 < config_.aiding.mag_recovery) {
      outcome = AidingOutcome::RejectedMagnitude;
    } else {
      mag_reference_.restart(m_B, propagator_->state().q_WB);
      mag_off_since_.reset();
    }
  } else {
    mag_off_since_.reset();
  }
  if (outcome != AidingOutcome::Waiting) {
    counters_.mag.count(outcome);
    return outcome;
  }
  auto measurement = std::make_shared<const MagneticHeading>(
      m_B, orDefault(covariance_B, config_.aiding.mag_stddev), config_.aiding.declination,
      config_.aiding.mag_gate, linear_variance_.fieldTiltVariance());
  return placeMeasurement({stamp, std::move(measurement), m_B});
}

AidingOutcome AttitudeEngine::placeMeasurement(PendingMeasurement pm) {
  AidingCounters& counters = aidingCounters(pm.measurement->kind());
  if (tooFarAhead(pm.stamp)) {
    counters.count(AidingOutcome::Future);  // it would wait for rates that may never come
    return AidingOutcome::Future;
  }
  keepHistory();
  if (replay_.reaches(pm.stamp)) {
    const AidingOutcome outcome = applyMeasurement(pm);
    counters.count(outcome);
    return outcome;
  }
  // Ahead of the newest rate (or before the first): it waits for the rates to reach it.
  const Stamp stamp = pm.stamp;
  const auto pushed = pending_measurements_.push(stamp, std::move(pm));
  if (pushed.dropped) {
    aidingCounters(pushed.dropped->measurement->kind()).count(AidingOutcome::QueueFull);
  }
  if (!pushed.kept) counters.count(AidingOutcome::QueueFull);  // the furthest ahead
  return pushed.kept ? AidingOutcome::Waiting : AidingOutcome::QueueFull;
}

void AttitudeEngine::applyDueMeasurements() {
  while (!pending_measurements_.empty() && replay_.reaches(pending_measurements_.frontStamp())) {
    const PendingMeasurement pm = pending_measurements_.pop();
    aidingCounters(pm.measurement->kind()).count(applyMeasurement(pm));
  }
}

AidingOutcome AttitudeEngine::decideMeasurement(const Measurement& m, Stamp stamp,
                                                const Eigen::Vector3d& value, Eigen::Quaterniond& q,
                                                ErrorState& e, bool& reset) {
  const bool gravity = m.kind() == MeasurementKind::Gravity;
  RejectionRun& run = gravity ? accel_run_ : mag_run_;
  reset = false;
  if (gravity && !tilt_known_) {
    m.reset(q, e);  // the first gravity sample: the tilt from it, the heading unknown
    reset = true;
    tilt_known_ = true;
    run.clear();
    return AidingOutcome::Aligned;
  }
  if (fuseMeasurement(m, q, e).accepted) {
    run.accepted();
    if (!gravity) mag_reference_.follow(value, q);
    return AidingOutcome::Accepted;
  }
  const double recovery = gravity ? config_.aiding.accel_recovery : config_.aiding.mag_recovery;
  if (!run.rejected(stamp, recovery)) return AidingOutcome::RejectedGate;
  m.reset(q, e);  // rejected this long: the estimate, not the sensor, is what is wrong
  reset = true;
  if (!gravity) mag_reference_.restart(value, q);
  return AidingOutcome::Recovered;
}

AidingOutcome AttitudeEngine::applyAtNewest(const Measurement& m, Stamp stamp,
                                            const Eigen::Vector3d& value,
                                            std::shared_ptr<const Measurement> kept) {
  Eigen::Quaterniond q = propagator_->state().q_WB;
  ErrorState e = error_;
  bool reset = false;
  const AidingOutcome outcome = decideMeasurement(m, stamp, value, q, e, reset);
  if (outcome == AidingOutcome::RejectedGate) return outcome;
  propagator_->correctOrientation(q);
  error_ = e;
  if (keep_history_) replay_.keepAtNewest(std::move(kept), stamp, reset);
  return outcome;
}

AidingOutcome AttitudeEngine::applyMeasurement(const PendingMeasurement& pm) {
  if (replay_.atNewest(pm.stamp)) {
    // At the newest state: applied to it, nothing replayed.
    return applyAtNewest(*pm.measurement, pm.stamp, pm.value, pm.measurement);
  }
  // Late: applied where it belongs (FixReplay), when its second can afford the replay.
  if (!replay_.replayAffordable(pm.stamp)) return AidingOutcome::OverBudget;
  std::optional<FixReplay::Placed> placed = replay_.place(pm.stamp);
  if (!placed) return AidingOutcome::TooOld;
  bool reset = false;
  const AidingOutcome outcome =
      decideMeasurement(*pm.measurement, pm.stamp, pm.value, placed->q, placed->e, reset);
  if (outcome == AidingOutcome::RejectedGate) {
    replay_.dropPlaced(std::move(*placed));
    return outcome;
  }
  replay_.applyPlaced(std::move(*placed), pm.measurement, pm.stamp, reset);
  return outcome;
}

}  // namespace attitude_propagator
