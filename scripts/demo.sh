#!/usr/bin/env bash
# Installs what is missing, builds, and runs the demo.
# For now: the core library propagates the coning motion from a built-in 200 Hz rate stream
# and prints the orientation as it evolves next to the closed-form truth.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

bash "$REPO_DIR/scripts/install_deps.sh"
bash "$REPO_DIR/scripts/build.sh"
"${WORKSPACE}/devel/lib/attitude_propagator/kinematic_demo" "$@"
