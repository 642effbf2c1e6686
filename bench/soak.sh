#!/usr/bin/env bash
# Soak test: attitude_propagator_node under a steady IMU stream for a long time, watching its
# memory and CPU. Starts its own ROS master on a free port, the node (config/default.yaml, the
# kinematic model, unless --config is given) and the node benchmark's load generator
# (bench_imu_load_node) publishing sensor_msgs/Imu at RATE_HZ, and every 10 s writes one CSV
# row: t_s, rss_kib (VmRSS of the node), cpu_percent (of one core, over the last 10 s),
# messages (the node's diagnostics counter `received`). Stops everything at the end and prints
# RSS after the warm-up (min, max, growth, least-squares slope) and over the last half of the
# run (its spread relative to its mean: "flat" means within 10 %).
#   bash bench/soak.sh DURATION_S [RATE_HZ] [--config FILE] [--out FILE.csv] [--every S]
#                      [--slow-subscriber]
# RATE_HZ defaults to 1000, --out to docs/data/soak.csv, --every (the sampling period) to 10 s.
# --slow-subscriber adds a subscriber in another process to every output (imu/data,
# attitude_state, /tf) that takes 10 ms per message: its sockets back up, and the node's
# outgoing queues fill to their bound (docs/node.md, Queues). With a dynamic configuration whose
# rate_input is none (config/spinning_top.yaml) the node runs on its publish timer and the IMU
# stream is not subscribed. Builds the two executables if they are missing.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/../scripts/common.sh"

duration=""
rate=1000
config="$REPO_DIR/config/default.yaml"
out="$REPO_DIR/docs/data/soak.csv"
every=10
slow=false
positional=()
while [ $# -gt 0 ]; do
  case "$1" in
    --config) config="$(realpath "$2")"; shift ;;
    --out) out="$2"; shift ;;
    --every) every="$2"; shift ;;
    --slow-subscriber) slow=true ;;
    -h | --help) sed -n '2,17p' "$0"; exit 0 ;;
    *) positional+=("$1") ;;
  esac
  shift
done
duration="${positional[0]:-}"
rate="${positional[1]:-$rate}"
case "$duration" in
  '' | *[!0-9]*) echo "usage: bash bench/soak.sh DURATION_S [RATE_HZ] [--config FILE]" >&2; exit 2 ;;
esac
[ -f "$config" ] || { echo "soak: no config file $config" >&2; exit 2; }

source_ros
bin="$WORKSPACE/devel/lib/attitude_propagator"
if [ ! -x "$bin/attitude_propagator_node" ] || [ ! -x "$bin/bench_imu_load_node" ]; then
  bash "$REPO_DIR/scripts/build.sh" attitude_propagator_node bench_imu_load_node >/dev/null
fi
source_workspace

