#!/usr/bin/env bash
# Mutation check of the node (src/ros), in the robustness tier after scripts/mutants.sh: writes
# the plausible bugs of test/mutants/mutants_ros.txt into schemata of their files (each behind a
# run-time switch, test/mutants/schemata.py) in a scratch copy of the package, builds the node
# once in a scratch catkin workspace, and runs for each mutant the rostests it names (`tests:`)
# with AP_MUTANT=<its number>; a mutant the compiler refuses in a schema is planted in the copy
# on its own (one file compiled, the wrapper library and the node relinked) and restored after.
# Every mutant must be killed (a rostest fails or runs past the timeout). The checkout is never
# modified.
#   bash scripts/mutants_ros.sh [--only ID]... [--timeout S] [results_dir]
#   bash scripts/mutants.sh --list --list-file mutants_ros.txt   the mutants, and whether each applies
# The scratch workspace ($MUTANTS_ROS_DIR/ws; default $AP_WORKSPACE/mutants_ros when
# AP_WORKSPACE is set, otherwise ~/.cache/attitude_propagator_mutants_ros, one place for every
# clone: it holds a copy, not the checkout) is kept: a later run, from this clone or another,
# copies only the files that changed and rebuilds only what they touch. Its first build
# configures the workspace and compiles the whole node. JUnit XML goes to results_dir (default
# $MUTANTS_ROS_DIR/results/mutants_ros.xml), one test case per mutant, a survivor failing.
# Environment: MUTANTS_ROS_DIR, MUTANTS_ROS_TIMEOUT (seconds per rostest, default 300).
# Exit status: 0 when every mutant is killed, 1 when one survives or does not apply, 2 when the
# build or an unmutated rostest fails.
set -uo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
source_ros

driver="$REPO_DIR/test/mutants/mutate.py"
dir="${MUTANTS_ROS_DIR:-${AP_WORKSPACE:+$AP_WORKSPACE/mutants_ros}}"
dir="${dir:-${XDG_CACHE_HOME:-$HOME/.cache}/attitude_propagator_mutants_ros}"
ws="$dir/ws"
package="$ws/src/attitude_propagator"
timeout="${MUTANTS_ROS_TIMEOUT:-300}"
# What the rostests run: the node and the nodelet (one library), the generated messages and
# services in C++ and Python, and the reconfigure server's generated code.
targets=(attitude_propagator_node attitude_propagator_ros attitude_propagator_generate_messages
  attitude_propagator_gencfg)

options=()
results=""
while [ $# -gt 0 ]; do
  case "$1" in
    --only | --timeout)
      [ $# -ge 2 ] || { echo "mutants_ros: $1 needs a value"; exit 2; }
      if [ "$1" = --timeout ]; then timeout="$2"; else options+=("$1" "$2"); fi
      shift
      ;;
    -h | --help)
      awk 'NR > 1 && !/^#/ { exit } NR > 1 { sub(/^# ?/, ""); print }' "${BASH_SOURCE[0]}"
      exit 0
      ;;
    -*) echo "mutants_ros: unknown option $1"; exit 2 ;;
    *) results="$1" ;;
  esac
  shift
done
results="${results:-$dir/results}"

start=$SECONDS
/usr/bin/python3 "$driver" list --list mutants_ros.txt "${options[@]}" >/dev/null || {
  /usr/bin/python3 "$driver" list --list mutants_ros.txt "${options[@]}" | grep ERROR
  exit 1
}
mkdir -p "$package" "$results"
# A copy, not a link: the mutants are written into it. Unchanged files keep their times, so the
# workspace rebuilds only what changed since the last run.
/usr/bin/python3 "$driver" sync --package "$REPO_DIR" "$package" || exit 2
echo "mutants_ros: building the node in $ws"
if command -v ccache >/dev/null; then export AP_COMPILER_LAUNCHER=ccache; fi
catkin=(catkin_make $(prepare_devel_space "$ws") -DCMAKE_BUILD_TYPE=Release $(compiler_launcher)
  -DCMAKE_EXPORT_COMPILE_COMMANDS=ON
  -DPYTHON_EXECUTABLE=/usr/bin/python3 -DPython3_EXECUTABLE=/usr/bin/python3 -j"$(nproc)")
# Configured and the generated headers made first (the compile commands, and what the node's
# files include), then each file's mutants written into one schema of it in the copy, then one
# build serves them all.
if ! { (cd "$ws" && "${catkin[@]}" attitude_propagator_generate_messages \
  attitude_propagator_gencfg >"$dir/build.log" 2>&1) &&
  /usr/bin/python3 "$driver" schemata "$REPO_DIR" "$package" "$ws/build" --list mutants_ros.txt \
    "${options[@]}" &&
  (cd "$ws" && "${catkin[@]}" "${targets[@]}" >>"$dir/build.log" 2>&1); }; then
  echo "mutants_ros: build failed; see $dir/build.log"
  tail -n 30 "$dir/build.log"
  exit 2
fi
echo "mutants_ros: built in $((SECONDS - start)) s"

/usr/bin/python3 "$driver" ros "$ws" "$results" --timeout "$timeout" --root "$REPO_DIR" \
  $(printf -- '--target %s ' "${targets[@]}") "${options[@]}"
status=$?
echo "mutants_ros: whole check took $((SECONDS - start)) s (exit $status)"
exit "$status"
