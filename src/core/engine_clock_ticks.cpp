// The clock ticks for a run whose inputs' stamps drive the clock (a bag without /clock): the
// engine's grid budget decides how far one tick may go, so the rule lives with the budget.
#include <algorithm>

#include "attitude_propagator/engine.h"

namespace attitude_propagator {

std::vector<Stamp> AttitudeEngine::clockTicksTo(std::optional<Stamp> last, Stamp now) const {
  std::vector<Stamp> ticks;
  const double max_dt = timePolicyOf(config_).max_dt;
  if (last && now > *last && static_cast<double>(now - *last) * 1e-9 <= max_dt) {
    // Half the budget's grid periods per tick: a tick never finds more grid stamps due than
    // one call handles, whatever the rounding of the grid, so none waits for a later one.
    const double budget = static_cast<double>(config_.grid_budget);
    const auto step =
        std::max<Stamp>(1, static_cast<Stamp>(0.5 * budget / config_.publish_rate * 1e9));
    for (Stamp t = *last + step; t < now; t += step) ticks.push_back(t);
  }
  // A jump longer than max_dt (or back) stays one tick: clockTick judges it a gap (or a reset)
  // as it judges a clock record's jump.
  ticks.push_back(now);
  return ticks;
}

}  // namespace attitude_propagator
