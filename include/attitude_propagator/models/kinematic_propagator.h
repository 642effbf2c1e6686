// Stateful kinematic propagation from timestamped body-rate samples, with the time and
// bad-input policy of docs/design.md §6–§7. No ROS: the node forwards stamps and rates to
// addSample().
#pragma once

#include <array>
#include <cstdint>
#include <optional>

#include <Eigen/Geometry>

#include "attitude_propagator/numerics/auto_integrator.h"
#include "attitude_propagator/numerics/integrator.h"
#include "attitude_propagator/numerics/kinematic_step.h"
#include "attitude_propagator/time/average_stamp.h"
#include "attitude_propagator/time/stamp_filter.h"
#include "attitude_propagator/time/time_policy.h"

namespace attitude_propagator {

/// A silence longer than this many mean periods of the rate stream (the mean of its intervals
/// since the anchor, the last 16 or so weighted most, once three of at least 1 us are known) is
/// a dropout: the state is held across it (HeldGap), as across one longer than max_dt, which
/// stays the bound in seconds. Up to
/// kMaxGapFill lost samples in a row (kMaxGapFill + 1 periods) are bridged instead: filled in
/// for interval averages, spanned by one step for point samples.
constexpr double kGapPeriods = 5.5;
/// Largest `max_gap_fill`: lost samples in a row that can be filled before a dropout.
constexpr int kMaxGapFill = 4;

struct KinematicConfig {
  /// Auto: chosen per step by KinematicAutoRule (cf4 unless the stream shows filled losses or
  /// heavy stamp jitter; auto_integrator.h).
  Integrator integrator = Integrator::Auto;
  TimePolicy time_policy;
  Eigen::Quaterniond initial_q_WB = Eigen::Quaterniond::Identity();
  /// What a sample's rate means (point value, or mean over the interval it closes).
  RateSamples rate_samples = RateSamples::Instantaneous;
  /// Interval averages: where in its interval a sample is stamped (Mid, Start: each waits for
  /// the next sample, IntervalEnds). Point samples: End only.
  AverageStamp average_stamp = AverageStamp::End;
  /// Interval-averaged samples: up to this many lost samples in a row (at most kMaxGapFill) are
  /// filled from the polynomial fitted to the neighbouring means (0: never), on a stream whose
  /// last intervals are regular (the stamps prove the loss). Longer silences are dropouts
  /// (kGapPeriods).
  int max_gap_fill = kMaxGapFill;
  /// Replace receipt stamps by the sensor-clock model's (SensorClockFilter).
  StampFilter stamp_filter = StampFilter::None;
};

class KinematicPropagator {
 public:
  /// Throws std::invalid_argument for a non-kinematic integrator, a non-positive or
  /// non-finite max_dt or backward_jump, or a zero / non-finite initial orientation.
  explicit KinematicPropagator(const KinematicConfig& config);

  /// Feeds the body rate w_B measured at time t, its gyro bias already subtracted (the engine
  /// owns the bias, for both models). With the stamp filter on, t is a receipt stamp and the
  /// filtered stamp is used, and the orientation follows the filter's later stamps of the
  /// samples before (RestampCorrection). The first sample anchors time: the state at its stamp
  /// is the initial (or set) state. The orientation then holds at the newest stamp; a stamp at or
  /// before it is DroppedStale, however far back (a persistent jump back is the engine's to
  /// recognise: reset()). A NaN or infinite stamp or rate is RejectedNonFinite, |w_B| >
  /// kMaxBodyRate (limits.h) RejectedOutOfRange; neither changes the state. Never throws.
  StampOutcome addSample(double t, const Eigen::Vector3d& w_B);

  /// Back to the initial orientation, waiting for an anchoring sample.
  void reset();

  /// Replaces the orientation at the newest stamp (an absolute fix) without anchoring: the
  /// sample window, the time and the method's start-up stay, so the steps that follow are the
  /// ones that would have followed anyway. A start-up re-integration from the anchor still to
  /// come (cf4) starts from the anchor turned by the same world-side rotation. No-op before
  /// the first sample or for a zero or non-finite q (normalised otherwise).
  void correctOrientation(const Eigen::Quaterniond& q_WB);

