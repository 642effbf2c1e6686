#!/usr/bin/env bash
# Regenerates the demo's rviz screenshot (docs/demo_rviz.png) with no display: a virtual X
# server (Xvfb), a ROS master on a free port, launch/demo.launch with rviz:=true; once tf holds
# the scene's frames and the rviz window is up, the screen is captured (ImageMagick's import)
# and every process started here is stopped, on success, failure or interrupt.
#   bash scripts/screenshot_rviz.sh [scene] [out.png] [settle seconds]
#     scene: coning (default: base_link and base_link_truth) | t_handle | spinning_top
# Needs the built workspace (scripts/build.sh); installs Xvfb, x11-utils, ImageMagick and rviz
# when they are missing.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"
scene="${1:-coning}"
out="${2:-$REPO_DIR/docs/demo_rviz.png}"
settle="${3:-6}"  # s after the window is up: software OpenGL needs a few frames
case "$scene" in
  coning) frames="base_link base_link_truth" ;;
  t_handle | spinning_top) frames="base_link" ;;
  *) echo "screenshot_rviz: unknown scene '$scene'; accepted: coning t_handle spinning_top" >&2
     exit 2 ;;
esac
for tool in Xvfb xwininfo import convert rviz; do
  if ! command -v "$tool" >/dev/null; then
    echo "screenshot_rviz: $tool is missing; installing xvfb x11-utils imagemagick rviz"
    as_root apt-get update -q
    as_root env DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends \
      xvfb x11-utils imagemagick rviz
    break
  fi
done
[ -f "${WORKSPACE}/devel/setup.bash" ] ||
  { echo "screenshot_rviz: no workspace at $WORKSPACE; run scripts/build.sh first" >&2; exit 2; }
source_ros
source_workspace

work="$(mktemp -d -t attitude_propagator_screenshot.XXXXXX)"
pids=()
cleanup() {
  local i
  # The newest first (rviz and the demo before the master and the X server); TERM, not INT: a
  # background job of a non-interactive shell ignores SIGINT.
  for ((i = ${#pids[@]} - 1; i >= 0; i--)); do
    kill -TERM "${pids[i]}" 2>/dev/null || true
    wait "${pids[i]}" 2>/dev/null || true
  done
  rm -rf "$work"
}
trap cleanup EXIT
trap 'exit 130' INT
trap 'exit 143' TERM HUP

fail() {
  echo "screenshot_rviz: $1; the logs end:" >&2
  tail -n 20 "$work"/*.log >&2 || true
  exit 1
}

# A display number nobody holds (its lock file and socket absent).
display=99
while [ -e "/tmp/.X${display}-lock" ] || [ -e "/tmp/.X11-unix/X${display}" ]; do
  display=$((display + 1))
done
export DISPLAY=":${display}"
# The screen is the window's size (rviz/demo.rviz: 1200 x 800), so the capture is the window.
Xvfb "$DISPLAY" -screen 0 1200x800x24 -nolisten tcp >"$work/xvfb.log" 2>&1 &
pids+=($!)
for _ in $(seq 100); do
  xwininfo -root >/dev/null 2>&1 && break
  sleep 0.1
done
xwininfo -root >/dev/null 2>&1 || fail "Xvfb did not start on $DISPLAY"

port=$(/usr/bin/python3 -c 'import socket; s = socket.socket(); s.bind(("", 0)); print(s.getsockname()[1])')
export ROS_MASTER_URI="http://localhost:${port}"
roscore -p "$port" >"$work/roscore.log" 2>&1 &
pids+=($!)
for _ in $(seq 150); do
  /usr/bin/python3 -c 'import rosgraph, sys; sys.exit(0 if rosgraph.is_master_online() else 1)' &&
    break
  sleep 0.2
done

roslaunch attitude_propagator demo.launch scene:="$scene" rviz:=true >"$work/demo.log" 2>&1 &
pids+=($!)

# The scene's frames in tf, as rviz will look them up.
/usr/bin/python3 - "$frames" <<'EOF' || fail "tf did not hold the frames ($frames) within 60 s"
import sys
import rospy
import tf2_ros

rospy.init_node("screenshot_wait", anonymous=True, disable_signals=True)
buffer = tf2_ros.Buffer()
tf2_ros.TransformListener(buffer)
for frame in sys.argv[1].split():
    buffer.lookup_transform("world", frame, rospy.Time(0), rospy.Duration(60.0))
EOF

# The rviz window mapped, then a few seconds for its first frames to be drawn.
for _ in $(seq 300); do
  xwininfo -root -tree 2>/dev/null | grep -q 'RViz' && break
  sleep 0.2
done
xwininfo -root -tree 2>/dev/null | grep -q 'RViz' || fail "no rviz window within 60 s"
sleep "$settle"

# Captured until the 3D view is drawn (more than a blank window's few colours), then
# reduced to a 256-colour palette to keep the PNG small.
for _ in $(seq 10); do
  import -display "$DISPLAY" -window root "$work/shot.png"
  colours=$(identify -format '%k' "$work/shot.png")
  [ "$colours" -gt 200 ] && break
  sleep 2
done
[ "$colours" -gt 200 ] || fail "the screen stayed blank ($colours colours)"
mkdir -p "$(dirname "$out")"
convert "$work/shot.png" -colors 256 "PNG8:$work/small.png"
mv "$work/small.png" "$out"
echo "screenshot_rviz: wrote $out ($(du -k "$out" | cut -f1) kB, scene $scene)"
