#include "attitude_propagator/ros/node_diagnostics.h"

#include <cmath>
#include <cstdint>
#include <optional>

namespace attitude_propagator {

std::optional<double> lagBeyondWarning(std::initializer_list<std::optional<double>> lags) {
  for (const std::optional<double>& lag : lags) {
    if (lag && std::abs(*lag) > kInputLagWarning) return lag;
  }
  return std::nullopt;
}

std::optional<double> inputLagBeyondWarning(const AttitudeEngine& engine) {
  return lagBeyondWarning({engine.inputLag(Source::Imu), engine.inputLag(Source::Twist),
                           engine.inputLag(Source::Torque)});
}

void summarize(diagnostic_updater::DiagnosticStatusWrapper& status, bool expects_input,
               double silence, const std::string& window_problem, FixInput& fixes,
               const EngineCounters& c, std::optional<double> lag, const std::string& refused) {
  if (expects_input && (silence < 0.0 || silence > 1.0) && !refused.empty()) {
    status.summary(diagnostic_msgs::DiagnosticStatus::WARN, "rate input refused: " + refused);
  } else if (expects_input && (silence < 0.0 || silence > 1.0)) {
    status.summary(diagnostic_msgs::DiagnosticStatus::WARN, "no rate input in the last second");
  } else if (!window_problem.empty()) {
    status.summary(diagnostic_msgs::DiagnosticStatus::WARN, window_problem);
  } else if (const std::string warning = fixes.warning(c); !warning.empty()) {
    status.summary(diagnostic_msgs::DiagnosticStatus::WARN, warning);
  } else if (lag) {
    status.summaryf(diagnostic_msgs::DiagnosticStatus::WARN,
                    "inputs arrive %.3f s %s ROS time (sensor clock skewed, or a queue): tf "
                    "lookups at now will miss",
                    std::abs(*lag), *lag > 0.0 ? "behind" : "ahead of");
  } else {
    status.summary(diagnostic_msgs::DiagnosticStatus::OK, "propagating");
  }
}

void addFieldFit(diagnostic_updater::DiagnosticStatusWrapper& status, const HardIronFit& fit) {
  status.add("mag_bias_fit_reads", fit.count());
  const std::optional<HardIronSphere> sphere = fit.solve();
  if (!sphere) {
    status.add("mag_bias_fit", "none");
    status.add("mag_bias_fit_stddev", "none");
    status.add("mag_bias_fit_determined", false);
    return;
  }
  const Eigen::Vector3d& c = sphere->centre;
  const Eigen::Vector3d& s = sphere->centre_stddev;
  status.addf("mag_bias_fit", "[%.3g, %.3g, %.3g]", c.x(), c.y(), c.z());
  status.addf("mag_bias_fit_stddev", "[%.2g, %.2g, %.2g]", s.x(), s.y(), s.z());
  status.add("mag_bias_fit_determined", sphere->determined());
}

void NodeDiagnostics::diagnose(const ros::WallTime& now, const NodeConfig& config,
                               const AttitudeEngine& engine, FixInput& fixes,
                               const TfConflictWatch& tf, std::uint64_t callback_errors,
                               diagnostic_updater::DiagnosticStatusWrapper& status) {
  const EngineCounters& c = engine.counters();
  const double dt = (now - last_diagnosis_).toSec();
  const double input_rate = dt > 0.0 ? (c.accepted - accepted_at_last_diagnosis_) / dt : 0.0;
  last_diagnosis_ = now;
  accepted_at_last_diagnosis_ = c.accepted;

  const bool expects_input = config.rate_input != RateInput::None;
  const double silence = last_input_.isZero() ? -1.0 : (now - last_input_).toSec();
  const bool refused_lately = !last_refused_.isZero() && (now - last_refused_).toSec() <= 1.0;
  summarize(status, expects_input, silence, window_.problem(), fixes, c,
            inputLagBeyondWarning(engine), refused_lately ? refused_cause_ : std::string());
  if (const std::optional<Stamp> other = engine.otherClock()) {
    // The cause of what else goes wrong (jumps, refused stamps): named first.
    const double apart = static_cast<double>(*engine.clockNow() - *other) * 1e-9;
    const std::string sources = clock_sources_.empty() ? "publishers unknown" : clock_sources_;
    status.mergeSummaryf(diagnostic_msgs::DiagnosticStatus::WARN,
                         "ROS time takes turns between two timelines %.3f s apart (%s): the later "
                         "followed, the other ignored",
                         apart, sources.c_str());
  }
  const KinematicPropagator* kinematic = engine.kinematic();
  const SensorClockFilter* filter = kinematic != nullptr ? kinematic->stampFilter() : nullptr;
  if (filter != nullptr && filter->misfit()) {
    status.mergeSummaryf(diagnostic_msgs::DiagnosticStatus::WARN,
                         "stamp_filter: the stamps do not fit one sensor period (jitter %.3g ms, "
                         "period %.3g ms): their receipt stamps are used",
                         filter->jitter() * 1e3, filter->period() * 1e3);
  }
  const EngineState state = engine.state();
  status.add("model", engine.modelName());
  status.add("integrator", integratorName(engine.integrator()));
  status.add("input_rate_hz", input_rate);
  // Every engine counter under its name, in the core table's order (docs/node.md, "Counters").
  forEachEngineCounter(
      c, [&status](const CounterInfo& info, std::uint64_t value) { status.add(info.name, value); });
  status.add("pending", engine.pending());
  if (const std::optional<Stamp> other = engine.otherClock()) {
    status.add("clock_other_timeline_s", static_cast<double>(*other) * 1e-9);
    status.add("clock_sources", clock_sources_);
  }
  // Mean ROS time minus stamp on arrival: a constant skew between the sensor's clock and
  // this machine's shows here (WARN above kInputLagWarning).
  for (Source source : {Source::Imu, Source::Twist, Source::Torque}) {
    if (const std::optional<double> lag = engine.inputLag(source)) {
      status.add(source == Source::Torque ? "torque_lag_s" : "rate_lag_s", *lag);
    }
  }
  status.add("callback_errors", callback_errors);
  status.add("tf_conflicts", tf.conflicts());
  status.add("tf_stopped", tf.stopped());
  status.add("tf_resumes", tf.resumes());
  const Eigen::Vector3d& b = engine.gyroBias();
  status.addf("gyro_bias", "[%g, %g, %g]", b.x(), b.y(), b.z());
  fixes.diagnose(status, engine);
  status.add("tilt_known", engine.tiltKnown());
  if (config.parameters.use_mag) addFieldFit(status, engine.fieldFit());
  if (const KinematicPropagator* k = kinematic) {
    status.add("rate_samples", config.parameters.rate_samples);
    status.add("filled_samples", k->filledSamples());
    if (const SensorClockFilter* f = filter) {
      status.add("stamp_filter_period_s", f->period());
      status.add("stamp_filter_offset_s", f->offset());
      status.add("stamp_filter_jitter_s", f->jitter());
      status.add("stamp_filter_rejected", f->rejected());
      status.add("stamp_filter_missed_periods", f->missed());
      status.add("stamp_filter_restarts", f->restarts());
      status.add("stamp_batch", f->batchSize());
      status.add("stamp_filter_unfiltered", f->unfiltered());
      status.add("stamp_filter_misfit", f->misfit());
      status.add("stamp_filter_fallbacks", f->fallbacks());
      status.add("stamp_filter_moved", f->moved());
      status.add("stamp_filter_largest_later_s", f->largestLater());
      status.add("stamp_filter_largest_earlier_s", f->largestEarlier());
    }
  }
  status.add("norm_error", state.norm_error);
  if (engine.dynamicModel()) {
    status.add("kinetic_energy", state.kinetic_energy);
    status.add("energy_drift", engine.energyDrift());
    status.add("momentum_drift", engine.momentumDrift());
  }
}

}  // namespace attitude_propagator
