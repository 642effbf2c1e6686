#!/usr/bin/env bash
# catkin_lint finds no problem at its strictest level (-W2: errors, warnings and notices).
# The checkout folder need not be named like the package, so that one notice is ignored.
# The verdict must not depend on what else is installed (rviz, for one, is started by
# launch/demo.launch): the lint runs twice, once as the machine is and once with no other
# package in sight, and both must be clean.
cd "$(dirname "${BASH_SOURCE[0]}")/../.." || exit 1
export PATH="/usr/bin:$PATH"
command -v catkin_lint >/dev/null || { echo "catkin_lint not installed"; exit 1; }
lint() { catkin_lint -W2 --ignore package_path_name . 2>&1; }
nowhere="$(mktemp -d)"
trap 'rm -rf "$nowhere"' EXIT
status=0
for environment in "as installed" "no other package"; do
  if [ "$environment" = "as installed" ]; then
    out=$(lint)
  else
    out=$(ROS_PACKAGE_PATH="$nowhere" CMAKE_PREFIX_PATH="$nowhere" lint)
  fi
  if ! echo "$out" | grep -q "found 0 problems"; then
    echo "catkin_lint ($environment):"
    echo "$out"
    status=1
  fi
done
exit $status
