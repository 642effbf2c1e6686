// Gravity and the magnetic field as measurements beside the gyro (docs/design.md §6.10): what a
// user configures, what became of each sample, the counters kept per kind, and the run of gate
// rejections that ends in a recovery.
#pragma once

#include <array>
#include <cstdint>
#include <optional>

#include <Eigen/Core>

#include "attitude_propagator/limits.h"
#include "attitude_propagator/time/source_timeline.h"

namespace attitude_propagator {

struct AidingConfig {
  /// The IMU's linear_acceleration is a measurement of the gravity direction.
  bool use_accel = false;
  double accel_stddev = 0.1;  ///< m/s^2 per axis, for a sample without a covariance
  /// A sample's own covariance is used when it gives one; false: ignored (accel_stddev always).
  bool use_accel_covariance = true;
  /// The magnetometer's field is a measurement of the heading (never of roll and pitch).
  bool use_mag = false;
  double mag_stddev = 1e-6;  ///< tesla per axis, for a sample without a covariance
  /// A sample's own covariance is used when it gives one; false: ignored (mag_stddev always).
  bool use_mag_covariance = true;
  double declination = 0.0;  ///< rad, magnetic north east of true north positive
  /// T, body frame: the magnetometer's own field (hard iron, a calibration's offset), subtracted
  /// from every field sample before it is used or judged; |mag_bias| at most kMaxMagBias.
  Eigen::Vector3d mag_bias = Eigen::Vector3d::Zero();
  /// The attitude starts from the first gravity sample (tilt; the heading unknown until a
  /// field sample or a fix): no initial_orientation given.
  bool align = false;
  double accel_gate = kAccelGate;
  double mag_gate = kMagGate;
  /// s over which the linear acceleration seen is averaged (LinearAcceleration); 0: none taken
  /// (the direction's noise is the sensor's alone).
  double linear_window = kLinearAccelerationWindow;
  double accel_recovery = kAccelRecovery;  ///< s of gate rejections in a row, then a reset
  double mag_recovery = kMagRecovery;      ///< the same for the field
  bool any() const { return use_accel || use_mag; }
};

/// What became of a gravity or field sample.
enum class AidingOutcome {
  Accepted,           ///< fused at its stamp (the rates since replayed when it was late)
  Aligned,            ///< gravity: the first sample, the tilt set from it (align)
  Recovered,          ///< applied as a reset after a long run of rejections (limits.h)
  Waiting,            ///< stamped ahead of the newest rate: applied when the rates reach it
  RejectedGate,       ///< the innovation beyond the chi-square gate
  RejectedMagnitude,  ///< gravity: |f| off g; field: |m| or the dip off the learned field
  NotAligned,         ///< field: the tilt is not known yet (align, no gravity sample yet)
  TooOld,             ///< stamped before the history kept (fix_history) or the anchor
  Invalid,            ///< non-finite, zero, or a bad covariance
  QueueFull,          ///< waiting, and dropped: kMaxPendingMeasurements were stamped nearer
  Future,             ///< stamped more than max_future ahead of the clock
  OverBudget,         ///< late, its replay beyond the second's budget (replay_budget.h)
  Off,                ///< the kind is not configured (use_accel, use_mag false): ignored
};
const char* aidingOutcomeName(AidingOutcome outcome);

/// Per kind (accel_*, mag_*): what became of the samples. Every counter only grows.
struct AidingCounters {
  std::uint64_t accepted = 0;
  std::uint64_t aligned = 0;
  std::uint64_t recovered = 0;
  std::uint64_t rejected_gate = 0;
  std::uint64_t rejected_magnitude = 0;
  std::uint64_t not_aligned = 0;
  std::uint64_t too_old = 0;
  std::uint64_t invalid = 0;
  std::uint64_t queue_full = 0;
  std::uint64_t future = 0;
  std::uint64_t over_budget = 0;
  void count(AidingOutcome outcome);
  /// Calls f(name, value) for each counter, in aidingCounterTable()'s order: the one list the
  /// diagnostics, the tools' summaries and the docs' table follow.
  template <class F>
  void forEach(F&& f) const;
};

/// One of AidingCounters' counters: its name (accel_<name> and mag_<name> in the diagnostics),
/// what befell the samples it counts, whether they were applied, and its field.
struct AidingCounterInfo {
  const char* name;
  const char* meaning;
  bool applied;
  std::uint64_t AidingCounters::*field;
};

/// Every counter of AidingCounters once, in the order of docs/node.md's table.
const std::array<AidingCounterInfo, 11>& aidingCounterTable();

template <class F>
void AidingCounters::forEach(F&& f) const {
  for (const AidingCounterInfo& info : aidingCounterTable()) f(info.name, this->*info.field);
}

/// The linear acceleration seen lately in the gravity samples, from two sides, each averaged over
/// kLinearAccelerationWindow seconds (exponentially, by the samples' stamps):
///  - the part of each sample the estimate does not explain, f_B - g C_BW e_up, its squared size
///    (from zero: before the tilt is known it says nothing). A lasting acceleration the tilt has
///    already followed no longer shows here;
///  - the specific force's magnitude, |f|^2 - g^2 = |a|^2 + 2 g a_up (from the first sample): it
///    owes nothing to the estimate, and a horizontal acceleration (a turn, a braking: at right
///    angles to gravity, |f| hardly off g) shows in it as |a|^2 for as long as it lasts, while a
///    vertical one (a_up, whose mean over a window is the change of a bounded vertical velocity)
///    mostly averages out.
/// What a sample is taken to carry, less the sensor's noise (LinearVariance): the two sides
/// spread their power differently. The unexplained part holds all three axes (the vertical's
/// too: vibration, heave) and is spread evenly over them; the magnitude is, for a horizontal
/// acceleration, the power of the part that turns the direction, and it is given whole to each
/// axis: a lasting acceleration keeps its direction in the plane, so one axis carries all of it
/// while it lasts, and its samples share one error rather than averaging theirs away. While a
/// vehicle turns or brakes, or a hand shakes, the gravity direction is trusted less, and as much
/// again once it stops; a single sample far off (a bump) is left to the gate.
struct LinearVariance {
  /// m^2/s^4 per axis: each gravity sample's noise from the linear acceleration,
  /// max((<|f_B - g u|^2> - tr) / 3, |<|f|^2 - g^2>| - tr), tr the sensor's noise (the trace
  /// both sides' means hold anyway), at least 0 (GravityDirection).
  double direction = 0.0;
  /// m^2/s^4 per axis: the larger side spread evenly over three axes, max(<|f_B - g u|^2>,
  /// |<|f|^2 - g^2>|) less the sensor's noise, over three: how far the filtered tilt may be off
  /// beyond its covariance (MagneticHeading, over g^2).
  double spread = 0.0;

