#!/usr/bin/env bash
# Installs what is missing, builds, and runs the demo headless for a bounded time:
# demo.launch streams a scene's inputs to attitude_propagator, and print_tf (a tf2 listener)
# prints the orientation it receives through tf, twice a second, next to the closed form.
#   bash scripts/demo.sh [scene] [seconds]     scene: coning (default) | t_handle | spinning_top
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
scene="${1:-coning}"
seconds="${2:-10}"
case "$scene" in
  coning) axis=z ;;
  t_handle) axis=y ;;
  spinning_top) axis=z ;;
  *) echo "demo: unknown scene '$scene'; accepted: coning t_handle spinning_top" >&2; exit 2 ;;
esac

bash "$REPO_DIR/scripts/install_deps.sh"
bash "$REPO_DIR/scripts/build.sh" >/dev/null
source_ros
source_workspace

# A master of our own on a free port, so the demo neither needs nor disturbs another one.
port=$(/usr/bin/python3 -c 'import socket; s = socket.socket(); s.bind(("", 0)); print(s.getsockname()[1])')
export ROS_MASTER_URI="http://localhost:${port}"
log="$(mktemp -t attitude_propagator_demo.XXXXXX.log)"
echo "demo: scene $scene for ${seconds} s"
roslaunch -p "$port" attitude_propagator demo.launch scene:="$scene" >"$log" 2>&1 &
launch_pid=$!
stop_launch() {
  # TERM, not INT: a background job of a non-interactive shell ignores SIGINT.
  kill -TERM "$launch_pid" 2>/dev/null || true
  wait "$launch_pid" 2>/dev/null || true
}
trap stop_launch EXIT
for _ in $(seq 150); do
  /usr/bin/python3 -c 'import rosgraph, sys; sys.exit(0 if rosgraph.is_master_online() else 1)' &&
    break
  sleep 0.2
done

status=0
timeout $((seconds + 60)) "${WORKSPACE}/devel/lib/attitude_propagator/print_tf" \
  _duration:="$seconds" _axis:="$axis" __name:=print_tf || status=$?
if [ "$status" -ne 0 ]; then
  echo "demo: print_tf failed ($status); the launch log ($log) ends:" >&2
  tail -n 30 "$log" >&2
else
  rm -f "$log"
fi
exit "$status"
