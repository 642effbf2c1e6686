#include "attitude_propagator/models/kinematic_model.h"

#include <cmath>
#include <utility>
#include <variant>

#include "attitude_propagator/models/engine_config.h"
#include "attitude_propagator/numerics/quaternion.h"

namespace attitude_propagator {

KinematicModel::KinematicModel(const EngineConfig& config, PropagatorHost& host,
                               const TimeBase& time)
    : host_(host), time_(time), kinematic_(config.kinematic) {}

bool KinematicModel::submit(const Input& input) {
  apply(input);
  return true;  // every input changes the model, or may have
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

void KinematicModel::followCovariance(const Step& step, const Input& input) {
  if (step.outcome == StampOutcome::Advanced) {
    host_.propagateCovariance(step.h, step.w_step, input.rate_covariance_B);
  } else if (step.outcome == StampOutcome::Anchored) {
    host_.anchorCovariance();  // the initial state again, as uncertain as configured
  }
}

void KinematicModel::replay(const ModelStep& step) {
  // What was counted, noted and published stays as it was: only the state and its covariance.
  followCovariance(this->step(step.input), step.input);
}

void KinematicModel::apply(const Input& input) {
  const Step s = step(input);
  if (s.misfit) {
    const SensorClockFilter* filter = kinematic_.stampFilter();
    host_.note({EngineNote::StampFilterMisfit, input.source, input.stamp, filter->jitter(),
                filter->period()});
  }
  if (!host_.handleOutcome(s.outcome, input.source, input.stamp)) return;
  followCovariance(s, input);
  // With the stamp filter on, or averages stamped at their start or midpoint, the state holds
  // where the propagator put it, not at the input's stamp.
  const std::optional<Stamp> moved =
      kinematic_.movesStamps() ? time_.stampAt(kinematic_.time()) : std::nullopt;
  const Stamp stamp = moved ? *moved : input.stamp;
  host_.emitState(stamp);
  host_.inputApplied(input, stamp);
}

bool KinematicModel::restartInputOrder(Source /*source*/) {
  // The rates stamp the kinematic model's states: its time starts again with them (a looped
  // bag), from the initial state, and the outputs' stamps start again too.
  return true;
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
