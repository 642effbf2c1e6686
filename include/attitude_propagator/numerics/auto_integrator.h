// `integrator: auto` on the kinematic model: the method is chosen per stream, online, by a
// bounded rule derived from the benchmark's real streams (docs/real_streams.md, "How `auto`
// chooses"; bench/kinematic_sweep.cpp). cf4 (the table's kinematic `auto`) unless the stream
// shows one of two things where the measurements put a lower-order method ahead of cf4 by more
// than 1.5x:
//   1. interval means with samples filled in for lost ones (max_gap_fill): from the first fill
//      on, the candidate (cf4 or exp2) whose error predicted from the stream itself is the
//      smaller so far. Each step adds, in the world frame of the means integrated (exp), each
//      candidate's error per step, h^3/12 m x (its slope - the reference slope) for the middle
//      of the five newest means (the Bortz term; the reference: the derivative of the quartic
//      through the five means, exact to fourth order; cf4's slope: its one-sided quadratic,
//      exp2's: the last difference), and on a filled step a fill's error, h/4 times the fourth
//      difference of the five means (the cubic of the fill, left one out, against the mean it
//      leaves out). Each estimate is rotated into the world with the frame at the middle of
//      its own interval (the newest frame has turned by about 2 h |w| since: on a fast spin
//      that turns an error circling the precession axis onto the spin axis, where it would add
//      up). Both as means over about kMemory regular runs of five unfilled means, so that a
//      drift adds up and an oscillation averages out; the prediction is the largest norm of the
//      sum so far. A body whose rate turns fast (coning) drifts with cf4 as the fills do and
//      against exp2; a tumbling body's rate is smooth, the fills cost little and exp2's late
//      slope a lot. The prediction leaves out the error both candidates share and how each
//      responds to a fill beyond its first order (the benchmark's fast tumbling body with 5 %
//      of the means lost: 1.41x exp2's error, cf4 for the first steps). rk4 is no candidate:
//      on means its slope is exp2's last difference, so its predicted error would be exp2's
//      (measured, the two are within 1.08x of each other on the sweep's means with 5 % lost
//      and the held-out cone's with 10 %). That cone (333 Hz) stays at 1.69x rk4's error:
//      rk4 and exp2 integrating from the anchor gain from their first step, whose missing
//      coning correction lies against their drift on a pure coning; auto starts on cf4, and
//      even on exp2 from the first fill on it would be at 1.53x;
//   2. stamp jitter that moves the rates a lot while the body turns: the jitter measure
//        J = sigma_t |dw|_rms / (h |w|_rms),
//      the stamp noise sigma_t (from the second differences of the stamps) times the rate's
//      relative change per sample, above kJitterOn (off again below kJitterOff), and the mean
//      rate at least kTurning |w|_rms: rk4 on point samples, exp2 on interval means (cf4's
//      noise guard still amplifies such rate noise). A body that only vibrates keeps cf4: the
//      coning drift a lower-order method misses then accumulates about fixed axes, and cf4 is
//      best even with the jitter (a pure 50 Hz coning at 200 Hz with 0.1 ms jitter: rk4 3.5x
//      cf4's error), where a turning body spreads that drift over all directions.
//      Not with the stamp filter on: it removes the jitter J measures, and during its start-up
//      (raw stamps) J would rise and hold the lower-order method for its whole memory, where
//      the measurements keep cf4 within 1.5x of the best on every filtered stream.
// Every statistic is an exponentially weighted mean over about kMemory samples: O(1) memory
// and time per sample.
#pragma once

#include <array>
#include <cstdint>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "attitude_propagator/numerics/integrator.h"
#include "attitude_propagator/numerics/kinematic_step.h"

