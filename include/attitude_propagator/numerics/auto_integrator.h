// `integrator: auto` on the kinematic model: the method is chosen per stream, online, by a
// bounded rule derived from the benchmark's real streams (docs/real_streams.md, "How `auto`
// chooses"; bench/kinematic_sweep.cpp). cf4 (the table's kinematic `auto`) unless the stream
// shows one of two things where the measurements put a lower-order method ahead of cf4 by more
// than 1.5x:
//   1. interval means filled in for lost samples (max_gap_fill) within the last
//      kFillWindow steps: exp2 (cf4's cubic through filled means is worse than exp2's pair);
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

#include <cstdint>

#include <Eigen/Core>

#include "attitude_propagator/numerics/integrator.h"
#include "attitude_propagator/numerics/kinematic_step.h"

namespace attitude_propagator {

class KinematicAutoRule {
 public:
  /// Samples the statistics weigh (the weight of a sample falls by e after this many).
  static constexpr double kMemory = 64.0;
  /// Samples seen before the jitter measure may switch the method.
  static constexpr std::uint64_t kWarmUp = 32;
  /// Steps after a filled sample during which exp2 integrates (cf4's window: 4 samples).
  static constexpr std::uint64_t kFillWindow = 4;
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
  /// An anchor: the next interval has no predecessor (the statistics are kept: they describe
  /// the stream).
  void restart();
  /// Forgets the stream.
  void reset();

 private:
  RateSamples kind_;
  bool stamps_filtered_;
  Integrator base_;  // the table's kinematic `auto` (cf4), looked up once
  Integrator choice_;
  std::uint64_t samples_ = 0;
  std::uint64_t steps_since_fill_;
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
