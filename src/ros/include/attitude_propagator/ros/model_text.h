// The line the node logs at start: the model, its integrator, the frames it publishes and its
// inputs. Pure: the wrapper logs it.
#pragma once

#include <string>

#include "attitude_propagator/config/parameters.h"
#include "attitude_propagator/engine.h"

namespace attitude_propagator {

/// "attitude_propagator: dynamic model ... (integrator ..., max_step ...), publishing F -> B at
/// R Hz; rate input ..., torque input on|off", or for the kinematic model "... per <rate_input>
/// message".
std::string modelText(const NodeConfig& config, const AttitudeEngine& engine);

}  // namespace attitude_propagator
