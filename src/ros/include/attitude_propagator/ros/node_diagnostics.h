// The node's diagnostics status: its summary (level and message) by the first WARN rule that
// holds, and every counter and state as key/values, computed from the engine, the fix input,
// the tf-conflict watch and the wrapper's own counts. Pure (no node handle): the wrapper
// passes the diagnostic_updater's status and the wall time, and notes each input handed on.
#pragma once

#include <cstdint>
#include <initializer_list>
#include <optional>
#include <string>
#include <utility>

#include <diagnostic_updater/DiagnosticStatusWrapper.h>
#include <ros/time.h>

#include "attitude_propagator/config/parameters.h"
#include "attitude_propagator/engine.h"
#include "attitude_propagator/ros/fix_input.h"
#include "attitude_propagator/ros/input_window.h"
#include "attitude_propagator/ros/tf_conflict_watch.h"

namespace attitude_propagator {

/// The first lag (ROS time minus stamp, s; one per source, empty: none yet) further from ROS
/// time than kInputLagWarning, either way; empty if none is.
std::optional<double> lagBeyondWarning(std::initializer_list<std::optional<double>> lags);
/// The mean lag of a source whose inputs arrive further from ROS time than kInputLagWarning,
/// if any.
std::optional<double> inputLagBeyondWarning(const AttitudeEngine& engine);

/// The summary, by the first rule that holds: WARN when rate input is expected and none came
/// in the last second (`silence`: wall seconds since the last input, negative: none yet),
/// naming why when rates arrive but are refused (`refused`: the cause of the latest refusal in
/// that second, empty: none; "no rate input" only when none arrives);
/// WARN with the input window's problem; WARN with the fixes' warning; WARN when inputs lag
/// beyond kInputLagWarning (`lag`, from inputLagBeyondWarning); else OK "propagating".
void summarize(diagnostic_updater::DiagnosticStatusWrapper& status, bool expects_input,
               double silence, const std::string& window_problem, FixInput& fixes,
               const EngineCounters& c, std::optional<double> lag, const std::string& refused = "");

/// use_mag: the sphere the field reads lie on (AttitudeEngine::fieldFit), live while the sensor
/// is turned for a calibration: mag_bias_fit_reads; mag_bias_fit, its centre (T, body frame: the
/// mag_bias to give) and mag_bias_fit_stddev per axis, or "none" while the reads fix no sphere;
/// mag_bias_fit_determined, HardIronSphere::determined().
void addFieldFit(diagnostic_updater::DiagnosticStatusWrapper& status, const HardIronFit& fit);

class NodeDiagnostics {
 public:
  /// Diagnostics from wall time `now` on (the input rate's first interval starts there).
  explicit NodeDiagnostics(const ros::WallTime& now) : last_diagnosis_(now) {}

  /// An input handed to the engine at wall time `now`.
  void inputArrived(const ros::WallTime& now) { last_input_ = now; }
  /// A rate input refused before the engine at wall time `now`, and why (named in the summary
  /// while no rate is handed on).
  void inputRefused(const ros::WallTime& now, std::string cause) {
    last_refused_ = now;
    refused_cause_ = std::move(cause);
  }
  /// The /clock publishers of the two timelines last recognised (clockSourcesText), named
  /// while the engine sees two.
  void clockSources(std::string text) { clock_sources_ = std::move(text); }
  const std::string& clockSources() const { return clock_sources_; }
  /// Closes the one-second window of input counters when it is due (input_window.h).
  void closeInputWindow(const ros::WallTime& now, const AttitudeEngine& engine, double max_dt) {
    window_.closeInputWindow(now, engine.counters(), max_dt);
  }
  /// The summary and the key/values at wall time `now`; `callback_errors` counts the
  /// exceptions the wrapper caught.
  void diagnose(const ros::WallTime& now, const NodeConfig& config, const AttitudeEngine& engine,
                FixInput& fixes, const TfConflictWatch& tf, std::uint64_t callback_errors,
                diagnostic_updater::DiagnosticStatusWrapper& status);
  /// When diagnose() last ran.
  const ros::WallTime& lastDiagnosis() const { return last_diagnosis_; }

 private:
  std::uint64_t accepted_at_last_diagnosis_ = 0;
  ros::WallTime last_diagnosis_;
  ros::WallTime last_input_;
  ros::WallTime last_refused_;
  std::string refused_cause_;
  std::string clock_sources_;
  InputWindow window_;
};

}  // namespace attitude_propagator
