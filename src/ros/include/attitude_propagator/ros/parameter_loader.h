// Reads the node's private parameters into the core's Parameters struct (defaults live there).
#pragma once

#include <string>

#include <ros/node_handle.h>

#include "attitude_propagator/config/parameters.h"

namespace attitude_propagator {

/// Reads every private parameter of pnh that is set into a Parameters (unset ones keep the
/// struct's default) and validates them with the core.
/// Throws std::invalid_argument naming the parameter and the accepted values for an unknown
/// private parameter name, a value of the wrong type, or a value the core rejects. Warnings
/// (a frame parameter with tf1's leading '/') are logged with `log_prefix` (instance_log.h).
NodeConfig loadParameters(const ros::NodeHandle& pnh, const std::string& log_prefix = {});

}  // namespace attitude_propagator
