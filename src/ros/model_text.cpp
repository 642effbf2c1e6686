#include "attitude_propagator/ros/model_text.h"

#include "attitude_propagator/ros/log_text.h"

namespace attitude_propagator {

std::string modelText(const NodeConfig& config, const AttitudeEngine& engine) {
  const auto& p = config.parameters;
  if (engine.dynamicModel()) {
    return formatted(
        "attitude_propagator: dynamic model %s (integrator %s, max_step %g s), "
        "publishing %s -> %s at %g Hz; rate input %s, torque input %s",
        engine.modelName().c_str(), integratorName(engine.integrator()).c_str(),
        config.dynamic->max_step, p.fixed_frame.c_str(), p.body_frame.c_str(), p.publish_rate,
        p.rate_input.c_str(), config.torque_input ? "on" : "off");
  }
  return formatted(
      "attitude_propagator: kinematic model (integrator %s), publishing %s -> %s per "
      "%s message",
      integratorName(engine.integrator()).c_str(), p.fixed_frame.c_str(), p.body_frame.c_str(),
      p.rate_input.c_str());
}

}  // namespace attitude_propagator
