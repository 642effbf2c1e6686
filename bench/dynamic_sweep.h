// Work-precision sweep, stability map and long-run invariants of the dynamic integrators
// (docs/design.md §8).
#pragma once

#include <cstdio>
#include <vector>

#include "csv.h"
#include "dynamic_scenes.h"
#include "timing.h"

namespace bench {

/// Every dynamic method on every scene at every step of the scene (dopri5: over tolerances at
/// a fixed output step): one CSV row each. Sets each scene's max_rate from its truth.
void runDynamicSweep(std::vector<DynamicScene>& scenes, const TimingOptions& timing,
                     std::FILE* out);

/// Error after `duration` against |w| dt, log-spaced from 1e-3 to 10, torque-free scenes.
void runDynamicStability(DynamicScene scene, double duration, std::FILE* out);

/// Energy and |M| relative drift against time for every method at step h over a long run,
/// one row (method,dt,tolerance,t,energy_rel_drift,momentum_rel_drift,err_rad) every
/// `every` seconds.
void runInvariants(const DynamicScene& scene, double h, double duration, double every,
                   std::FILE* out);

}  // namespace bench
