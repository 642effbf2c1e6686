#include "attitude_propagator/models/kinematic_model.h"

#include <cmath>
#include <utility>
#include <variant>

#include "attitude_propagator/models/engine_config.h"
#include "attitude_propagator/numerics/quaternion.h"

namespace attitude_propagator {

KinematicModel::KinematicModel(const EngineConfig& config, const TimeBase& time)
    : time_(time), kinematic_(config.kinematic) {}

ModelResult KinematicModel::submit(const Input& input, std::optional<Stamp> /*clock*/) {
  const Step s = step(input);
  ModelResult r;
  r.outcome = s.outcome;
  r.source = input.source;
  r.stamp = input.stamp;
  r.input = &input;  // every input changes the model, or may have
  r.keep_step = true;
  if (s.misfit) {
    const SensorClockFilter* filter = kinematic_.stampFilter();
    r.note = EngineNote{EngineNote::StampFilterMisfit, input.source, input.stamp, filter->jitter(),
                        filter->period()};
  }
  if (!stateHoldsAtStamp(s.outcome)) return r;
  followCovariance(s, r);
  // With the stamp filter on, or averages stamped at their start or midpoint, the state holds
  // where the propagator put it, not at the input's stamp.
  const std::optional<Stamp> moved =
      kinematic_.movesStamps() ? time_.stampAt(kinematic_.time()) : std::nullopt;
  if (moved) r.stamp = *moved;
  r.publish = true;
  r.hand_on = true;
  return r;
}

std::optional<double> KinematicModel::savedTime() const {
  if (!kinematic_.anchored()) return std::nullopt;
  return kinematic_.time();
}

void KinematicModel::restore(const ModelSnapshot& from) {
  if (const auto* saved = std::get_if<KinematicPropagator>(&from)) kinematic_ = *saved;
}

KinematicModel::Step KinematicModel::step(const Input& input) {
  const double t = time_.coreTime(input.stamp);
  // time() is only defined once anchored (the window is empty before).
  const double t_before = kinematic_.anchored() ? kinematic_.time() : 0.0;
  const Eigen::Quaterniond q_before = kinematic_.orientation();
  const SensorClockFilter* filter = kinematic_.stampFilter();
  const std::uint64_t fallbacks = filter != nullptr ? filter->fallbacks() : 0;
  Step s;
  s.outcome = kinematic_.addSample(t, input.value);
  s.misfit = filter != nullptr && filter->fallbacks() > fallbacks;
  if (s.outcome == StampOutcome::Advanced) {
    // The step's own rotation drives the covariance, whatever the integrator did inside it.
    s.h = t - t_before;
    s.w_step = logMap(q_before.conjugate() * kinematic_.orientation()) / s.h;
  }
  return s;
}

void KinematicModel::followCovariance(const Step& step, ModelResult& result) {
  if (step.outcome == StampOutcome::Advanced) {
    result.covariance = ModelResult::Covariance::Step;
    result.h = step.h;
    result.w_step = step.w_step;
  } else if (step.outcome == StampOutcome::Anchored) {
    // The initial state again, as uncertain as configured.
    result.covariance = ModelResult::Covariance::Anchor;
  }
}

ModelResult KinematicModel::replay(const ModelStep& step) {
  // The live step again: the engine keeps only its covariance.
  return submit(step.input, std::nullopt);
}

Propagator::InputOrderRestart KinematicModel::restartInputOrder(Source /*source*/) {
  // The rates stamp the kinematic model's states: its time starts again with them (a looped
  // bag), from the initial state, and the outputs' stamps start again too.
  return {true, 0};
}

void KinematicModel::reconfigure(const EngineConfig& next) {
  KinematicPropagator k(next.kinematic);
  if (kinematic_.anchored()) {
    k.setState(kinematic_.time(), kinematic_.orientation(), kinematic_.rate());
  }
  kinematic_ = std::move(k);
}

EngineState KinematicModel::state() const {
  EngineState s;
  s.q_WB = kinematic_.orientation();
  s.w_B = kinematic_.rate();
  s.norm_error = kinematic_.normError();
  s.steps = kinematic_.steps();
  return s;
}

}  // namespace attitude_propagator
