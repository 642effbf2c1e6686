// The integrators under test, read from the core's table so that a new method is picked up by
// the benchmarks without an edit here.
#pragma once

#include <vector>

#include "attitude_propagator/numerics/integrator.h"

namespace bench {

namespace ap = attitude_propagator;

/// Every kinematic (or dynamic) integrator but `auto`, in the core's order.
inline std::vector<ap::Integrator> methodsFor(ap::Model model) { return ap::integratorsFor(model); }

/// Whether the method is the exact solution (the table's kExactFlow): judged by the independent
/// reference, since against the closed form it would score zero.
inline bool isExactSolution(ap::Integrator method) {
  return (ap::integratorInfo(method).keeps & ap::keeps::kExactFlow) != 0;
}

}  // namespace bench
