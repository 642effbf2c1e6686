// The gravity and field counters under the names the node's diagnostics and the bag tools'
// summaries give them: accel_<name> and mag_<name>, <name> from AidingCounters::forEach, so the
// one list in the core is the list everywhere (docs/node.md's table follows it too).
#pragma once

#include <cstdint>
#include <string>

#include "attitude_propagator/engine.h"

namespace attitude_propagator {

/// Calls f(name, value) for each accel_* counter, then each mag_* counter.
template <class F>
void forEachAidingCounter(const EngineCounters& c, F&& f) {
  c.accel.forEach(
      [&f](const char* name, std::uint64_t value) { f(std::string("accel_") + name, value); });
  c.mag.forEach(
      [&f](const char* name, std::uint64_t value) { f(std::string("mag_") + name, value); });
}

}  // namespace attitude_propagator
