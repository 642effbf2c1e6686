#!/usr/bin/env bash
# The core library includes only what it may: the C++ standard library, Eigen, Boost and its
# own headers (include/attitude_propagator/, not the ROS layer's), each room only its own and
# those of the rooms before it (below); the config library (node parameters, src/config) may
# include any room and its own (attitude_propagator/config/*.h). An allow-list, because on
# Debian the ROS headers sit in /usr/include next to Boost's, where a stray include would
# compile. The ROS layer's headers live outside the core's include directory (src/ros/include),
# so the core's build cannot find them either.
cd "$(dirname "${BASH_SOURCE[0]}")/../.." || exit 1

std_headers=" algorithm any array atomic bitset cassert cctype cerrno cfenv cfloat charconv \
chrono cinttypes climits clocale cmath complex condition_variable cstdarg cstddef cstdint \
cstdio cstdlib cstring ctime cwchar deque exception execution filesystem fstream functional \
future initializer_list iomanip ios iosfwd iostream istream iterator limits list locale map \
memory memory_resource mutex new numeric optional ostream queue random ratio regex \
scoped_allocator set shared_mutex sstream stack stdexcept streambuf string string_view \
system_error thread tuple type_traits typeindex typeinfo unordered_map unordered_set utility \
valarray variant vector "

# The rooms of the core (docs/design.md §2.4), each above the ones before it: a file may include
# its own room's headers and those of the rooms listed before its own, never one after. The
# top level (include/attitude_propagator/*.h, src/core/*.cpp) is the engine, which wires every
# room, and two building blocks every room may use (limits.h, quoted_text.h).
rooms=(numerics time estimation models)
base_headers=" limits.h quoted_text.h "
# Files (header and source, by path in their room) that may include one room after their own,
# as file:room. The replay of late corrections (estimation/fix_replay) is the estimation room's
# rule of where a correction acts, but it acts in the model's history and replays the model's
# steps: it takes the models room's interface (Propagator, FixHistory, FixOutcome).
above_allowed=" estimation/fix_replay:models "

# room_of PATH: the room a file or header path lies in; "engine" at the top level, "config"
# for the node parameters (src/config, attitude_propagator/config), which may include any room.
room_of() {
  local path=$1
  path=${path#include/}
  path=${path#src/core/}
  path=${path#attitude_propagator/}
  case "$path" in
    src/config/* | config/*) echo config; return ;;
  esac
  local room
  for room in "${rooms[@]}"; do
    [[ "$path" == "$room"/* ]] && { echo "$room"; return; }
  done
  echo engine
}

# rank ROOM: its place in the order (the engine and config above every room).
rank() {
  local i
  for i in "${!rooms[@]}"; do [ "${rooms[$i]}" = "$1" ] && { echo "$i"; return; }; done
  echo 99
}

# own_header_allowed HEADER FILE: an attitude_propagator header that exists, in a room the
# file may include (its own, one before, or a building block); config headers from config only.
own_header_allowed() {
  local path=${1//\"/} file=$2
  [ -f "include/$path" ] || return 1
  local name=${path#attitude_propagator/}
  local from to
  from=$(room_of "$file")
  to=$(room_of "$path")
  if [ "$to" = config ]; then
    [ "$from" = config ]
    return
  fi
  if [ "$to" = engine ]; then
    # The top level: the engine's header, for the engine and config only; the building blocks
    # for everyone.
    [[ "$base_headers" == *" $name "* ]] && return 0
    [ "$from" = engine ] || [ "$from" = config ]
    return
  fi
  [ "$(rank "$to")" -le "$(rank "$from")" ] && return 0
  local stem=${file#include/attitude_propagator/}
  stem=${stem#src/core/}
  [[ "$above_allowed" == *" ${stem%.*}:$to "* ]]
}

allowed() {
  local header=$1 file=$2
  case "$header" in
    \<Eigen/*\> | \<unsupported/Eigen/*\> | \<boost/*\>) return 0 ;;
    \"attitude_propagator/*.h\")
      own_header_allowed "$header" "$file"
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
    echo "$file:$lineno: $header is not allowed here: the core takes std, Eigen, Boost and its own headers, each room its own and the rooms before it ($(room_of "$file") may not include $(room_of "${header//\"/}"); order: ${rooms[*]}, then the engine)"
    status=1
  fi
done < <(find src/core include/attitude_propagator src/config -name '*.h' -o -name '*.cpp' |
  sort | xargs grep -nHE '^[[:space:]]*#[[:space:]]*include')
exit $status
