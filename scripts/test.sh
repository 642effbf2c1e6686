#!/usr/bin/env bash
# Builds the package and runs every test: the core's gtest suite, the rostest integration
# tests, and the repository checks. Ends with a line "N passed, M failed"; exits non-zero if
# anything failed.
set -uo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

bash "$REPO_DIR/scripts/install_deps.sh" || exit 1
bash "$REPO_DIR/scripts/build.sh" || { echo "0 passed, 1 failed"; exit 1; }
source_ros
cd "$WORKSPACE"
catkin_make -j"$(nproc)" tests >/dev/null || { echo "0 passed, 1 failed"; exit 1; }
results="${WORKSPACE}/build/test_results/attitude_propagator"
rm -rf "$results"
catkin_make -j1 run_tests 2>&1 | tail -n 80

# The repository checks (test/checks) run inside run_tests and are counted with the rest.
/usr/bin/python3 "$REPO_DIR/scripts/count_test_results.py" "$results"
