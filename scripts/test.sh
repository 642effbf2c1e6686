#!/usr/bin/env bash
# Builds the package and runs every test: the core's gtest suite, the rostest integration
# tests, the repository checks, the core suite again under ASan + UBSan (scripts/sanitize.sh),
# the mutation check of the core, the message layer and the bag tools (scripts/mutants.sh) and
# of the node (scripts/mutants_ros.sh), and, when clang with libFuzzer is present, the fuzz
# regression inputs and each fuzz target for FUZZ_SECONDS (default 60; 0 skips the fuzzing,
# not the regressions; scripts/fuzz.sh).
# Ends with a line "N passed, M failed" (every gtest case, sanitized ones too, every mutant,
# and every fuzz target run or regression input counts as one); exits non-zero if anything
# failed.
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

# Robustness: the core suite under sanitizers, the mutation check, then the fuzz targets (see
# scripts/fuzz.sh).
robustness="${WORKSPACE}/build/test_results_robustness"
rm -rf "$robustness"
result_dirs=("$results" "$robustness/sanitize" "$robustness/mutants" "$robustness/mutants_ros")
bash "$REPO_DIR/scripts/sanitize.sh" "$robustness/sanitize"
# Mutation check: each plausible bug of test/mutants/mutants.txt, mutants_messages.txt and
# mutants_tools.txt must fail its layer's suite (a surviving mutant counts as a failed test; see
# scripts/mutants.sh).
bash "$REPO_DIR/scripts/mutants.sh" "$robustness/mutants"
# The node's: each bug of mutants_ros.txt must fail the rostests it names.
bash "$REPO_DIR/scripts/mutants_ros.sh" "$robustness/mutants_ros"
if have_libfuzzer; then
  result_dirs+=("$robustness/fuzz")
  bash "$REPO_DIR/scripts/fuzz.sh" --regressions --junit "$robustness/fuzz"
  fuzz_seconds="${FUZZ_SECONDS:-60}"
  if [ "$fuzz_seconds" -gt 0 ]; then
    bash "$REPO_DIR/scripts/fuzz.sh" --junit "$robustness/fuzz" "$fuzz_seconds"
  fi
else
  echo "fuzz: skipped (clang++ with libFuzzer not available)"
fi

/usr/bin/python3 "$REPO_DIR/scripts/count_test_results.py" "${result_dirs[@]}"
