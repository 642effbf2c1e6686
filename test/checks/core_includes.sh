#!/usr/bin/env bash
# The core library includes only what it may: the C++ standard library, Eigen, Boost and its
# own headers (include/attitude_propagator/*.h and its estimation room, not the ROS layer's); the config library
# (node parameters, src/config) may also include its own (attitude_propagator/config/*.h). An allow-list, because
# on Debian the ROS headers sit in /usr/include next to Boost's, where a stray include would
# compile. The ROS layer's headers live outside the core's include directory
# (src/ros/include), so the core's build cannot find them either.
cd "$(dirname "${BASH_SOURCE[0]}")/../.." || exit 1

std_headers=" algorithm any array atomic bitset cassert cctype cerrno cfenv cfloat charconv \
chrono cinttypes climits clocale cmath complex condition_variable cstdarg cstddef cstdint \
cstdio cstdlib cstring ctime cwchar deque exception execution filesystem fstream functional \
future initializer_list iomanip ios iosfwd iostream istream iterator limits list locale map \
memory memory_resource mutex new numeric optional ostream queue random ratio regex \
scoped_allocator set shared_mutex sstream stack stdexcept streambuf string string_view \
system_error thread tuple type_traits typeindex typeinfo unordered_map unordered_set utility \
valarray variant vector "

# The estimation room (the error state, the measurements) knows nothing of the engine, the
# models or time beyond a stamp: it may include itself and these building blocks only.
estimation_allows=" quaternion.h orientation_covariance.h limits.h source_timeline.h "

allowed() {
  local header=$1 file=$2
  case "$file" in
    src/core/estimation/* | include/attitude_propagator/estimation/*)
      case "$header" in
        \"attitude_propagator/estimation/*.h\") ;;
        \"attitude_propagator/*.h\")
          local name=${header//\"/}
          name=${name#attitude_propagator/}
          [[ "$estimation_allows" == *" $name "* ]] || return 1 ;;
      esac ;;
  esac
  case "$file" in
    src/config/* | include/attitude_propagator/config/*)
      [[ "$header" == \"attitude_propagator/config/*.h\" && -f "include/${header//\"/}" ]] && return 0 ;;
  esac
  case "$header" in
    \<Eigen/*\> | \<unsupported/Eigen/*\> | \<boost/*\>) return 0 ;;
    \"attitude_propagator/estimation/*.h\")
      local path=${header//\"/}
      [[ "$path" != attitude_propagator/estimation/*/* && -f "include/$path" ]]
      return ;;
    \"attitude_propagator/*.h\")
      local path=${header//\"/}
      [[ "$path" != attitude_propagator/*/* && -f "include/$path" ]]
      return ;;
    \<*\>)
      local name=${header#<}
      name=${name%>}
      [[ "$std_headers" == *" $name "* ]]
      return ;;
  esac
  return 1
}

status=0
while IFS= read -r line; do
  file=${line%%:*}
  rest=${line#*:}
  lineno=${rest%%:*}
  header=$(sed -E 's/^[[:space:]]*#[[:space:]]*include[[:space:]]*([<"][^>"]*[>"]).*/\1/' <<<"${rest#*:}")
  if ! allowed "$header" "$file"; then
    echo "$file:$lineno: $header is not allowed in the core (std, Eigen, Boost, attitude_propagator/*.h)"
    status=1
  fi
done < <(grep -nHE '^[[:space:]]*#[[:space:]]*include' src/core/*.cpp src/core/estimation/*.cpp \
  include/attitude_propagator/*.h include/attitude_propagator/estimation/*.h \
  src/config/*.cpp include/attitude_propagator/config/*.h)
exit $status
