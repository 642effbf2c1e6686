#!/usr/bin/env bash
# The layers (docs/design.md §2.1) in the built files: each layer's shared library or program
# needs only the libraries its layer may link. Read from the files themselves: their NEEDED
# entries (readelf -d: what they link directly) and every library the loader would load for them
# (ldd: what comes in through those). The configure step checks the targets' link lines
# (the layer check at the end of CMakeLists.txt); this sees what the linker really recorded,
# link options included. So it needs the built workspace (scripts/test.sh builds first).
#   core, config  (libattitude_propagator_core.so, _config.so): the C and C++ runtimes, Boost and
#                 the core only; no catkin library, nothing else.
#   messages      (libattitude_propagator_messages.so): not roscpp, tf2_ros, nodelet,
#                 dynamic_reconfigure, diagnostic_updater or the ROS wrapper.
#   bag tools     (propagate_bag, evaluate_bag_core): not the ROS wrapper, nodelet, tf2_ros or
#                 dynamic_reconfigure.
source "$(dirname "${BASH_SOURCE[0]}")/../../scripts/common.sh"
source_ros
# Under catkin's run_tests (test/checks/junit.py) the workspace's environment is already set.
[ -n "${AP_CATKIN_ENV:-}" ] || source_workspace
cd "$REPO_DIR" || exit 1
command -v readelf >/dev/null || { echo "layer dependencies: readelf not installed (binutils)"; exit 1; }

program="$(catkin_find --first-only --libexec attitude_propagator propagate_bag 2>/dev/null)"
[ -x "$program" ] || program="$WORKSPACE/devel/lib/attitude_propagator/propagate_bag"
bin_dir="$(dirname "$program")"
lib_dir="$(dirname "$bin_dir")"

# Library names as the loader knows them (sonames: libroscpp.so.4d, libnodeletlib.so.1d).
ros_node='^lib(roscpp|tf2_ros|nodeletlib|dynamic_reconfigure[a-z_]*|diagnostic_updater)\.so'
wrapper='^libattitude_propagator_ros\.so'
tools_forbidden='^lib(attitude_propagator_ros|nodeletlib|tf2_ros|dynamic_reconfigure[a-z_]*)\.so'
# The core's and config's allow-list: the C and C++ runtimes, Boost, the core itself.
core_allowed='^(libstdc\+\+|libm|libgcc_s|libc|libpthread|libdl|librt|libboost_[a-z0-9_]*|libattitude_propagator_core)\.so|^(/lib64/)?ld-linux|^linux-vdso'

status=0
refuse() {
  echo "layer dependencies: $1"
  status=1
}

# needed FILE: the NEEDED entries, one a line.
needed() { readelf -d "$1" 2>/dev/null | sed -n 's/.*(NEEDED).*\[\(.*\)\]/\1/p'; }
# loaded FILE: every library the loader resolves for FILE, one a line (by the name asked for).
loaded() { LD_LIBRARY_PATH="$lib_dir${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}" ldd "$1" 2>/dev/null |
  awk '{print $1}'; }

# check FILE LAYER RULE PATTERN: RULE is "deny" (no library matching PATTERN) or "allow" (only
# libraries matching PATTERN).
check() {
  local file=$1 layer=$2 rule=$3 pattern=$4 direct lib how
  if [ ! -f "$file" ]; then
    refuse "$file is not built (build the package first)"
    return
  fi
  direct=$'\n'"$(needed "$file")"$'\n'
  while IFS= read -r lib; do
    [ -n "$lib" ] || continue
    how="indirectly (through another library)"
    [[ "$direct" == *$'\n'"$lib"$'\n'* ]] && how=directly
    if { [ "$rule" = deny ] && [[ "$lib" =~ $pattern ]]; } ||
      { [ "$rule" = allow ] && ! [[ "$lib" =~ $pattern ]]; }; then
      refuse "$(basename "$file") ($layer) needs $lib $how, which its layer may not link (docs/design.md §2.1)"
    fi
  done < <({
    printf '%s' "$direct"
    loaded "$file"
  } | sort -u)
}

check "$lib_dir/libattitude_propagator_core.so" core allow "$core_allowed"
check "$lib_dir/libattitude_propagator_config.so" config allow "$core_allowed"
check "$lib_dir/libattitude_propagator_messages.so" "message layer" deny "$ros_node|$wrapper"
for tool in propagate_bag evaluate_bag_core; do
  check "$bin_dir/$tool" "bag tools" deny "$tools_forbidden"
done
exit $status