# A master of our own on a free port, so the soak neither needs nor disturbs another one.
port=$(/usr/bin/python3 -c 'import socket; s = socket.socket(); s.bind(("", 0)); print(s.getsockname()[1])')
export ROS_MASTER_URI="http://localhost:${port}"
tmp="$(mktemp -d -t attitude_propagator_soak.XXXXXX)"
export ROS_LOG_DIR="$tmp/log"
pids=()
stop_all() {
  # Newest first: the generator, the node, then the master; INT lets roscpp shut down cleanly.
  local i
  for ((i = ${#pids[@]} - 1; i >= 0; i--)); do
    kill -INT "${pids[$i]}" 2>/dev/null || true
    for _ in $(seq 50); do kill -0 "${pids[$i]}" 2>/dev/null || break; sleep 0.1; done
    kill -TERM "${pids[$i]}" 2>/dev/null || true
    wait "${pids[$i]}" 2>/dev/null || true
  done
  pids=()
}
trap 'stop_all; rm -rf "$tmp"' EXIT

roscore -p "$port" >"$tmp/roscore.log" 2>&1 &
pids+=($!)
for _ in $(seq 150); do
  /usr/bin/python3 -c 'import rosgraph, sys; sys.exit(0 if rosgraph.is_master_online() else 1)' &&
    break
  sleep 0.2
done
rosparam load "$config" /attitude_propagator
"$bin/attitude_propagator_node" __name:=attitude_propagator >"$tmp/node.log" 2>&1 &
node_pid=$!
pids+=("$node_pid")
# The generator sends for longer than the soak; it is stopped with the rest. Its rate list goes
# through rosparam: roscpp reads a `_rates:=[...]` argument as a string, and the generator would
# silently fall back to its own list (starting at 1 kHz).
rosparam set /imu_load_generator/rates "[${rate}.0]"
"$bin/bench_imu_load_node" __name:=imu_load_generator \
  _seconds:=$((duration + 3600)) _mode:=soak _out:="$tmp/generator.csv" >"$tmp/generator.log" 2>&1 &
pids+=($!)
if $slow; then
  /usr/bin/python3 - >"$tmp/slow.log" 2>&1 <<'PYTHON' &
"""A subscriber that reads 100 messages a second of each output: rospy runs the callback in
the thread that reads the socket, so a sleeping callback stops the reading and the node's
outgoing queue to this process fills up."""
import time

import rospy
from attitude_propagator.msg import AttitudeState
from sensor_msgs.msg import Imu
from tf2_msgs.msg import TFMessage


def slow(_):
    time.sleep(0.01)


rospy.init_node("slow_subscriber")
subs = [rospy.Subscriber(topic, kind, slow, tcp_nodelay=True)
        for topic, kind in (("imu/data", Imu), ("attitude_state", AttitudeState),
                            ("/tf", TFMessage))]
rospy.spin()
PYTHON
  pids+=($!)
fi

echo "soak: node pid $node_pid, $(basename "$config"), IMU at $rate Hz, ${duration} s," \
  "slow subscriber: $slow, every $every s -> $out"
mkdir -p "$(dirname "$out")"
/usr/bin/python3 - "$node_pid" "$duration" "$out" "$every" <<'PYTHON'
"""Samples the node every `every` s: VmRSS, CPU over the interval, diagnostics `received`."""
import os
import sys
import threading
import time

import rospy
from diagnostic_msgs.msg import DiagnosticArray

pid, duration, out, every = int(sys.argv[1]), float(sys.argv[2]), sys.argv[3], float(sys.argv[4])
ticks = os.sysconf("SC_CLK_TCK")
received = [0]
lock = threading.Lock()


def on_diagnostics(msg):
    for status in msg.status:
        if status.name.endswith(": state"):
            for kv in status.values:
                if kv.key == "received":
                    with lock:
                        received[0] = int(kv.value)


def rss_kib():
    with open(f"/proc/{pid}/status") as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1])
    return 0


def cpu_seconds():
    with open(f"/proc/{pid}/stat") as f:
        fields = f.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / ticks  # utime + stime


rospy.init_node("soak_sampler", anonymous=True, disable_signals=True)
rospy.Subscriber("/diagnostics", DiagnosticArray, on_diagnostics)
start = time.monotonic()
last_t, last_cpu = start, cpu_seconds()
with open(out, "w") as f:
    f.write("t_s,rss_kib,cpu_percent,messages\n")
    k = 1
    while True:
        time.sleep(max(0.0, start + every * k - time.monotonic()))
        if not os.path.exists(f"/proc/{pid}"):
            sys.exit("soak: the node exited early")
        now, cpu = time.monotonic(), cpu_seconds()
        with lock:
            messages = received[0]
        f.write(f"{now - start:.1f},{rss_kib()},{100 * (cpu - last_cpu) / (now - last_t):.1f},"
                f"{messages}\n")
        f.flush()
        last_t, last_cpu = now, cpu
        if now - start >= duration:
            break
        k += 1
rospy.signal_shutdown("done")
PYTHON
stop_all

/usr/bin/python3 - "$out" <<'PYTHON'
"""Summary: RSS after the warm-up (the first minute, or the first tenth of a shorter run)."""
import csv
import sys

rows = [{k: float(v) for k, v in r.items()} for r in csv.DictReader(open(sys.argv[1]))]
if not rows:
    sys.exit("soak: no samples")
end = rows[-1]["t_s"]
warm = [r for r in rows if r["t_s"] >= min(60.0, end / 10)]
t = [r["t_s"] for r in warm]
rss = [r["rss_kib"] for r in warm]
cpu = [r["cpu_percent"] for r in rows]
n = len(t)
mt, mr = sum(t) / n, sum(rss) / n
var = sum((x - mt) ** 2 for x in t)
slope = sum((x - mt) * (y - mr) for x, y in zip(t, rss)) / var if var > 0 else 0.0
rate = (rows[-1]["messages"] - warm[0]["messages"]) / (end - t[0]) if end > t[0] else 0.0
print(f"soak: {end:.0f} s, {int(rows[-1]['messages'])} messages received "
      f"({rate:.0f}/s after the warm-up)")
print(f"soak: RSS after {t[0]:.0f} s: min {min(rss):.0f} KiB, max {max(rss):.0f} KiB, "
      f"growth {rss[-1] - rss[0]:+.0f} KiB (first to last), slope {slope * 3600:+.1f} KiB/h")
half = [r["rss_kib"] for r in rows if r["t_s"] >= end / 2]
mean = sum(half) / len(half)
spread = (max(half) - min(half)) / mean
print(f"soak: RSS over the last half ({len(half)} samples): {min(half):.0f} .. {max(half):.0f} "
      f"KiB, spread {100 * spread:.1f} % of the mean: {'flat' if spread <= 0.1 else 'NOT flat'}")
for mark in (end / 2, end):
    near = min(rows, key=lambda r: abs(r["t_s"] - mark))
    print(f"soak: RSS at {near['t_s']:.0f} s: {near['rss_kib']:.0f} KiB")
print(f"soak: CPU {min(cpu):.1f} .. {max(cpu):.1f} % of one core, mean {sum(cpu) / len(cpu):.1f} %")
PYTHON
