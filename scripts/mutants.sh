#!/usr/bin/env bash
# Mutation check of the core library: plants each plausible bug of test/mutants/mutants.txt in
# the core sources, one at a time, and runs the core gtest suite (test/core) on it; every
# mutant must be killed (a test fails, the suite crashes or runs past the timeout).
#   bash scripts/mutants.sh [--only ID]... [--jobs N] [--timeout S] [results_dir]
#   bash scripts/mutants.sh --list [--only ID]...   the mutants, and whether each still applies
# The sources are copied to a scratch folder and built once with plain CMake
# (test/mutants/CMakeLists.txt); each mutant then compiles its one file and relinks
# (test/mutants/mutate.py). The checkout is never modified. JUnit XML goes to results_dir
# (default $MUTANTS_DIR/results), one test case per mutant, a survivor failing.
# Environment: MUTANTS_DIR (default $AP_WORKSPACE/mutants), MUTANTS_JOBS (default: the cores),
# MUTANTS_TIMEOUT (seconds per suite run, default 30), CXX (default g++).
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
results=""
listing=false
while [ $# -gt 0 ]; do
  case "$1" in
    --list) listing=true ;;
    --only | --jobs | --timeout)
      [ $# -ge 2 ] || { echo "mutants: $1 needs a value"; exit 2; }
      if [ "$1" = --jobs ]; then jobs="$2"; else options+=("$1" "$2"); fi
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
  exec /usr/bin/python3 "$driver" list --root "$REPO_DIR" "${options[@]}"
fi
results="${results:-$dir/results}"
mkdir -p "$build" "$results"
rm -f "$results/mutants.xml"

start=$SECONDS
/usr/bin/python3 "$driver" sync "$REPO_DIR" "$scratch" || exit 2
forget_other_source "$build" "$scratch/test/mutants"
echo "mutants: building the core and its suite in $build"
if ! { cmake -S "$scratch/test/mutants" -B "$build" -G "Unix Makefiles" \
  -DCMAKE_CXX_COMPILER="${CXX:-g++}" -DMUTANT_SLOTS="$jobs" >"$build/cmake.log" 2>&1 &&
  cmake --build "$build" -j "$(nproc)" >"$build/build.log" 2>&1; }; then
  echo "mutants: build failed; see $build/cmake.log and $build/build.log"
  tail -n 30 "$build/build.log" 2>/dev/null
  exit 2
fi
echo "mutants: built in $((SECONDS - start)) s"

/usr/bin/python3 "$driver" run "$build" "$results" --root "$scratch" --jobs "$jobs" \
  --timeout "${MUTANTS_TIMEOUT:-30}" "${options[@]}"
status=$?
echo "mutants: whole check took $((SECONDS - start)) s (exit $status)"
exit "$status"
