#!/usr/bin/env bash
# Installs whatever the package needs and is missing.
#  - Debian 12: Debian's ROS 1 packages by name (see DEBIAN_PACKAGES in common.sh).
#  - Ubuntu with ROS_DISTRO set (e.g. Noetic from /opt/ros): rosdep, from package.xml.
# Works as root, or as a user with sudo.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/common.sh"

if [ -n "${ROS_DISTRO:-}" ] && [ -d "/opt/ros/${ROS_DISTRO}" ]; then
  source_ros
  command -v rosdep >/dev/null || as_root apt-get install -y python3-rosdep
  [ -d /etc/ros/rosdep/sources.list.d ] || as_root rosdep init
  rosdep update
  rosdep install --from-paths "$REPO_DIR" --ignore-src -y
  as_root apt-get install -y --no-install-recommends libbenchmark-dev python3-matplotlib \
    clang
  exit 0
fi

missing=()
for pkg in "${DEBIAN_PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null | grep -q "install ok installed" ||
    missing+=("$pkg")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install_deps: all ${#DEBIAN_PACKAGES[@]} packages present"
  exit 0
fi
echo "install_deps: installing ${missing[*]}"
as_root apt-get update -q
as_root env DEBIAN_FRONTEND=noninteractive apt-get install -y -q --no-install-recommends \
  "${missing[@]}"
