// The node's parameters for the tools, from the node's YAML (config/default.yaml and the scene
// files) and from `--set name=value`; the node reads the same files through rosparam.
#pragma once

#include <string>

#include "attitude_propagator/config/parameters.h"

namespace attitude_propagator {
namespace tools {

/// Reads a YAML map of node parameters into p. Unknown names and wrong types throw
/// std::invalid_argument naming the parameter, as the node's loader does.
void loadConfigFile(const std::string& path, Parameters& p);
/// Applies one `name=value`, the value in YAML flow syntax (`cf4`, `true`, `[1, 2, 3]`).
void applySetting(const std::string& assignment, Parameters& p);

}  // namespace tools
}  // namespace attitude_propagator
