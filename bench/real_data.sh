#!/usr/bin/env bash
# What the bag tools do with each public real recording (test1.bag, ardrone_imu.bag,
# phidgets_imu_upside_down.bag; not part of the repository, see docs/real_data.md), written into docs/real_data.md
# between the markers `<!-- >>> real recordings (bench/real_data.sh) -->` and
# `<!-- <<< real recordings -->` (the section "What the tools do with each recording"; the rest
# of the page is left as it is). For each recording present:
#   1. propagate_bag BAG --rates TOPIC --csv OUT, as a new user would first run it; when it asks
#      for a setting (`--set body_frame=<the IMU's frame>` for an IMU alone) again with it, and
#      once more with --set stamp_filter=sensor_clock: the summaries, the longest interval
#      between the states' stamps, and how far the filter moved the stamps and the final
#      attitude (from the two CSVs: the summary does not report the filter);
#   2. with an AHRS orientation in the IMU messages (test1, ardrone_imu): evaluate_bag BAG
#      --rates TOPIC --truth TOPIC --csv PREFIX (it draws PREFIX.png too), and per method
#      (integrator and rate_samples reading) the relative errors over 1 s and 10 s it prints,
#      with those over 60 s from bench/real_windows.py on propagate_bag's states of each method
#      (the series CSV holds the absolute error angle only, from which no relative error
#      follows).
# A recording that is absent is skipped with a message; with none present the page is not
# touched. Runs the built tools (scripts/build.sh), never builds them; AP_WORKSPACE names
# another workspace (scripts/common.sh).
#   bash bench/real_data.sh [DATA_DIR] [--doc FILE] [--work DIR]
# DATA_DIR (the folder holding the recordings) defaults to $REAL_DATA; with neither, nothing is
# run and the page is left as it is. --doc defaults to docs/real_data.md; --work (the runs' outputs, kept) to
# a new temporary folder.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/../scripts/common.sh"

data="${REAL_DATA:-}"
doc="$REPO_DIR/docs/real_data.md"
work=""
while [ $# -gt 0 ]; do
  case "$1" in
    --doc) doc="$(realpath "$2")"; shift ;;
    --work) work="$2"; shift ;;
    -h | --help) sed -n '2,24p' "$0"; exit 0 ;;
    -*) echo "usage: bash bench/real_data.sh [DATA_DIR] [--doc FILE] [--work DIR]" >&2; exit 2 ;;
    *) data="$1" ;;
  esac
  shift
done

# name, rate topic, whether its messages carry the IMU's own AHRS orientation
recordings=(
  "test1 /imu/data ahrs"
  "ardrone_imu /ardrone/imu ahrs"
  "phidgets_imu_upside_down /imu/data_raw -"
)
present=()
for entry in "${recordings[@]}"; do
  read -r name _ _ <<<"$entry"
  if [ -f "$data/$name.bag" ]; then
    present+=("$entry")
  else
    echo "real_data: $data/$name.bag is absent: skipped" >&2
  fi
