// What the engine is configured with: the model and its configuration, the time rules, the
// fixes and the aiding measurements. The models read it (makePropagator, reconfigure), so it
// lives in their room, below the engine (docs/design.md §2).
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>

#include <Eigen/Core>

#include "attitude_propagator/estimation/aiding.h"
#include "attitude_propagator/estimation/fix_config.h"
#include "attitude_propagator/models/dynamic_propagator.h"
#include "attitude_propagator/models/kinematic_propagator.h"
#include "attitude_propagator/numerics/integrator.h"
#include "attitude_propagator/time/source_timeline.h"  // Stamp

namespace attitude_propagator {

struct EngineConfig {
  Model model = Model::Kinematic;  ///< Kinematic or Dynamic (resolved)
  KinematicConfig kinematic;
  std::optional<DynamicConfig> dynamic;
  double publish_rate = 100.0;  ///< dynamic model: states at multiples of 1/publish_rate
  double rate_stddev = 0.0;     ///< rad/s, for inputs without a covariance
  /// Orientation uncertainty (rad) at an anchor of the initial state: P_B = stddev² I.
  double initial_orientation_stddev = 0.0;
  Eigen::Vector3d gyro_bias_B = Eigen::Vector3d::Zero();  ///< rad/s, until a bias sample
  /// Seconds by which a rate is older than its stamp (an on-chip filter's group delay, a fixed
  /// transport latency): rate stamps are moved back by it before anything else, so the states
  /// (and imu/data) carry the instant the rate describes. At least 0, at most max_dt.
  double rate_delay = 0.0;
  /// Seconds an input (or set_state) may be stamped ahead of the clock; further is refused, so
  /// tf never receives a stamp beyond it. Checked once a clock is known.
  double max_future = 1.0;
  /// Dynamic model: inputs stamped ahead of the clock wait, at most this many; past it the
  /// one stamped furthest ahead is dropped (counted).
  std::size_t max_pending = 4096;
  /// Dynamic model: grid stamps handled per call at most; the rest wait for the next call.
  std::size_t grid_budget = 1000;
  /// Dynamic model: integrator work (steps; dopri5 attempts) per call at most, summed over
  /// the grid stamps of the call: two propagator calls' worth (kDefaultStepBudget), well under
  /// a second of CPU, so a starved node catching up still answers services and SIGINT. The
  /// rest waits for the next call.
  std::uint64_t work_budget = std::uint64_t{1} << 18;
  /// Absolute attitude fixes and the gyro bias estimate.
  FixConfig fixes;
  /// Gravity and the magnetic field as measurements (kinematic model).
  AidingConfig aiding;
};

/// The settings the engine checks itself, at start and on reconfigure (the propagators check
/// their own): max_future, rate_delay (0 to max_dt), the fixes', the aiding's, and
/// estimate_gyro_bias with the kinematic model only. Throws std::invalid_argument naming the
/// setting and what it accepts.
void checkEngineSettings(const EngineConfig& c);
/// checkEngineSettings, and first the settings fixed at start: publish_rate and gyro_bias.
void checkEngineConfig(const EngineConfig& c);
/// rate_delay in nanoseconds.
Stamp rateDelayNs(const EngineConfig& c);
/// The rate noise per sample in force for inputs without a covariance: rate_stddev, or with
/// gravity or field measurements and no rate_stddev, kAidedRateStddev (else the covariance
/// would never grow between measurements and the gates would refuse every one).
Eigen::Matrix3d defaultRateCovariance(const EngineConfig& c);

}  // namespace attitude_propagator
