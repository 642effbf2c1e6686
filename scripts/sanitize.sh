#!/usr/bin/env bash
# Builds the core library and its gtest suite (test/core) with ASan + UBSan in a build
# directory of their own (plain CMake, test/sanitize/CMakeLists.txt) and runs the suite. The
# same build holds the fuzz targets when clang has libFuzzer (scripts/fuzz.sh): built here with
# clang++ then, otherwise with ${CXX:-g++}.
#   bash scripts/sanitize.sh [results_dir]   gtest XML goes to results_dir (default BUILD/results)
# Environment: SANITIZE_BUILD_DIR (default $AP_WORKSPACE/sanitize), CXX (without libFuzzer;
# default g++).
# Exit status: that of the suite (non-zero on a failed test or a sanitizer report), 2 when the
# build fails.
set -uo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

build="${SANITIZE_BUILD_DIR:-$WORKSPACE/sanitize}"
results="${1:-$build/results}"
mkdir -p "$build" "$results"
rm -f "$results/core_tests_sanitized.xml"

echo "sanitize: building the core tests with ASan + UBSan in $build"
start=$SECONDS
if ! { configure_sanitize_build "$build" &&
  cmake --build "$build" -j "$(nproc)" >"$build/build.log" 2>&1; }; then
  echo "sanitize: build failed; see $build/cmake.log and $build/build.log"
  tail -n 30 "$build/build.log" 2>/dev/null
  exit 2
fi
echo "sanitize: built in $((SECONDS - start)) s; running"

# A sanitizer report aborts the run; the XML then lacks, and the caller counts that as failed.
export ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1}"
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}"
start=$SECONDS
"$build/core_tests_sanitized" --gtest_output="xml:$results/core_tests_sanitized.xml" \
  >"$build/test.log" 2>&1
status=$?
grep -E '^\[  (PASSED|FAILED) ' "$build/test.log"
grep -E '^\[  FAILED  \]|ERROR: (AddressSanitizer|LeakSanitizer)|runtime error|SUMMARY' \
  "$build/test.log" | sort -u | head -n 20
echo "sanitize: suite ran in $((SECONDS - start)) s (exit $status; log $build/test.log)"
exit "$status"
