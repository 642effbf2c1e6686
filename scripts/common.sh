# Shared by the scripts in this folder: paths, the environment and the package lists.
# Sourced, not run.

REPO_DIR="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd -P)"
# The catkin workspace and the builds of the checkout's own files (the sanitizer build, the
# mutants' plain CMake build) live in the checkout's .workspace/ (ignored by git; the package is
# linked into its src/), so a build finds its sources at the same relative path in every clone
# and the compiler cache below serves a clone anywhere. AP_WORKSPACE puts them elsewhere. (The
# node mutants' catkin workspace holds a copy and lives at one place: scripts/mutants_ros.sh.)
WORKSPACE="${AP_WORKSPACE:-$REPO_DIR/.workspace}"

# ROS tools and matplotlib live in Debian's /usr/bin/python3, not in a python3 earlier on PATH.
export PATH="/usr/bin:$PATH"

# A compiler cache outside the checkout, shared by every build of the scripts (catkin, the
# sanitizer build, the mutants' builds, the node mutants' workspace): a second run and every
# mutant schema already compiled once cost a cache lookup instead of a compile. ccache hashes
# the paths under the checkout (CCACHE_BASEDIR) relative to the compiler's folder, and not that
# folder itself (CCACHE_NOHASHDIR, for the -g builds): with the workspace inside the checkout,
# a fresh clone at any path hits what another clone compiled. (A cached object's debug
# information then names the folder it was compiled in.) CCACHE_DISABLE=1 turns it off.
export CCACHE_DIR="${CCACHE_DIR:-${XDG_CACHE_HOME:-$HOME/.cache}/attitude_propagator_ccache}"
export CCACHE_BASEDIR="${CCACHE_BASEDIR:-$REPO_DIR}"
export CCACHE_NOHASHDIR="${CCACHE_NOHASHDIR:-1}"
export CCACHE_MAXSIZE="${CCACHE_MAXSIZE:-8G}"
# The CMake arguments that put the cache in front of the compiler, when ccache is installed.
compiler_launcher() {
  if command -v ccache >/dev/null; then
    echo "-DCMAKE_CXX_COMPILER_LAUNCHER=ccache -DCMAKE_C_COMPILER_LAUNCHER=ccache"
  fi
}

# Debian 12 packages by name (Debian's own ROS 1 lives under /usr, no rosdep index), in three
# lists; install_deps.sh installs all three (DEBIAN_PACKAGES).
# The build, and what the README's commands run: roslaunch and roscore (python3-roslaunch),
# rosrun (rosbash), rosparam (python3-rosparam), rostopic, rosbag, and dynparam (with
# python3-dynamic-reconfigure, run through rosrun). The README's "In your catkin workspace"
# names exactly these (test/checks/ordinary_build.sh compares them).
DEBIAN_BUILD_PACKAGES=(
  build-essential cmake catkin
  ros-base-dev ros-message-generation ros-message-runtime
  libroscpp-dev libstd-msgs-dev libstd-srvs-dev libgeometry-msgs-dev libsensor-msgs-dev
  libdiagnostic-msgs-dev libdiagnostic-updater-dev
  libtf2-ros-dev libtf2-eigen-dev libtf2-msgs-dev tf2-tools libros-rosgraph-msgs-dev
  libdynamic-reconfigure-config-init-mutex-dev python3-dynamic-reconfigure
  libnodelet-dev pluginlib-dev libtopic-tools-dev
  python3-rospy python3-roslaunch python3-rosnode
  rosbash python3-rosparam python3-rostopic python3-tf2-ros python3-tf2-msgs python3-sensor-msgs python3-diagnostic-msgs
  python3-std-srvs python3-geometry-msgs python3-std-msgs python3-rosgraph-msgs python3-yaml
  libeigen3-dev libboost-dev libboost-math-dev
  librosbag-storage-dev libnav-msgs-dev libyaml-cpp-dev python3-rosbag python3-matplotlib
)
# The tests (`catkin_make run_tests`): gtest, rostest, catkin_lint for the repository checks.
DEBIAN_TEST_PACKAGES=(
  catkin-lint librostest-dev python3-rostest libgtest-dev googletest
)
# Only the project's own scripts: the benchmarks (Google Benchmark), fuzzing (clang with
# libFuzzer) and the compiler cache. A build in a catkin workspace needs none of them.
DEBIAN_SCRIPT_PACKAGES=(
  libbenchmark-dev clang libclang-rt-14-dev ccache
)
DEBIAN_PACKAGES=("${DEBIAN_BUILD_PACKAGES[@]}" "${DEBIAN_TEST_PACKAGES[@]}"
  "${DEBIAN_SCRIPT_PACKAGES[@]}")

