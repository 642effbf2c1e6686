#!/usr/bin/env bash
# The launch files resolve (includes, args, config files) for the node, the nodelet, every
# demo scene and the launch examples, and each config/*.yaml is valid YAML. Needs the built
# workspace (scripts/test.sh builds first).
source "$(dirname "${BASH_SOURCE[0]}")/../../scripts/common.sh"
source_ros
# Under catkin's run_tests (test/checks/junit.py) the workspace's environment is already set.
[ -n "${AP_CATKIN_ENV:-}" ] || source_workspace
cd "$REPO_DIR" || exit 1
status=0
check() {
  if ! out=$(roslaunch --nodes "$@" 2>&1); then
    echo "launch check failed: roslaunch $*"
    echo "$out"
    status=1
  fi
}
check attitude_propagator attitude_propagator.launch
check attitude_propagator attitude_propagator.launch use_nodelet:=true body_frame:=imu_body
for scene in coning t_handle spinning_top; do
  check attitude_propagator demo.launch scene:="$scene"
done
check attitude_propagator demo.launch rviz:=true
for example in launch/examples/*.launch; do
  check "$example"
done
for yaml in config/*.yaml; do
  /usr/bin/python3 -c 'import sys, yaml; yaml.safe_load(open(sys.argv[1]))' "$yaml" ||
    { echo "invalid YAML: $yaml"; status=1; }
done
exit "$status"
