#!/usr/bin/env bash
# Fuzzes the core library with libFuzzer (clang, ASan + UBSan): targets in test/fuzz/, built in
# the one sanitizer build of the core (test/sanitize, shared with scripts/sanitize.sh).
#   bash scripts/fuzz.sh [seconds]        build, then fuzz every target at once for `seconds`
#                                         of wall time (default 60), each from its own seed
#   bash scripts/fuzz.sh --regressions    build, then run each target over the inputs in
#                                         test/fuzz/regressions/<target>/ only; an input named
#                                         after an integrator (dopri5_...) must read that
#                                         method's code (fuzz_support.h), below the number of
#                                         codes, so that a new method does not change it
# Options (before the seconds): --junit DIR writes one JUnit XML per run into DIR (one test
# case per fuzzed target, one per regression input), as scripts/test.sh counts them.
# Environment: FUZZ_TARGETS (default "kinematic dynamic parameters"), FUZZ_TIMEOUT (seconds
# one input may take, default 30), FUZZ_SEED (default: drawn anew each run and printed; give it
# to repeat a run), SANITIZE_BUILD_DIR (default $AP_WORKSPACE/sanitize).
# A finding fails the run and is kept as a regression input: copied to
# test/fuzz/regressions/<target>/ (commit it with the fix), with the command that reproduces
# it printed; libFuzzer's own copy stays under test/fuzz/findings/ (not committed).
# Exit status: 0 nothing found, 1 a finding or a failing regression input, 2 no build.
set -uo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

mode=fuzz
junit_dir=""
seconds=60
while [ $# -gt 0 ]; do
  case "$1" in
    --regressions) mode=regressions ;;
    --junit) junit_dir="$2"; shift ;;
    -h | --help) sed -n '2,20p' "$0"; exit 0 ;;
    *) seconds="$1" ;;
  esac
  shift
done
targets=(${FUZZ_TARGETS:-kinematic dynamic parameters})
# Per input: the sanitizers slow the core 10-20x, and the machine may be shared.
timeout_s="${FUZZ_TIMEOUT:-30}"
build="${SANITIZE_BUILD_DIR:-$WORKSPACE/sanitize}"
fuzz_dir="$REPO_DIR/test/fuzz"
findings="$fuzz_dir/findings"

if ! have_libfuzzer; then
  echo "fuzz: clang++ with libFuzzer is not available (apt-get install clang libclang-rt-14-dev)"
  exit 2
fi
mkdir -p "$build" "$findings"
echo "fuzz: building the targets in $build"
fuzz_bins=()
for target in "${targets[@]}"; do fuzz_bins+=("fuzz_$target"); done
if ! { configure_sanitize_build "$build" &&
  cmake --build "$build" -j "$(nproc)" --target "${fuzz_bins[@]}" >"$build/build.log" 2>&1; }; then
  echo "fuzz: build failed; see $build/cmake.log and $build/build.log"
  tail -n 30 "$build/build.log" 2>/dev/null
  exit 2
fi

export ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=0}"
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}"
# A seed drawn anew each run (and printed), so that every run of the test command explores
# other inputs; FUZZ_SEED repeats a run. The working corpus starts from the committed seeds
# each time; FUZZ_KEEP_CORPUS=1 grows it across runs (for longer exploration by hand).
seed="${FUZZ_SEED:-$(( (RANDOM << 15 | RANDOM) + 1 ))}"
flags=(-timeout="$timeout_s" -rss_limit_mb=2048 -max_len=2048 -print_final_stats=1)

xml_escape() { sed -e 's/&/\&amp;/g' -e 's/</\&lt;/g' -e 's/>/\&gt;/g' -e 's/"/\&quot;/g'; }

# junit_case NAME SECONDS [FAILURE_TEXT]: one <testcase> element.
junit_case() {
  local name="$1" time="$2" failure="${3:-}"
  printf '  <testcase classname="fuzz" name="%s" time="%s">' "$name" "$time"
  if [ -n "$failure" ]; then
    printf '<failure message="finding">%s</failure>' "$(printf '%s' "$failure" | xml_escape)"
  fi
  printf '</testcase>\n'
}

# The lines of a libFuzzer log that say what went wrong.
finding_summary() {
  grep -E 'FUZZ ORACLE|runtime error|ERROR: (AddressSanitizer|LeakSanitizer)|libFuzzer: (timeout|out-of-memory)|SUMMARY: [A-Za-z]*Sanitizer' \
    "$1" | head -n 6
}

# The integrator codes (fuzz_support.h's integratorCodes(): the table's rows, in code order), as
# make_seeds.py reads them from the table's source.
mapfile -t codes < <(cd "$fuzz_dir" &&
  /usr/bin/python3 -B -c 'import make_seeds; print("\n".join(make_seeds.NAMES))')
