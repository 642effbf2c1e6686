// dynamic_reconfigure and the parameters: which parameters change live, what a change
// touches, and the values in force shown back in rqt_reconfigure. The wrapper validates the
// parameters asked for like those at start and applies them.
#pragma once

#include <optional>
#include <string>

#include "attitude_propagator/AttitudePropagatorConfig.h"
#include "attitude_propagator/config/parameters.h"
#include "attitude_propagator/engine.h"
#include "attitude_propagator/numerics/integrator.h"
#include "attitude_propagator/ros/log_text.h"

namespace attitude_propagator {

/// The parameters a live change asks for: those in force, with the live ones (the rate's
/// standard deviation, max_dt, torque_timeout, publish_tf, reverse_tf, integrator) from `live`.
Parameters liveParameters(const Parameters& in_force, const AttitudePropagatorConfig& live);

/// What a change from `now` to `next` touches.
struct LiveChange {
  bool engine_changes =
      false;                ///< the engine's: the rate's stddev, max_dt, torque_timeout, integrator
  bool tf_toggled = false;  ///< publish_tf
  bool child_changed = false;  ///< reverse_tf: our child frame
};
LiveChange liveChange(const Parameters& now, const Parameters& next);

/// Validates `p` as the parameters at start are and, when `change` touches the engine's,
/// reconfigures `engine` with them; on success `config` becomes them. Else the refusal (the
/// validator's or the engine's message), and neither changes.
std::string applyLive(const Parameters& p, const LiveChange& change, AttitudeEngine& engine,
                      NodeConfig& config);

/// What the log says of a change: refused (`error`, quoting the value asked for) or, when the
/// engine's parameters changed, those now in force (`integrator` the one resolved); nothing
/// else.
std::optional<LogLine> reconfigureText(const std::string& error, bool engine_changes,
                                       const Parameters& in_force, Integrator integrator);

/// The live values in force back into `live` (a refused change shows the values kept).
void showInForce(const Parameters& in_force, AttitudePropagatorConfig& live);

}  // namespace attitude_propagator
