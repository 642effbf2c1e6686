#!/usr/bin/env bash
# catkin_lint finds no errors or warnings in the package (notices are style suggestions).
cd "$(dirname "${BASH_SOURCE[0]}")/../.." || exit 1
export PATH="/usr/bin:$PATH"
command -v catkin_lint >/dev/null || { echo "catkin_lint not installed"; exit 1; }
out=$(catkin_lint -W1 . 2>&1)
echo "$out" | grep -q "found 0 problems" || { echo "$out"; exit 1; }