[ "${#codes[@]}" -gt 0 ] || { echo "fuzz: no integrator codes from make_seeds.py"; exit 2; }
# The method a regression input's file name starts with (the longest such name), or nothing.
method_named() {
  local file="$1" best="" code
  for code in "${codes[@]}"; do
    if [[ "$file" == "${code}_"* ]] && [ ${#code} -gt ${#best} ]; then best="$code"; fi
  done
  echo "$best"
}
# Why an input named after METHOD does not test it, from its FUZZ_TRACE log; nothing if it does.
# Its code byte must name METHOD and lie below the number of codes, so that the input keeps its
# meaning when a method is appended to the codes.
wrong_method() {
  local log="$1" method="$2" line code offset read i
  [ -n "$method" ] || return 0
  line="$(grep -m1 -E '^integrator code [0-9]+ at [0-9]+: ' "$log")"
  if [ -z "$line" ]; then
    echo "named after $method, but it reads no integrator (FUZZ_TRACE shows none)"
    return 0
  fi
  read -r code offset read <<<"$(echo "$line" | sed -E 's/^integrator code ([0-9]+) at ([0-9]+): (.*)$/\1 \2 \3/')"
  for i in "${!codes[@]}"; do [ "${codes[$i]}" = "$method" ] && break; done
  if [ "$read" != "$method" ] || [ "$code" -ge ${#codes[@]} ]; then
    echo "named after $method, but its byte $offset is code $code ($read; codes 0-$((${#codes[@]} - 1)) keep their meaning): set byte $offset to $i"
  fi
}
failed=0
cases=()
pids=()
fuzzed=()
for target in "${targets[@]}"; do
  bin="$build/fuzz_$target"
  log="$build/$target.$mode.log"
  if [ "$mode" = regressions ]; then
    inputs=("$fuzz_dir/regressions/$target"/*)
    [ -e "${inputs[0]}" ] || { echo "fuzz: $target: no regression inputs"; continue; }
    for input in "${inputs[@]}"; do
      name="$target/regressions/$(basename "$input")"
      start=$SECONDS
      method="$(method_named "$(basename "$input")")"
      if [ -n "$method" ]; then
        FUZZ_TRACE=1 "$bin" "${flags[@]}" -seed=1 "$input" >"$log" 2>&1
      else
        "$bin" "${flags[@]}" -seed=1 "$input" >"$log" 2>&1
      fi
      status=$?
      wrong="$(wrong_method "$log" "$method")"
      if [ $status -eq 0 ] && [ -z "$wrong" ]; then
        echo "fuzz: $name passed"
        cases+=("$(junit_case "$name" $((SECONDS - start)))")
      elif [ -n "$wrong" ]; then
        failed=$((failed + 1))
        echo "fuzz: $name FAILED: $wrong"
        cases+=("$(junit_case "$name" $((SECONDS - start)) "$wrong")")
      else
        failed=$((failed + 1))
        summary="$(finding_summary "$log")"
        echo "fuzz: $name FAILED:"
        echo "$summary" | sed 's/^/    /'
        echo "    reproduce: $bin $input"
        cases+=("$(junit_case "$name" $((SECONDS - start)) "$summary")")
      fi
    done
    continue
  fi
  # Fuzzing: every target at once (they share the cores for the same wall time), each from
  # the run's seed plus its index.
  corpus="$build/corpus/$target"
  [ "${FUZZ_KEEP_CORPUS:-0}" = 1 ] || rm -rf "$corpus"
  mkdir -p "$corpus"
  rm -f "$findings/$target"-*
  index=${#pids[@]}
  "$bin" "${flags[@]}" -seed=$((seed + index)) -max_total_time="$seconds" \
    -artifact_prefix="$findings/$target-" "$corpus" "$fuzz_dir/corpus/$target" >"$log" 2>&1 &
  pids+=($!)
  fuzzed+=("$target")
done

if [ "$mode" = fuzz ]; then
  echo "fuzz: ${fuzzed[*]} for ${seconds} s at once, seed $seed (FUZZ_SEED=$seed repeats this run)"
  start=$SECONDS
  for i in "${!fuzzed[@]}"; do
    target="${fuzzed[$i]}"
    bin="$build/fuzz_$target"
    log="$build/$target.$mode.log"
    wait "${pids[$i]}"
    status=$?
    stats="$(grep -E '^stat::number_of_executed_units' "$log" | awk '{print $2}')"
    if [ "$status" -eq 0 ]; then
      echo "fuzz: $target passed (${stats:-?} inputs in $((SECONDS - start)) s, seed $((seed + i)))"
      cases+=("$(junit_case "$target" $((SECONDS - start)))")
      continue
    fi
    failed=$((failed + 1))
    summary="$(finding_summary "$log")"
    artifact="$(ls -t "$findings"/"$target"-* 2>/dev/null | head -n 1)"
    kept="(none written; log: $log)"
    if [ -n "$artifact" ]; then
      mkdir -p "$fuzz_dir/regressions/$target"
      kept="$fuzz_dir/regressions/$target/found-$(sha1sum "$artifact" | cut -c1-12)"
      cp "$artifact" "$kept"
    fi
    echo "fuzz: $target FAILED after $((SECONDS - start)) s (seed $((seed + i))):"
    echo "$summary" | sed 's/^/    /'
    echo "    kept as a regression input: $kept"
    echo "    reproduce: $bin $kept"
    cases+=("$(junit_case "$target" $((SECONDS - start)) "$summary (input: $kept)")")
  done
fi

if [ -n "$junit_dir" ]; then
  mkdir -p "$junit_dir"
  {
    echo '<?xml version="1.0" encoding="UTF-8"?>'
    echo "<testsuite name=\"fuzz_$mode\" tests=\"${#cases[@]}\" failures=\"$failed\">"
    [ ${#cases[@]} -eq 0 ] || printf '%s\n' "${cases[@]}"
    echo '</testsuite>'
  } >"$junit_dir/fuzz_$mode.xml"
fi
[ "$failed" -eq 0 ]
