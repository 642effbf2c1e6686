#!/usr/bin/env bash
# Mutation check of the core, the message layer and the bag tools: plants each plausible bug of
# test/mutants/mutants.txt (src/core, src/config), mutants_messages.txt (src/messages) and
# mutants_tools.txt (src/tools), or with --list-file of the named lists only, in its source, one
# at a time, and runs the gtest suite that must notice it: the core suite (test/core), the
# message layer's (test/messages), or the bag tools' (test/bag, on the tools rebuilt with the
# mutant). Every mutant must be killed (a test fails, the suite crashes or runs past the
# timeout). The node's list (mutants_ros.txt) is scripts/mutants_ros.sh's.
#   bash scripts/mutants.sh [--list-file NAME]... [--only ID]... [--jobs N] [--timeout S] [results_dir]
#   bash scripts/mutants.sh --list [--list-file NAME]... [--only ID]...
#                                  the mutants of every list, and whether each still applies
# The sources are copied to a scratch folder, each file's mutants are written into one schema of
# it there (every mutant behind a run-time switch, test/mutants/schemata.py), and the copy is
# built once with plain CMake (test/mutants/CMakeLists.txt): a mutant in a schema is one run of
# its suite with AP_MUTANT=<its number>; a mutant the compiler refuses in a schema compiles its
# one file and relinks the programs that hold it (test/mutants/mutate.py). The checkout is never
# modified. The message layer and
# the tools need the package's generated message headers: those of the catkin workspace
# ($AP_WORKSPACE/devel/include), generated first when missing. JUnit XML goes to results_dir
# (default $MUTANTS_DIR/results), one test case per mutant, a survivor failing.
# Environment: MUTANTS_DIR (default $AP_WORKSPACE/mutants), MUTANTS_JOBS (default: the cores),
# MUTANTS_TIMEOUT (seconds per run of the core or message suite, default 30),
# MUTANTS_BAG_TIMEOUT (seconds per run of the bag tools' suite, default 300), CXX (default g++).
# Exit status: 0 when every mutant is killed, 1 when one survives or does not apply (the list
# must track the code), 2 when the build or the unmutated suite fails.
set -uo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

driver="$REPO_DIR/test/mutants/mutate.py"
dir="${MUTANTS_DIR:-$WORKSPACE/mutants}"
scratch="$dir/src"
build="$dir/build"
jobs="${MUTANTS_JOBS:-$(nproc)}"

options=()
selection=()
results=""
listing=false
while [ $# -gt 0 ]; do
  case "$1" in
    --list) listing=true ;;
    --only | --jobs | --timeout | --list-file)
      [ $# -ge 2 ] || { echo "mutants: $1 needs a value"; exit 2; }
      case "$1" in
        --jobs) jobs="$2" ;;
        --timeout) options+=("$1" "$2") ;;
        --list-file) selection+=(--list "$2") ;;
        *) selection+=("$1" "$2") ;;
      esac
      shift
      ;;
    -h | --help)
      awk 'NR > 1 && !/^#/ { exit } NR > 1 { sub(/^# ?/, ""); print }' "${BASH_SOURCE[0]}"
      exit 0
      ;;
    -*) echo "mutants: unknown option $1"; exit 2 ;;
    *) results="$1" ;;
  esac
  shift
done

[[ "$jobs" =~ ^[1-9][0-9]*$ ]] || { echo "mutants: --jobs: a positive whole number"; exit 2; }
if $listing; then
  exec /usr/bin/python3 "$driver" list --root "$REPO_DIR" "${selection[@]}"
fi
# The suites the selected mutants need: core, messages, tools.
groups="$(/usr/bin/python3 "$driver" groups --root "$REPO_DIR" "${selection[@]}")" || {
  echo "$groups"
  exit 2
}
targets=()
message_include=""
for group in $groups; do
  case "$group" in
    core) targets+=(core_tests_mutants) ;;
    messages) targets+=(messages_tests_mutants) ;;
    tools) targets+=(bag_tools_tests_mutants) ;;
  esac
  if [ "$group" != core ]; then message_include="$WORKSPACE/devel/include"; fi
done
if [ -n "$message_include" ] && [ ! -f "$message_include/attitude_propagator/AttitudeState.h" ]; then
  echo "mutants: generating the messages in $WORKSPACE"
  bash "$REPO_DIR/scripts/build.sh" attitude_propagator_generate_messages >/dev/null || exit 2
fi
# The bag suite also runs the package's Python programs (scene_publisher imports its messages):
# the workspace's environment, as catkin's run_tests gives it.
if [ -n "$message_include" ]; then
  source_ros
  source_workspace
fi
results="${results:-$dir/results}"
mkdir -p "$build" "$results"
rm -f "$results/mutants.xml"

start=$SECONDS
/usr/bin/python3 "$driver" sync "$REPO_DIR" "$scratch" || exit 2
forget_other_source "$build" "$scratch/test/mutants"
echo "mutants: building the suites ($(echo $groups)) in $build"
# The compile commands the driver runs by hand (schemata, slots) get the cache in front too.
if command -v ccache >/dev/null; then export AP_COMPILER_LAUNCHER=ccache; fi
# shellcheck disable=SC2046
if ! cmake -S "$scratch/test/mutants" -B "$build" -G "Unix Makefiles" $(compiler_launcher) \
  -DCMAKE_CXX_COMPILER="${CXX:-g++}" -DMUTANT_SLOTS="$jobs" \
  -DMUTANTS_MESSAGE_INCLUDE="$message_include" >"$build/cmake.log" 2>&1; then
  echo "mutants: configuring failed; see $build/cmake.log"
  tail -n 30 "$build/cmake.log"
  exit 2
fi
# Every file's mutants into one schema each, in the scratch copy (test/mutants/schemata.py).
/usr/bin/python3 "$driver" schemata "$REPO_DIR" "$scratch" "$build" --jobs "$jobs" \
  "${selection[@]}" || exit 2
if ! cmake --build "$build" -j "$(nproc)" --target "${targets[@]}" >"$build/build.log" 2>&1; then
  echo "mutants: build failed; see $build/cmake.log and $build/build.log"
  tail -n 30 "$build/build.log" 2>/dev/null
  exit 2
fi
echo "mutants: built in $((SECONDS - start)) s"

/usr/bin/python3 "$driver" run "$build" "$results" --root "$REPO_DIR" --jobs "$jobs" \
  --timeout "${MUTANTS_TIMEOUT:-30}" --bag-timeout "${MUTANTS_BAG_TIMEOUT:-300}" \
  "${options[@]}" "${selection[@]}"
status=$?
echo "mutants: whole check took $((SECONDS - start)) s (exit $status)"
exit "$status"
