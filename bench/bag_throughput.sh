#!/usr/bin/env bash
# Throughput and memory of the bag tools on a generated bag: a 200 Hz sensor_msgs/Imu stream
# of the coning motion in frame imu_link (mounted on base_link by a /tf_static transform) and
# its closed-form attitude as a 200 Hz geometry_msgs/PoseStamped truth (about 100 MB for the
# default 1000 s). Every run's summary line must show all IMU messages accepted.
#
# Runs propagate_bag with --io-floor (reads, decodes and writes the same outputs without
# propagating) and with each kinematic integrator, then evaluate_bag_core over all of them in
# one pass; each run three times, the fastest kept (the machine may be shared). Prints per run
# the wall time, the CPU time (user + system), the multiple of real time, the ratio to the I/O
# floor and the peak resident memory (GNU time), and evaluate_bag_core's time against the sum of
# the propagate_bag runs, one per kinematic integrator. Bag output is uncompressed (the default); cf4 is also run with
# --compression lz4. The same with --csv output when CSV=1.
#
# Usage: bash bench/bag_throughput.sh [SECONDS_OF_DATA] [WORK_DIR]   (from the devel space built
# by scripts/build.sh; never part of the tests)
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/../scripts/common.sh"
source_ros
source_workspace

SECONDS_OF_DATA="${1:-1000}"
WORK="${2:-/tmp/attitude_propagator_bag_bench}"
BIN="${WORKSPACE}/devel/lib/attitude_propagator"
mkdir -p "$WORK"
BAG="$WORK/coning_${SECONDS_OF_DATA}s.bag"
# The kinematic integrators, in the table's order: evaluate_bag_core's --integrators default.
IFS=, read -r -a INTEGRATORS < <("$BIN/evaluate_bag_core" --help |
  sed -n 's/^ *--integrators LIST  *comma-separated (default \([a-z0-9_,]*\))$/\1/p')
[ "${#INTEGRATORS[@]}" -gt 0 ] || { echo "no integrators in evaluate_bag_core --help"; exit 1; }

if [ ! -f "$BAG" ]; then
  echo "writing $BAG ..."
  /usr/bin/python3 - "$BAG" "$SECONDS_OF_DATA" <<'EOF'
import math
import sys

import rosbag
import rospy
from geometry_msgs.msg import PoseStamped, TransformStamped
from sensor_msgs.msg import Imu
from tf2_msgs.msg import TFMessage

path, seconds = sys.argv[1], float(sys.argv[2])
beta, omega, rate = 0.1, 2.0 * math.pi * 1.1, 200.0  # the coning motion of coning_motion.h
s, c = math.sin(0.5 * beta), math.cos(0.5 * beta)
start = 1700000000
imu, pose = Imu(), PoseStamped()
imu.header.frame_id = "imu_link"
imu.orientation_covariance[0] = -1.0
pose.header.frame_id = "map"
mount = TransformStamped()  # the IMU's frame in the body, as a robot's static tf gives it
mount.header.stamp = rospy.Time(start)
mount.header.frame_id, mount.child_frame_id = "base_link", "imu_link"
mount.transform.rotation.w = 1.0
with rosbag.Bag(path, "w") as bag:
    bag.write("/tf_static", TFMessage([mount]), rospy.Time(start))
    for k in range(int(seconds * rate) + 1):
        t = k / rate
        stamp = rospy.Time(start) + rospy.Duration.from_sec(t)
        wt = omega * t
        imu.header.stamp = pose.header.stamp = stamp
        imu.angular_velocity.x = -2.0 * omega * s * s
        imu.angular_velocity.y = -omega * math.sin(beta) * math.sin(wt)
        imu.angular_velocity.z = omega * math.sin(beta) * math.cos(wt)
        q = pose.pose.orientation
        q.w, q.x, q.y, q.z = c, 0.0, s * math.cos(wt), s * math.sin(wt)
        bag.write("/imu/data_raw", imu, stamp)
        bag.write("/truth", pose, stamp)
EOF
fi
ls -l "$BAG"

# Runs "$@" three times; prints "wall_s max_rss_kb cpu_s" of the fastest.
measure() {
  local best="" line
  for _ in 1 2 3; do
    line=$(/usr/bin/time -f "%e %M %U %S" "$@" 2>&1 >/dev/null | tail -n 1 |
      awk '{ print $1, $2, $3 + $4 }')
    if [ -z "$best" ] || awk -v a="${line%% *}" -v b="${best%% *}" 'BEGIN { exit !(a < b) }'; then
      best="$line"
    fi
  done
  echo "$best"
}

report() {  # name wall rss floor cpu floor_cpu
  awk -v n="$1" -v w="$2" -v m="$3" -v f="$4" -v c="$5" -v fc="$6" -v s="$SECONDS_OF_DATA" \
    'BEGIN { printf "  %-22s %8.3f s wall %7.3f s CPU  %7.0fx real time  %5.2fx I/O floor (CPU %5.2fx)  %6.1f MB RSS\n", n, w, c, s / w, w / f, c / fc, m / 1024 }'
}

run_propagate() {  # output option (-o FILE.bag or --csv FILE.csv)
  local out_opt="$1" out_file="$2"
  echo "propagate_bag $out_opt (${SECONDS_OF_DATA} s of 200 Hz IMU):"
  read -r floor rss floor_cpu < <(measure "$BIN/propagate_bag" "$BAG" "$out_opt" "$out_file" \
    --no-progress --io-floor)
  report "I/O floor" "$floor" "$rss" "$floor" "$floor_cpu" "$floor_cpu"
  SUM=0
  for integrator in "${INTEGRATORS[@]}"; do
    read -r wall rss cpu < <(measure "$BIN/propagate_bag" "$BAG" "$out_opt" "$out_file" \
      --no-progress --set integrator="$integrator")
    report "$integrator" "$wall" "$rss" "$floor" "$cpu" "$floor_cpu"
    SUM=$(awk -v a="$SUM" -v b="$wall" 'BEGIN { print a + b }')
  done
  if [ "$out_opt" = -o ]; then
    read -r floor rss floor_cpu < <(measure "$BIN/propagate_bag" "$BAG" -o "$out_file" \
      --no-progress --io-floor --compression lz4)
    report "I/O floor, lz4" "$floor" "$rss" "$floor" "$floor_cpu" "$floor_cpu"
    read -r wall rss cpu < <(measure "$BIN/propagate_bag" "$BAG" -o "$out_file" --no-progress \
      --set integrator=cf4 --compression lz4)
    report "cf4, lz4" "$wall" "$rss" "$floor" "$cpu" "$floor_cpu"
  fi
  rm -f "$out_file"
}

run_propagate -o "$WORK/out.bag"

echo "evaluate_bag_core (${#INTEGRATORS[@]} integrators x 2 rate_samples readings, one pass):"
read -r wall rss _ < <(measure "$BIN/evaluate_bag_core" "$BAG" --truth /truth --csv "$WORK/eval" --no-progress)
awk -v w="$wall" -v m="$rss" -v sum="$SUM" -v n="${#INTEGRATORS[@]}" \
  'BEGIN { printf "  %-22s %8.3f s  %5.2fx the sum of the %d propagate_bag runs (%.3f s)  %6.1f MB RSS\n", "all methods", w, w / sum, n, sum, m / 1024 }'
"$BIN/evaluate_bag_core" "$BAG" --truth /truth --csv "$WORK/eval" --no-progress

if [ "${CSV:-0}" = 1 ]; then run_propagate --csv "$WORK/out.csv"; fi
