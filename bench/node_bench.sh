#!/usr/bin/env bash
# Node benchmark: the IMU load generator publishes sensor_msgs/Imu at
# 1 kHz .. 200 kHz, 3 s each, to attitude_propagator_node (separate processes, TCP) and to the
# nodelet (generator loaded in the same manager, shared-pointer publish), and records the
# fraction of messages that reached imu/data and the input-to-output latency p50/p99, one CSV
# row per run, mode and rate.
#   bash bench/node_bench.sh [out.csv]   (default docs/data/node_bench.csv; about 4 min)
# NODE_BENCH_RATES (e.g. "[1000, 20000]"), NODE_BENCH_SECONDS and NODE_BENCH_REPEATS (3)
# override the defaults.
# Expects the package built (bench/run_all.sh builds it). Runs its own ROS master on a private
# port, so it neither needs nor disturbs a running roscore.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/../scripts/common.sh"
source_ros
source_workspace

OUT="${1:-$REPO_DIR/docs/data/node_bench.csv}"
PORT="${NODE_BENCH_PORT:-11797}"
export ROS_MASTER_URI="http://localhost:${PORT}"
export ROS_LOG_DIR="${ROS_LOG_DIR:-$(mktemp -d)}"
mkdir -p "$(dirname "$OUT")"
TMP="$(mktemp -d)"
trap 'rm -rf "$TMP"' EXIT

# The load generator's nodelet is a benchmark tool, not a plugin of the package, which neither
# installs nor exports it. A throwaway package that only this script's ROS_PACKAGE_PATH sees
# exports its description (bench/bench_nodelets.xml); pluginlib finds the library in the devel
# space through CMAKE_PREFIX_PATH.
plugin_pkg="$TMP/packages/attitude_propagator_bench"
mkdir -p "$plugin_pkg"
cp "$REPO_DIR/bench/bench_nodelets.xml" "$plugin_pkg/"
cat >"$plugin_pkg/package.xml" <<'XML'
<?xml version="1.0"?>
<package format="3">
  <name>attitude_propagator_bench</name>
  <version>0.0.0</version>
  <description>The node benchmark's IMU load generator nodelet (bench/node_bench.sh).</description>
  <maintainer email="attitude-propagator@users.noreply.github.com">attitude_propagator maintainers</maintainer>
  <license>BSD-3-Clause</license>
  <exec_depend>nodelet</exec_depend>
  <export>
    <nodelet plugin="${prefix}/bench_nodelets.xml"/>
  </export>
</package>
XML
export ROS_PACKAGE_PATH="$TMP/packages:${ROS_PACKAGE_PATH:-}"

run_mode() {
  local mode="$1" csv="$TMP/$1.csv"
  echo "node_bench: $mode"
  roslaunch -p "$PORT" "$REPO_DIR/bench/node_bench.launch" mode:="$mode" out:="$csv" \
    rates:="${NODE_BENCH_RATES:-[1000, 2000, 5000, 10000, 20000, 50000, 100000, 200000]}" \
    seconds:="${NODE_BENCH_SECONDS:-3.0}" \
    >"$TMP/$mode.log" 2>&1 &
  local launch_pid=$!
  local waited=0
  until [ -f "$csv" ] || [ $waited -ge 180 ]; do
    sleep 1
    waited=$((waited + 1))
    kill -0 "$launch_pid" 2>/dev/null || break
  done
  kill -INT "$launch_pid" 2>/dev/null || true
  wait "$launch_pid" 2>/dev/null || true
  if [ ! -f "$csv" ]; then
    echo "node_bench: $mode produced no result; log:" >&2
    tail -n 30 "$TMP/$mode.log" >&2
    return 1
  fi
  grep "load generator" "$TMP/$mode.log" | sed 's/^.*load generator/  load generator/' || true
}

# Node and nodelet alternate, REPEATS times each, so background load (a shared 2-core machine)
# hits both alike; bench/plot.py reports the median over the repeats per mode and rate.
REPEATS="${NODE_BENCH_REPEATS:-3}"
echo "run,mode,rate_hz,seconds,sent,sent_rate_hz,received,delivered_fraction,latency_p50_ms,latency_p99_ms,latency_max_ms" >"$OUT.tmp"
for run in $(seq 1 "$REPEATS"); do
  for mode in node nodelet; do
    run_mode "$mode"
    tail -n +2 "$TMP/$mode.csv" | sed "s/^/$run,/" >>"$OUT.tmp"
    rm -f "$TMP/$mode.csv"
  done
done
mv "$OUT.tmp" "$OUT"
echo "node_bench: wrote $OUT"
