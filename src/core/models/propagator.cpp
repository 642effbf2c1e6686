#include "attitude_propagator/models/propagator.h"

#include "attitude_propagator/models/dynamic_scheduler.h"
#include "attitude_propagator/models/engine_config.h"
#include "attitude_propagator/models/kinematic_model.h"

namespace attitude_propagator {

const TimePolicy& timePolicyOf(const EngineConfig& config) {
  return config.dynamic ? config.dynamic->time_policy : config.kinematic.time_policy;
}

std::unique_ptr<Propagator> makePropagator(const EngineConfig& config, const TimeBase& time) {
  if (config.model == Model::Dynamic) return std::make_unique<DynamicScheduler>(config, time);
  return std::make_unique<KinematicModel>(config, time);
}

}  // namespace attitude_propagator
