// Work-precision sweep and stability map of the kinematic integrators (docs/design.md §8).
#pragma once

#include <cstdio>
#include <vector>

#include "csv.h"
#include "kinematic_scenes.h"
#include "timing.h"

namespace bench {

/// Every kinematic method on every scene at every sample rate of the scene: one CSV row each.
void runKinematicSweep(const std::vector<KinematicScene>& scenes, const TimingOptions& timing,
                       std::FILE* out);

/// Error after a fixed time against |w| dt, log-spaced from 1e-3 to 10, on exact stamps and on
/// stamps received after an exponential latency of 0.1 ms and 1 ms mean and standard deviation
/// (column jitter_s: the standard deviation).
void runKinematicStability(const KinematicScene& scene, double duration, std::FILE* out);

/// Every kinematic method and `auto` on the streams real gyros deliver (point and averaged rates
/// at 100-1000 Hz, mid- and start-stamped means, receipt latency, lost samples, a noisy MEMS gyro,
/// on-chip filters with and without rate_delay, FIFO reads, a rate change), one CSV row each:
/// scene, stream, method, settings, largest error along the path against the truth at the
/// reported stamp, the error floor the stream's noise alone sets (empty if none), the largest
/// error after the first quarter of the path (a stamp filter has settled by then), and for
/// `auto` the methods it integrated with and its rule's jitter measure.
void runStreamSweep(const std::vector<KinematicScene>& scenes, std::FILE* out);

/// Aborts (returns false, with a message) if a scene's closed form does not satisfy
/// dq/dt = 1/2 q (x) (0, w_B): the truth must be checked before it judges anything.
bool checkClosedForm(const KinematicScene& scene);

}  // namespace bench
