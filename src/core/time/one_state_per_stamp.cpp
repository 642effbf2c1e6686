#include "attitude_propagator/time/one_state_per_stamp.h"

namespace attitude_propagator {

bool publishable(Stamp stamp, const std::optional<Stamp>& last_published) {
  return !last_published || stamp > *last_published;
}

}  // namespace attitude_propagator
