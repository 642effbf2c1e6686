#!/usr/bin/env bash
# catkin_lint finds no problem at its strictest level (-W2: errors, warnings and notices).
# The checkout folder need not be named like the package, so that one notice is ignored.
cd "$(dirname "${BASH_SOURCE[0]}")/../.." || exit 1
export PATH="/usr/bin:$PATH"
command -v catkin_lint >/dev/null || { echo "catkin_lint not installed"; exit 1; }
out=$(catkin_lint -W2 --ignore package_path_name . 2>&1)
echo "$out" | grep -q "found 0 problems" || { echo "$out"; exit 1; }