  /// Pins the state: orientation q_WB (normalised at any finite scale) and body rate w_B hold
  /// at time t (a new anchor). Throws std::invalid_argument, leaving the state unchanged, for
  /// non-finite values, a zero quaternion or |w_B| > kMaxBodyRate.
  void setState(double t, const Eigen::Quaterniond& q_WB, const Eigen::Vector3d& w_B);

  bool anchored() const { return anchored_; }
  /// Stamp the state holds at (0 before the first sample).
  double time() const { return window_.size() > 0 ? window_.newest().t : 0.0; }
  const Eigen::Quaterniond& orientation() const { return q_WB_; }
  /// Body rate of the newest sample (as fed; interval-averaged: the interval's mean).
  Eigen::Vector3d rate() const {
    return window_.size() > 0 ? window_.newest().w_B : Eigen::Vector3d::Zero();
  }
  /// |q| - 1 of the last step before renormalisation.
  double normError() const { return norm_error_; }
  /// Integration steps since the last anchor (first sample, gap, jump back, set_state, reset).
  std::uint64_t steps() const { return steps_; }
  /// The method integrating: the configured one, or with `auto` the one its rule chose for the
  /// last step (cf4 before any).
  Integrator integrator() const { return integrator_; }
  /// The rule `auto` chooses by, or nullptr when a method was configured.
  const KinematicAutoRule* autoRule() const { return automatic_ ? &auto_rule_ : nullptr; }
  RateSamples rateSamples() const { return rate_samples_; }

  /// Samples filled in for lost ones (interval-averaged samples only), since construction.
  std::uint64_t filledSamples() const { return filled_samples_; }
  /// True when the state holds at stamps other than the samples' own (the stamp filter, or
  /// averages stamped at their start or midpoint): then time() says where.
  bool movesStamps() const {
    return stamp_filter_ != StampFilter::None || average_stamp_ != AverageStamp::End;
  }
  /// The stamp filter, or nullptr when `stamp_filter` is none.
  const SensorClockFilter* stampFilter() const {
    return stamp_filter_ == StampFilter::SensorClock ? &clock_ : nullptr;
  }

 private:
  StampOutcome addFiltered(double t, const Eigen::Vector3d& w_B);
  StampOutcome addStamped(double t, const Eigen::Vector3d& w_B);
  void restamp(const SensorClockFilter::Result& clock, const Eigen::Vector3d& w_B,
               StampOutcome outcome);
  void anchor(double t, const Eigen::Vector3d& w_B);
  StampOutcome integrate(const RateSample& sample);
  Eigen::Quaterniond restartFromAnchor(const RateWindow& window) const;
  StampOutcome fillAndIntegrate(const RateSample& sample);
  // The stream's nominal period, the median of its last intervals since the anchor, and whether
  // those intervals all lie within kRegularIntervals of it.
  struct NominalPeriod {
    double period = 0.0;
    bool regular = false;
  };
  std::optional<NominalPeriod> nominalPeriod() const;  // empty before three intervals
  bool dropout(double interval) const;
  int lostSamples(double interval) const;
  void rememberInterval(double interval);

  bool automatic_;  // `auto`: integrator_ follows auto_rule_
  KinematicAutoRule auto_rule_;
  bool filling_ = false;  // the sample integrating is filled in for a lost one
  Integrator integrator_;
  TimePolicy policy_;
  Eigen::Quaterniond initial_q_WB_;
  Eigen::Quaterniond q_WB_;
  Eigen::Quaterniond anchor_q_WB_;  // state at the anchor, for a method's start-up restart
  RateWindow window_;
  std::uint64_t samples_since_anchor_ = 0;
  bool anchored_ = false;
  double norm_error_ = 0.0;
  std::uint64_t steps_ = 0;
  RateSamples rate_samples_;
  int max_gap_fill_;
  StampFilter stamp_filter_;
  SensorClockFilter clock_;
  RestampCorrection restamp_;  // after clock_, whose memory it shares
  AverageStamp average_stamp_;
  IntervalEnds interval_ends_;
  std::uint64_t filled_samples_ = 0;
  std::array<double, 5> intervals_{};  // the last intervals integrated, for the nominal period
  std::size_t interval_count_ = 0;     // since the anchor
  double mean_interval_ = 0.0;         // the mean period since the anchor, for dropouts
  std::uint64_t mean_count_ = 0;       // intervals in it (at most kMeanIntervals)
};

}  // namespace attitude_propagator