done
if [ ${#present[@]} -eq 0 ]; then
  echo "real_data: no recording in $data (give the folder as DATA_DIR or REAL_DATA);" \
    "$doc left as it is" >&2
  exit 0
fi
data="$(realpath "$data")"

source_ros
bin="$WORKSPACE/devel/lib/attitude_propagator"
for tool in propagate_bag evaluate_bag; do
  if [ ! -x "$bin/$tool" ]; then
    echo "real_data: no $bin/$tool: build with scripts/build.sh" >&2
    exit 1
  fi
done
source_workspace
[ -n "$work" ] || work="$(mktemp -d -t attitude_propagator_real.XXXXXX)"
mkdir -p "$work"
work="$(realpath "$work")"
cd "$work"

# A tool's output as the docs show it: the bags by their names, the run's timing left out.
shown() { sed -e "s|$data/||g" -e 's/; [0-9.]* s wall, .*real time//' "$1"; }
# Runs a tool into LOG (stdout and stderr); prints its exit code.
run() {
  local log="$1"
  shift
  local rc=0
  "$@" >"$log" 2>&1 || rc=$?
  echo "$rc"
}

section="$work/section.md" overview="$work/overview.md" details="$work/details.md"
: >"$overview"
: >"$details"

for entry in "${present[@]}"; do
  read -r name topic ahrs <<<"$entry"
  bag="$data/$name.bag"
  echo "real_data: $name" >&2
  {
    echo
    echo "### $name.bag ($topic)"
    echo
    first_rc=$(run first.log "$bin/propagate_bag" "$bag" --rates "$topic" --csv "$name.csv")
    frame="$(sed -n 's/.*take it as the body: --set body_frame=\([^ )]*\).*/\1/p' first.log |
      head -1)"
    echo "\`propagate_bag $name.bag --rates $topic --csv $name.csv\` (exit $first_rc):"
    echo
    echo '```text'
    shown first.log
    echo '```'
    settings=()
    if [ -n "$frame" ]; then
      settings=(--set "body_frame=$frame")
      echo
      echo "It needs the IMU's frame as the body, which it names: with \`--set body_frame=$frame\`"
    fi
    rc=$(run plain.log "$bin/propagate_bag" "$bag" --rates "$topic" "${settings[@]}" \
      --csv "$name.csv")
    rc_filter=$(run filter.log "$bin/propagate_bag" "$bag" --rates "$topic" "${settings[@]}" \
      --set stamp_filter=sensor_clock --csv "${name}_sensor_clock.csv")
    echo "(exit $rc), and with \`--set stamp_filter=sensor_clock\` as well (exit $rc_filter):"
    echo
    echo '```text'
    shown plain.log
    shown filter.log
    echo '```'
    echo
    if grep -qi 'stamp\|filter' filter.log; then
      filter_said="The summary reports what the filter did (above); from the two CSVs,"
    else
      filter_said="The summary says nothing of what the filter did; from the two CSVs,"
    fi
    /usr/bin/python3 - "$name.csv" "${name}_sensor_clock.csv" "$filter_said" filter.txt <<'PY'
import csv
import math
import re
import sys
import textwrap


def read(path):
    with open(path, newline="") as f:
        return [(float(r["stamp"]), [float(r[k]) for k in ("qw", "qx", "qy", "qz")])
                for r in csv.DictReader(f)]


plain, filtered = read(sys.argv[1]), read(sys.argv[2])
intervals = [b[0] - a[0] for a, b in zip(plain, plain[1:])]
median = sorted(intervals)[len(intervals) // 2]
moved = sorted(abs(a[0] - b[0]) for a, b in zip(plain, filtered))
dot = min(1.0, abs(sum(x * y for x, y in zip(plain[-1][1], filtered[-1][1]))))
longest = max(intervals)
text = ("Gaps in the summary are intervals longer than `max_dt` (1 s by default) or than 5.5 "
        "mean periods of the stream (a dropout), over which the state is held: the states' "
        "stamps are %.2f ms apart at the median, %d intervals of %d are longer than 2.5 of "
        "those, the longest %.3f s. %s the filter moved the stamps by %.3f ms at the median and "
        "%.1f ms at most (%d states in both), and the final attitudes are %.3f° apart." %
        (1e3 * median, sum(1 for d in intervals if d > 2.5 * median), len(intervals), longest,
         sys.argv[3],
         1e3 * moved[len(moved) // 2], 1e3 * moved[-1], len(plain),
         math.degrees(2.0 * math.acos(dot))))
# A number and its unit stay on one line.
print(textwrap.fill(re.sub(r"(\d) (s|ms)(?!\w)", "\\1\0\\2", text), 96).replace("\0", " "))
with open(sys.argv[4], "w") as f:
    f.write("%.1f ms (median %.3f ms); final attitude %.3f° apart\n" %
            (1e3 * moved[-1], 1e3 * moved[len(moved) // 2], math.degrees(2.0 * math.acos(dot))))
PY
    if [ "$ahrs" = ahrs ]; then
      eval_rc=$(run evaluate.log "$bin/evaluate_bag" "$bag" --rates "$topic" --truth "$topic" \
        --csv "$name.evaluation")
      echo
      echo "\`evaluate_bag $name.bag --rates $topic --truth $topic --csv $name.evaluation\`"
      echo "(exit $eval_rc; no setting needed: it reads the rates in their own frame) found:"
      echo
      echo '```text'
      grep -E '^  (time offset|mount q_ST|truth resolves)' evaluate.log | sed "s|$data/||g"
      echo '```'
      echo
      if [ -f "$name.evaluation.csv" ]; then
        mount="$(sed -n 's/.*mount q_ST \[x y z w\] = \[\([^]]*\)\].*/\1/p' evaluate.log)"
        mkdir -p "$name.states"
        # The methods of evaluate_bag's rows (integrator,rate_samples), each run on its own.
        for method in $(tail -n +2 "$name.evaluation.csv" | cut -d, -f2,3); do
          "$bin/propagate_bag" "$bag" --rates "$topic" "${settings[@]}" \
            --set "integrator=${method%,*}" --set "rate_samples=${method#*,}" \
            --csv "$name.states/${method%,*}.${method#*,}.csv" </dev/null >states.log 2>&1 ||
            { cat states.log >&2; exit 1; }
        done
        echo "Relative (window) error, RMS (largest) in rad, per method:"
        echo
        # shellcheck disable=SC2086
        /usr/bin/python3 "$REPO_DIR/bench/real_windows.py" "$bag" "$topic" "$name.evaluation.csv" \
          "$name.states" --mount $mount --lowest lowest.txt
      else
        echo "evaluate_bag gave no result:"
        echo
        echo '```text'
        shown evaluate.log | tail -5
        echo '```'
      fi
    else
      echo
      echo "No AHRS orientation in its messages (zero quaternion): nothing for evaluate_bag to"
      echo "compare with."
    fi
  } >>"$details"
  # One row of the overview: the first try, the run with its setting, the filter, the windows.
  accepted="$(sed -n 's/.*), \([0-9]*\) accepted, .*/\1/p' plain.log | head -1)"
  total="$(sed -n 's/^propagate_bag: \([0-9]*\) messages.*/\1/p' plain.log | head -1)"
  gaps="$(sed -n 's/.* gaps \([0-9]*\), .*/\1/p' plain.log | head -1)"
  first="exit $first_rc"
  [ -z "$frame" ] || first="$first, asks for \`--set body_frame=$frame\`"
  lowest="no AHRS: none"
  [ ! -s lowest.txt ] || lowest="$(cat lowest.txt)"
  echo "| $name.bag | $first | $accepted of $total accepted (exit $rc), $gaps gaps |" \
    "$(cat filter.txt) | $lowest |" >>"$overview"
  rm -f lowest.txt
done

{
  echo "Every shared recording run through both tools as a new user would run them first, by"
  echo "\`bash bench/real_data.sh [DATA_DIR]\`, which writes this section (the bags are named"
  echo "relative to their folder; the runs' timings are left out). The gravity measurements are"
  echo "[below](#how-it-was-measured)."
  echo
  echo "| recording | \`propagate_bag BAG --rates TOPIC --csv OUT\` | with that setting |" \
    "\`stamp_filter: sensor_clock\` moved the stamps by, at most |" \
    "lowest relative error (rad RMS) to the AHRS |"
  echo "|---|---|---|---|---|"
  cat "$overview"
  cat "$details"
} >"$section"

/usr/bin/python3 - "$doc" "$section" <<'PY'
import sys

doc, section = sys.argv[1], sys.argv[2]
begin, end = "<!-- >>> real recordings (bench/real_data.sh) -->", "<!-- <<< real recordings -->"
text = open(doc, encoding="utf-8").read()
body = open(section, encoding="utf-8").read().rstrip("\n")
block = begin + "\n" + body + "\n" + end
if begin in text and end in text:
    text = text[:text.index(begin)] + block + text[text.index(end) + len(end):]
else:
    heading = "## What the tools do with each recording\n\n" + block + "\n\n"
    anchor = "## How it was measured"
    at = text.index(anchor) if anchor in text else len(text)
    text = text[:at] + heading + text[at:]
open(doc, "w", encoding="utf-8").write(text)
PY
echo "real_data: wrote $doc (outputs in $work)" >&2