namespace attitude_propagator {

class KinematicAutoRule {
 public:
  /// Samples the statistics weigh (the weight of a sample falls by e after this many).
  static constexpr double kMemory = 64.0;
  /// Samples seen before the jitter measure may switch the method.
  static constexpr std::uint64_t kWarmUp = 32;
  /// The jitter measure J above which a lower-order method integrates, and below which cf4
  /// does again.
  static constexpr double kJitterOn = 2e-3;
  static constexpr double kJitterOff = 1e-3;
  /// The jitter rule needs the body to turn beyond its oscillation: |mean w| at least this
  /// share of |w|_rms. Otherwise (a vibrating body at rest) the coning drift rk4 misses
  /// accumulates about fixed axes and cf4 stays best even under the jitter.
  static constexpr double kTurning = 0.1;

  /// kind: what the rates mean; stamps_filtered: the sensor-clock stamp filter is on (the
  /// jitter rule is then off).
  KinematicAutoRule(RateSamples kind, bool stamps_filtered);

  /// The method for the step about to be integrated: the interval it spans, the rate at its
  /// end, and whether the sample was filled in for a lost one. The first step after an anchor
  /// has no previous interval (restart()).
  Integrator step(double interval, const Eigen::Vector3d& w_B, bool filled);
  /// The method the last step used (cf4 before any).
  Integrator choice() const { return choice_; }
  /// The jitter measure J (0 until a stamp second difference is known).
  double jitterMeasure() const;
  /// Interval means with fills: the largest error predicted for cf4 or exp2 since the first
  /// fill (rad; 0 before).
  double predictedError(Integrator method) const {
    return method == Integrator::Exp2 ? exp2_worst_ : cf4_worst_;
  }
  /// An anchor: the next interval has no predecessor (the statistics are kept: they describe
  /// the stream).
  void restart();
  /// Forgets the stream.
  void reset();

 private:
  // Interval means: the errors of the fills and of each candidate estimated from the five
  // newest means (a regular run without fills), in the frame of the means integrated, and
  // summed from the first fill on.
  void predictErrors(double interval, const Eigen::Vector3d& w_B, bool filled, bool regular,
                     double weight);
  void estimateErrors(double weight);

  RateSamples kind_;
  bool stamps_filtered_;
  Integrator base_;  // the table's kinematic `auto` (cf4), looked up once
  Integrator choice_;
  std::uint64_t samples_ = 0;
  // Interval means only: the five newest, oldest first, and how many in a row were regular and
  // not filled (the estimates need five).
  std::array<Eigen::Vector3d, 5> recent_{};
  std::uint64_t real_run_ = 0;
  Eigen::Quaterniond frame_ = Eigen::Quaterniond::Identity();  // the means integrated (exp)
  // ... at the start of the intervals of the three newest means, recent_[2..4], oldest first.
  std::array<Eigen::Quaterniond, 3> starts_{Eigen::Quaterniond::Identity(),
                                            Eigen::Quaterniond::Identity(),
                                            Eigen::Quaterniond::Identity()};
  bool filled_before_ = false;
  Eigen::Vector3d fill_drift_ = Eigen::Vector3d::Zero();  // a lone fill's error, world frame
  Eigen::Vector3d cf4_drift_ = Eigen::Vector3d::Zero();   // a step's error: cf4 ...
  Eigen::Vector3d exp2_drift_ = Eigen::Vector3d::Zero();  // ... and exp2, world frame
  // The errors predicted since the first fill, summed: the fills' and each candidate's own, and
  // the largest so far of each candidate's total.
  Eigen::Vector3d fills_sum_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d cf4_sum_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d exp2_sum_ = Eigen::Vector3d::Zero();
  double cf4_worst_ = 0.0;
  double exp2_worst_ = 0.0;
  bool lossy_ = false;
  bool have_interval_ = false;
  double last_interval_ = 0.0;
  Eigen::Vector3d last_w_ = Eigen::Vector3d::Zero();
  double mean_interval_ = 0.0;    // h
  double mean_d2_squared_ = 0.0;  // of the stamps' second differences: 6 sigma_t^2
  double mean_dw_squared_ = 0.0;  // |w_k - w_(k-1)|^2
  double mean_w_squared_ = 0.0;   // |w|^2
  Eigen::Vector3d mean_w_ = Eigen::Vector3d::Zero();
  bool jittered_ = false;
};

}  // namespace attitude_propagator
