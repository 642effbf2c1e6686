// Gravity and the magnetic field as measurements beside the gyro (docs/design.md §6.10): what a
// user configures, what became of each sample, the counters kept per kind, and the run of gate
// rejections that ends in a recovery.
#pragma once

#include <cstdint>
#include <optional>

#include "attitude_propagator/limits.h"
#include "attitude_propagator/source_timeline.h"

namespace attitude_propagator {

struct AidingConfig {
  /// The IMU's linear_acceleration is a measurement of the gravity direction.
  bool use_accel = false;
  double accel_stddev = 0.1;  ///< m/s^2 per axis, for a sample without a covariance
  /// The magnetometer's field is a measurement of the heading (never of roll and pitch).
  bool use_mag = false;
  double mag_stddev = 1e-6;  ///< tesla per axis, for a sample without a covariance
  double declination = 0.0;  ///< rad, magnetic north east of true north positive
  /// The attitude starts from the first gravity sample (tilt; the heading unknown until a
  /// field sample or a fix): no initial_orientation given.
  bool align = false;
  double accel_gate = kAccelGate;
  double mag_gate = kMagGate;
  double recovery = kAidingRecovery;  ///< s of gate rejections in a row, then a reset
  bool any() const { return use_accel || use_mag; }
};

/// What became of a gravity or field sample.
enum class AidingOutcome {
  Accepted,           ///< fused at its stamp (the rates since replayed when it was late)
  Aligned,            ///< gravity: the first sample, the tilt set from it (align)
  Recovered,          ///< applied as a reset after kAidingRecovery s of rejections
  Waiting,            ///< stamped ahead of the newest rate: applied when the rates reach it
  RejectedGate,       ///< the innovation beyond the chi-square gate
  RejectedMagnitude,  ///< gravity: |f| off g; field: |m| or the dip off the learned field
  NotAligned,         ///< field: the tilt is not known yet (align, no gravity sample yet)
  TooOld,             ///< stamped before the history kept (fix_history) or the anchor
  Invalid,            ///< non-finite, zero, or a bad covariance
  QueueFull,          ///< waiting, and dropped: kMaxPendingMeasurements were stamped nearer
  Future,             ///< stamped more than max_future ahead of the clock
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
  void count(AidingOutcome outcome);
  /// Calls f(name, value) for each counter, in the order above: the one list the diagnostics,
  /// the tools' summaries and the docs' table follow.
  template <class F>
  void forEach(F&& f) const {
    f("accepted", accepted);
    f("aligned", aligned);
    f("recovered", recovered);
    f("rejected_gate", rejected_gate);
    f("rejected_magnitude", rejected_magnitude);
    f("not_aligned", not_aligned);
    f("too_old", too_old);
    f("invalid", invalid);
    f("queue_full", queue_full);
    f("future", future);
  }
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
