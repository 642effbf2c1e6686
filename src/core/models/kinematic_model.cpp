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

void KinematicModel::apply(const Input& input) {
  const double t = time_.coreTime(input.stamp);
  // time() is only defined once anchored (the window is empty before).
  const double t_before = kinematic_.anchored() ? kinematic_.time() : 0.0;
  const Eigen::Quaterniond q_before = kinematic_.orientation();
  const SensorClockFilter* filter = kinematic_.stampFilter();
  const std::uint64_t fallbacks = filter != nullptr ? filter->fallbacks() : 0;
  const StampOutcome outcome = kinematic_.addSample(t, input.value);
  if (filter != nullptr && filter->fallbacks() > fallbacks) {
    host_.note({EngineNote::StampFilterMisfit, input.source, input.stamp, filter->jitter(),
                filter->period()});
  }
  if (!host_.handleOutcome(outcome, input.source, input.stamp)) return;
  if (outcome == StampOutcome::Advanced) {
    // The step's own rotation drives the covariance, whatever the integrator did inside it.
    const double h = t - t_before;
    const Eigen::Vector3d w_step = logMap(q_before.conjugate() * kinematic_.orientation()) / h;
    host_.propagateCovariance(h, w_step, input.rate_covariance_B);
  } else if (outcome == StampOutcome::Anchored) {
    host_.anchorCovariance();  // the initial state again, as uncertain as configured
  }
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
