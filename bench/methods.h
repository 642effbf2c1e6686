// The integrators under test, read from the core's own list so that a new method is picked up
// by the benchmarks without an edit here (STYLE: one row in the core's table).
#pragma once

#include <sstream>
#include <string>
#include <vector>

#include "attitude_propagator/integrator.h"

namespace bench {

namespace ap = attitude_propagator;

/// Every kinematic (or dynamic) integrator but `auto`, in the core's order.
inline std::vector<ap::Integrator> methodsFor(ap::Model model) {
  std::vector<ap::Integrator> methods;
  std::istringstream names(ap::integratorNames());
  std::string name;
  while (names >> name) {
    const ap::Integrator m = ap::integratorFromName(name);
    if (m == ap::Integrator::Auto) continue;
    const bool fits =
        model == ap::Model::Kinematic ? ap::supportsKinematic(m) : ap::supportsDynamic(m);
    if (fits) methods.push_back(m);
  }
  return methods;
}

}  // namespace bench
