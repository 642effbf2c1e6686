// One state per stamp (docs/design.md §6.6): the rule the engine publishes by, and the one the
// dynamic model's grid asks before it advances to a stamp, so the two cannot disagree.
#pragma once

#include <optional>

#include "attitude_propagator/time/source_timeline.h"

namespace attitude_propagator {

/// Whether a state stamped `stamp` may be handed on: stamps increase strictly, so only one
/// after the last published (any stamp before the first).
bool publishable(Stamp stamp, const std::optional<Stamp>& last_published);

}  // namespace attitude_propagator