  /// rad^2 per axis the field's heading allows the tilt beyond its covariance: spread / g^2.
  double fieldTiltVariance() const;
};

class LinearAcceleration {
 public:
  /// The variances for the sample at `stamp` whose unexplained part is `residual` (m/s^2) and
  /// whose force has the size `force` (m/s^2; 0: not given, the magnitude's side not used),
  /// with the sensor's noise `noise_trace` (m^2/s^4, the covariance's trace), averaged over
  /// `window` seconds.
  LinearVariance observe(Stamp stamp, const Eigen::Vector3d& residual, double noise_trace,
                         double window = kLinearAccelerationWindow, double force = 0.0);
  void reset() {
    mean_ = 0.0;
    magnitude_ = 0.0;
    last_.reset();
  }

 private:
  double mean_ = 0.0;       // <|f_B - g u|^2>
  double magnitude_ = 0.0;  // <|f|^2 - g^2>
  std::optional<Stamp> last_;
};

/// The published tilt covariance's share of what the filter cannot tell apart: a linear
/// acceleration that lasts and an error of its own tilt both keep the measured gravity
/// direction off the estimate's vertical, and the filter, taking the acceleration for noise,
/// follows either only slowly. The horizontal part of the measured up turned into the world by
/// the estimate, f_W / |f| = q_WB f_B / |f| (small: the sine of the angle between the two ups),
/// averaged over kTiltDisagreementWindow seconds, is how far the two have stayed apart; its
/// squared size is added to the published covariance's tilt plane (AttitudeEngine::state), not
/// to the filter's own (docs/numerics.md §7.2). What averages out (vibration, a hand's shake,
/// a swell) adds nothing; a turn adds its lean for as long as it lasts.
class TiltDisagreement {
 public:
  /// The sample at `stamp` whose measured up, in the world by the estimate, is `up_W` (unit).
  /// Until the window has passed, the mean of the samples so far (the first counts whole);
  /// then an exponential window over the stamps, a = 1 - exp(-dt / window).
  void observe(Stamp stamp, const Eigen::Vector3d& up_W, double window = kTiltDisagreementWindow);
  /// rad^2 per axis of the tilt plane: the averaged horizontal part's squared size.
  double variance() const { return mean_.squaredNorm(); }
  void reset() {
    mean_.setZero();
    count_ = 0;
    last_.reset();
  }

 private:
  Eigen::Vector2d mean_ = Eigen::Vector2d::Zero();
  std::uint64_t count_ = 0;
  std::optional<Stamp> last_;
};

/// The run of gate rejections of one kind: once it has lasted `seconds`, the next rejected
/// sample is applied as a reset and the run starts again.
class RejectionRun {
 public:
  /// A rejection at `stamp`: true when it ends the run in a recovery.
  bool rejected(Stamp stamp, double seconds);
  void accepted() { since_.reset(); }
  void clear() { since_.reset(); }

 private:
  std::optional<Stamp> since_;
};

}  // namespace attitude_propagator