as_root() {
  if [ "$(id -u)" = 0 ]; then "$@"; else sudo "$@"; fi
}

source_ros() {
  # On Ubuntu + ROS Noetic the environment comes from /opt/ros; Debian's ROS needs none.
  if [ -n "${ROS_DISTRO:-}" ] && [ -f "/opt/ros/${ROS_DISTRO}/setup.bash" ]; then
    set +u
    # shellcheck disable=SC1090
    source "/opt/ros/${ROS_DISTRO}/setup.bash"
    set -u
  fi
}

# True when clang++ links a libFuzzer target with ASan and UBSan (scripts/fuzz.sh).
have_libfuzzer() {
  command -v clang++ >/dev/null || return 1
  local dir
  dir="$(mktemp -d)"
  printf '%s\n' '#include <cstddef>' '#include <cstdint>' \
    'extern "C" int LLVMFuzzerTestOneInput(const uint8_t*, size_t) { return 0; }' >"$dir/t.cpp"
  clang++ -fsanitize=fuzzer,address,undefined "$dir/t.cpp" -o "$dir/t" >/dev/null 2>&1
  local status=$?
  rm -rf "$dir"
  return $status
}

# A CMake build directory remembers the source directory it was configured for, and cmake refuses
# it for any other (a second clone, or CI's fresh checkout, sharing the same cache folder). Such a
# directory is emptied so that it is configured afresh.
#   forget_other_source BUILD_DIR SOURCE_DIR
forget_other_source() {
  local build="$1" source="$2" recorded
  [ -f "$build/CMakeCache.txt" ] || return 0
  recorded="$(sed -n 's/^CMAKE_HOME_DIRECTORY:INTERNAL=//p' "$build/CMakeCache.txt")"
  if [ "$(realpath -m "$recorded")" != "$(realpath -m "$source")" ]; then
    echo "$build was configured for $recorded; configuring it afresh for $source"
    rm -rf "$build/CMakeCache.txt" "$build/CMakeFiles"
  fi
}

# The checkout as the catkin workspace links it ($WORKSPACE/src/attitude_propagator), the one
# place every build of the scripts finds the sources. Prints the path.
stable_source() {
  mkdir -p "${WORKSPACE}/src"
  ln -sfn "$REPO_DIR" "${WORKSPACE}/src/attitude_propagator"
  echo "${WORKSPACE}/src/attitude_propagator"
}

# catkin writes the environment its test commands run in (build/catkin_generated/
# setup_cached.sh) when it configures, with only the devel folders that exist by then: in a new
# workspace the package's Python messages would be missing from every rostest's PYTHONPATH. So
# the folders are made first, and a workspace configured without them is configured again.
# Prints the catkin_make argument that does that (--force-cmake), or nothing.
#   prepare_devel_space WORKSPACE
prepare_devel_space() {
  local ws="$1" python
  python="$ws/devel/lib/python3/dist-packages"
  mkdir -p "$python" "$ws/devel/lib/pkgconfig"
  local cached="$ws/build/catkin_generated/setup_cached.sh"
  if [ -f "$cached" ] && ! grep -q "$python" "$cached"; then echo "--force-cmake"; fi
}

source_workspace() {
  set +u
  # shellcheck disable=SC1091
  source "${WORKSPACE}/devel/setup.bash"
  set -u
}

# The one sanitizer build (test/sanitize) of scripts/sanitize.sh and scripts/fuzz.sh: with clang
# and libFuzzer it holds the sanitized suite and the fuzz targets; otherwise the suite alone,
# built with ${CXX:-g++}. Configures BUILD_DIR (afresh when its source or compiler changed);
# logs to BUILD_DIR/cmake.log.
#   configure_sanitize_build BUILD_DIR
configure_sanitize_build() {
  local build="$1" compiler cached
  if have_libfuzzer; then compiler=clang++; else compiler="${CXX:-g++}"; fi
  local source
  source="$(stable_source)/test/sanitize"
  mkdir -p "$build"
  forget_other_source "$build" "$source"
  if [ -f "$build/CMakeCache.txt" ]; then
    cached="$(sed -n 's/^CMAKE_CXX_COMPILER:[A-Z]*=//p' "$build/CMakeCache.txt")"
    if [ "$(basename "$cached")" != "$(basename "$(command -v "$compiler" || echo "$compiler")")" ]; then
      rm -rf "$build/CMakeCache.txt" "$build/CMakeFiles"
    fi
  fi
  # shellcheck disable=SC2046
  cmake -S "$source" -B "$build" -DCMAKE_CXX_COMPILER="$compiler" $(compiler_launcher) \
    >"$build/cmake.log" 2>&1
}
