#!/usr/bin/env bash
# The test command, in two tiers (docs/testing.md says what each guards and how long it takes):
#   bash scripts/test.sh                the tests: installs what is missing, builds, runs every
#                                       gtest (core, message layer, wrapper, bag tools), every
#                                       rostest and the repository checks (scripts/run_suites.py:
#                                       two at a time where the clock does not judge)
#   bash scripts/test.sh --robustness   the robustness tier: the core suite under ASan + UBSan
#                                       (scripts/sanitize.sh), the fuzz regression inputs and the
#                                       fuzz targets for FUZZ_SECONDS (default 60; 0 skips the
#                                       fuzzing, not the regressions) from a seed printed each run
#                                       (scripts/fuzz.sh), and the whole mutation check: every
#                                       mutant of every list (scripts/mutants.sh, then
#                                       scripts/mutants_ros.sh for the node's)
#   bash scripts/test.sh --all          both, as .ci/run runs them
# Each stage runs under a time limit of its own (the table below): a stage past its limit is
# stopped and counted as a failed test named after it, so a loaded machine fails one stage
# loudly instead of running past CI's limit. AP_STAGE_LIMIT_SCALE (default 1) scales every limit.
# Ends with the time each stage took and one line "N passed, M failed" over everything run (every
# gtest case, rostest case and check, sanitized case, mutant, fuzz target run and regression
# input counts as one); exits non-zero if anything failed.
set -uo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

tier1=true
robustness=false
case "${1:-}" in
  "") ;;
  --robustness) tier1=false; robustness=true ;;
  --all) robustness=true ;;
  -h | --help)
    awk 'NR > 1 && !/^#/ { exit } NR > 1 { sub(/^# ?/, ""); print }' "${BASH_SOURCE[0]}"
    exit 0
    ;;
  *) echo "test.sh: unknown argument '$1' (accepted: --robustness, --all, --help)"; exit 2 ;;
esac

# Seconds each stage may take: about 1.3 to 1.5 times what it took from a fresh clone with a
# compiler cache that had not seen the sources on 2 cores (docs/testing.md; mutants 1095 s and
# mutants_ros 506 s with 264 + 9 mutants; mutants 2400 s for the 322 + 9 since: the bag tools'
# 34 mutants each run the bag suite, about 80 s, so they alone take some 1400 s on two workers,
# and a fresh clone builds the schemata first, 460 s with a cold cache); sanitize took 369 s
# cold, and 454 s from a fresh clone after a change to the core's headers (its build 379 s),
# so it has 600 s; fuzz_regressions 17 s. The limits of --all sum to 89.5 minutes, under CI's
# 90.
declare -A LIMIT=(
  [install]=240 [build]=720 [suites]=360
  [sanitize]=600 [fuzz_regressions]=180 [fuzz]=150 [mutants]=2400 [mutants_ros]=720
)
scale="${AP_STAGE_LIMIT_SCALE:-1}"
stages_dir="${WORKSPACE}/build/test_results_stages"
rm -rf "$stages_dir"
mkdir -p "$stages_dir"
timings=()

# stage NAME COMMAND...: runs COMMAND under NAME's limit; a stage past its limit, or one whose
# failure leaves no results to count (REQUIRED=1), is written as a failed JUnit case.
stage() {
  local name="$1" limit status start=$SECONDS
  shift
  limit="$(awk -v l="${LIMIT[$name]}" -v s="$scale" 'BEGIN { printf "%d", l * s }')"
  echo "== $name (limit $limit s)"
  timeout --kill-after=30 "$limit" "$@"
  status=$?
  local spent=$((SECONDS - start)) why=""
  if [ "$status" -eq 124 ] || [ "$status" -eq 137 ]; then
    why="stopped at its time limit of $limit s (a loaded machine? docs/testing.md)"
  elif [ "$status" -ne 0 ] && [ "${REQUIRED:-0}" = 1 ]; then
    why="failed (exit $status)"
  fi
  timings+=("$(printf '%-17s %5d s  (limit %d s)%s' "$name" "$spent" "$limit" "${why:+  $why}")")
  if [ -n "$why" ]; then
    echo "== $name: FAILED: $why"
    printf '<?xml version="1.0" encoding="utf-8"?>\n<testsuites><testsuite name="stages" tests="1" failures="1"><testcase classname="stages" name="%s"><failure message="%s"/></testcase></testsuite></testsuites>\n' \
      "$name" "$why" >"$stages_dir/$name.xml"
  fi
  return "$status"
}

finish() {
  echo "== stage times"
  printf '  %s\n' "${timings[@]}"
  /usr/bin/python3 "$REPO_DIR/scripts/count_test_results.py" --stages "$stages_dir" "$@"
}

REQUIRED=1 stage install bash "$REPO_DIR/scripts/install_deps.sh" || { finish; exit 1; }
source_ros
result_dirs=()

if $tier1; then
  results="${WORKSPACE}/build/test_results/attitude_propagator"
  rm -rf "$results"
  # The package and every test program in one catkin_make (one configure check, not two).
  log="$WORKSPACE/build.log"
  REQUIRED=1 stage build bash -c "bash '$REPO_DIR/scripts/build.sh' all tests >'$log' 2>&1" ||
    { tail -n 40 "$log"; finish; exit 1; }
  result_dirs+=("$results")
  stage suites /usr/bin/python3 "$REPO_DIR/scripts/run_suites.py" "$WORKSPACE/build" \
    --jobs "$(nproc)"
fi

if $robustness; then
  robust="${WORKSPACE}/build/test_results_robustness"
  rm -rf "$robust"
  result_dirs+=("$robust/sanitize" "$robust/mutants" "$robust/mutants_ros")
  stage sanitize bash "$REPO_DIR/scripts/sanitize.sh" "$robust/sanitize"
  if have_libfuzzer; then
    result_dirs+=("$robust/fuzz")
    stage fuzz_regressions bash "$REPO_DIR/scripts/fuzz.sh" --regressions --junit "$robust/fuzz"
    fuzz_seconds="${FUZZ_SECONDS:-60}"
    if [ "$fuzz_seconds" -gt 0 ]; then
      LIMIT[fuzz]=$((LIMIT[fuzz] + fuzz_seconds - 60))
      stage fuzz bash "$REPO_DIR/scripts/fuzz.sh" --junit "$robust/fuzz" "$fuzz_seconds"
    fi
  else
    echo "fuzz: skipped (clang++ with libFuzzer not available)"
  fi
  # Every mutant of the gtest lists must fail its layer's suite, every mutant of the node's list
  # the rostests it names (a survivor counts as a failed test).
  stage mutants bash "$REPO_DIR/scripts/mutants.sh" "$robust/mutants"
  stage mutants_ros bash "$REPO_DIR/scripts/mutants_ros.sh" "$robust/mutants_ros"
fi

finish "${result_dirs[@]}"
