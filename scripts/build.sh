#!/usr/bin/env bash
# Builds the package in a catkin workspace (AP_WORKSPACE, default .workspace/ in the checkout,
# ignored by git), benchmarks included (ATTITUDE_PROPAGATOR_BUILD_BENCHMARKS, off in a plain
# catkin build). Extra arguments go to catkin_make (e.g. a target).
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
source_ros

stable_source >/dev/null
cd "$WORKSPACE"
# shellcheck disable=SC2046
catkin_make $(prepare_devel_space "$WORKSPACE") -DCMAKE_BUILD_TYPE=Release $(compiler_launcher) \
  -DPYTHON_EXECUTABLE=/usr/bin/python3 -DPython3_EXECUTABLE=/usr/bin/python3 \
  -DATTITUDE_PROPAGATOR_BUILD_BENCHMARKS=ON -j"$(nproc)" "$@"
