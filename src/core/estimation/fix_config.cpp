#include "attitude_propagator/estimation/fix_config.h"

namespace attitude_propagator {

const char* fixModeName(FixMode mode) { return mode == FixMode::Reset ? "reset" : "fuse"; }

}  // namespace attitude_propagator
