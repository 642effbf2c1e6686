#!/usr/bin/env bash
# Regenerates every benchmark figure of docs/benchmarks.md with one command:
#   bash bench/run_all.sh [--no-node]
# 1. builds the package in Release (scripts/build.sh, workspace $AP_WORKSPACE as elsewhere),
# 2. runs bench_sweep (work-precision sweep, stability map, invariants -> docs/data/*.csv),
# 3. runs bench_step_costs (Google Benchmark -> docs/data/step_costs.json),
# 3b. runs bench_ahrs (the engine against a Madgwick filter -> docs/data/ahrs.csv, its table in
#    docs/data/ahrs.md),
# 4. runs the node benchmark (bench/node_bench.sh -> docs/data/node_bench.csv) unless --no-node,
# 5. draws the charts and the results table with Debian's python3-matplotlib (bench/plot.py ->
#    docs/*.png, docs/results.md, and the section of docs/benchmarks.md between the results
#    markers).
# Not part of scripts/test.sh: it takes minutes and its figures are timings, not verdicts.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/../scripts/common.sh"

run_node=1
for arg in "$@"; do
  case "$arg" in
    --no-node) run_node=0 ;;
    *) echo "usage: bash bench/run_all.sh [--no-node]" >&2; exit 2 ;;
  esac
done

DATA="$REPO_DIR/docs/data"
BIN="$WORKSPACE/devel/lib/attitude_propagator"
mkdir -p "$DATA"

bash "$REPO_DIR/scripts/install_deps.sh"
bash "$REPO_DIR/scripts/build.sh"

{
  echo "date: $(date -u '+%Y-%m-%d %H:%M UTC')"
  echo "commit: $(git -C "$REPO_DIR" rev-parse --short HEAD 2>/dev/null || echo unknown)"
  echo "cpu: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ *//'), $(nproc) cores"
  echo "load before the run: $(cut -d' ' -f1-3 /proc/loadavg)"
} >"$DATA/machine.txt"

echo "== bench_sweep (work-precision, stability, invariants)"
"$BIN/bench_sweep" "$DATA"

if [ -x "$BIN/bench_step_costs" ]; then
  echo "== bench_step_costs (Google Benchmark)"
  "$BIN/bench_step_costs" --benchmark_repetitions=7 --benchmark_report_aggregates_only=true \
    --benchmark_min_time=0.2 --benchmark_out="$DATA/step_costs.json" \
    --benchmark_out_format=json
else
  echo "== Google Benchmark not found: no step costs" >&2
fi

echo "== bench_ahrs (the engine against a Madgwick filter)"
"$BIN/bench_ahrs" "$DATA/ahrs.csv" | tee "$DATA/ahrs.md"

if [ "$run_node" = 1 ]; then
  echo "== node benchmark"
  bash "$REPO_DIR/bench/node_bench.sh" "$DATA/node_bench.csv"
fi

echo "== charts"
/usr/bin/python3 "$REPO_DIR/bench/plot.py" "$DATA" "$REPO_DIR/docs" "$REPO_DIR/docs/benchmarks.md"
echo "bench: charts in docs/, tables in docs/results.md and docs/benchmarks.md"
