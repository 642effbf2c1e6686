#!/usr/bin/env bash
# Whether estimate_gyro_bias lowers the attitude error on the public real recordings whose IMU
# messages carry the IMU's own AHRS orientation (test1.bag, ardrone_imu.bag; not part of the
# repository, see docs/real_data.md), with that orientation as absolute fixes: written into
# docs/real_data.md between the markers `<!-- real_bias: begin -->` and `<!-- real_bias: end -->`
# (the section "The gyro bias on the recordings"; the rest of the page is left as it is). For
# each recording present:
#   1. bench/real_bias.py derive: a copy of the bag with a fix topic /ahrs_fix, one AHRS
#      message (sensor_msgs/Imu, as it is) per second, recorded 0.1 s after its stamp;
#   2. propagate_bag over the copy with --fixes /ahrs_fix and the IMU's frame as the body, in
#      three settings: (a) estimate_gyro_bias false; (b) true, gyro_bias_stddev 2.424e-5 rad/s
#      and gyro_bias_random_walk 1e-6 rad/s/√s; (c) true, 0.01 rad/s and 1e-5 rad/s/√s (every
#      other parameter config/default.yaml's); the settings are given in full, so the runs do
#      not depend on the defaults, and the page says which setting has the defaults' values;
#   3. propagate_bag without fixes, and bench/real_bias.py drift: how fast the gyro's
#      integration departs from the AHRS over 10 s and 60 s windows (a constant bias, what the
#      estimate models, shows as the mean);
#   4. the oracles: bench/real_bias.py fit, the constant bias fitted offline from that run (the
#      mean (d) and the median (e) over back-to-back 1 s windows), and propagate_bag with it as
#      gyro_bias, no estimate, the fixes as in (a): what a bias estimate could do at best;
#   5. bench/real_bias.py rows: the error angle to the AHRS at the stamps of the messages that
#      were not made fixes, RMS and largest, the summary's fix counters and bias estimate, and
#      whether (c) lowers the RMS of (a); on the side, the error by body axis and right after
#      a fix against late in the second.
# A recording that is absent is skipped with a message; with none present the page is not
# touched. Runs the built propagate_bag (scripts/build.sh), never builds it; AP_WORKSPACE names
# another workspace (scripts/common.sh).
#   bash bench/real_bias.sh [DATA_DIR] [--doc FILE] [--work DIR]
# DATA_DIR (the folder holding the recordings) defaults to $REAL_DATA; with neither, nothing is
# run and the page is left as it is. --doc defaults to docs/real_data.md; --work (the runs'
# outputs and the derived bags, kept) to a new temporary folder.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/../scripts/common.sh"

data="${REAL_DATA:-}"
doc="$REPO_DIR/docs/real_data.md"
work=""
while [ $# -gt 0 ]; do
  case "$1" in
    --doc) doc="$(realpath "$2")"; shift ;;
    --work) work="$2"; shift ;;
    -h | --help) sed -n '2,31p' "$0"; exit 0 ;;
    -*) echo "usage: bash bench/real_bias.sh [DATA_DIR] [--doc FILE] [--work DIR]" >&2; exit 2 ;;
    *) data="$1" ;;
  esac
  shift
done

if [ ! -f "$doc" ]; then
  echo "real_bias: no $doc to write into" >&2
  exit 2
fi

# name, IMU topic (its AHRS orientation the fixes and the reference), the IMU's frame
recordings=(
  "test1 /imu/data imu_link"
  "ardrone_imu /ardrone/imu ardrone_base_link"
)
# label, random walk (rad/s/√s; - without the estimate), the settings
settings=(
  "(a) - estimate_gyro_bias=false"
  "(b) 1e-6 estimate_gyro_bias=true gyro_bias_stddev=2.424e-5 gyro_bias_random_walk=1e-6"
  "(c) 1e-5 estimate_gyro_bias=true gyro_bias_stddev=0.01 gyro_bias_random_walk=1e-5"
)
# The setting the verdict is about: the estimate with the defaults' values.
judged="(c)"
# label, statistic of real_bias.py fit: the constant bias fitted offline, as gyro_bias
oracles=(
  "(d) mean"
  "(e) median"
)
fix_topic=/ahrs_fix
present=()
for entry in "${recordings[@]}"; do
  read -r name _ _ <<<"$entry"
  if [ -f "$data/$name.bag" ]; then
    present+=("$entry")
  else
    echo "real_bias: $data/$name.bag is absent: skipped" >&2
  fi
done
if [ ${#present[@]} -eq 0 ]; then
  echo "real_bias: no recording in $data (give the folder as DATA_DIR or REAL_DATA);" \
    "$doc left as it is" >&2
  exit 0
fi
data="$(realpath "$data")"

source_ros
bin="$WORKSPACE/devel/lib/attitude_propagator"
if [ ! -x "$bin/propagate_bag" ]; then
  echo "real_bias: no $bin/propagate_bag: build with scripts/build.sh" >&2
  exit 1
fi
source_workspace
helper="$REPO_DIR/bench/real_bias.py"
[ -n "$work" ] || work="$(mktemp -d -t attitude_propagator_bias.XXXXXX)"
mkdir -p "$work"
work="$(realpath "$work")"
cd "$work"

# The bias values of config/default.yaml, and which setting has them.
default_of() { sed -n "s/^$1: *//p" "$REPO_DIR/config/default.yaml"; }
default_stddev="$(default_of gyro_bias_stddev)" default_walk="$(default_of gyro_bias_random_walk)"
fix_mode="$(default_of fix_mode)" fix_gate="$(default_of fix_gate)"
fix_history="$(default_of fix_history)" fix_stddev="$(default_of fix_stddev)"
same_number() {
  /usr/bin/python3 -c 'import sys; sys.exit(float(sys.argv[1]) != float(sys.argv[2]))' "$1" "$2"
}

# stdin filled to 96 columns, paragraph by paragraph, a number and its unit kept on one line.
wrap() {
  /usr/bin/python3 -c 'import re, sys, textwrap
paragraphs = [" ".join(p.split()) for p in sys.stdin.read().split("\n\n") if p.strip()]
print("\n\n".join(textwrap.fill(re.sub(r"(\d) (s|rad|rad/s|%)(?![\w/])", "\\1\0\\2", p), 96,
                                  break_on_hyphens=False, break_long_words=False).replace("\0", " ")
                    for p in paragraphs))'
}

table="$work/table.md" details="$work/details.md" verdicts="$work/verdicts.md"
: >"$table"
: >"$details"
: >"$verdicts"
for entry in "${present[@]}"; do
  read -r name topic frame <<<"$entry"
  echo "real_bias: $name" >&2
  derived="${name}_fixes.bag"
  rm -f "$derived"
  made="$(/usr/bin/python3 "$helper" derive "$data/$name.bag" "$topic" "$derived" \
    --fix-topic "$fix_topic")"
  row_args=()
  {
    echo
    echo "**$name.bag** ($topic, frame $frame): $made." | wrap
    echo
    echo "The summaries' fix lines:"
    echo
    echo '```text'
  } >>"$details"
  for setting in "${settings[@]}"; do
    read -r label walk rest <<<"$setting"
    read -r -a values <<<"$rest"
    tag="${label//[()]/}"
    sets=()
    for pair in "${values[@]}"; do sets+=(--set "$pair"); done
    "$bin/propagate_bag" "$derived" --rates "$topic" --set "body_frame=$frame" \
      --fixes "$fix_topic" "${sets[@]}" --csv "$name.$tag.csv" --no-progress </dev/null \
      >"$name.$tag.log" 2>&1 || { cat "$name.$tag.log" >&2; exit 1; }
    echo "$label $(grep '^  fixes:' "$name.$tag.log" | sed 's/^  //')" >>"$details"
    row_args+=("$label" "$name.$tag.csv" "$name.$tag.log" "$walk")
  done
  "$bin/propagate_bag" "$derived" --rates "$topic" --set "body_frame=$frame" \
    --csv "$name.gyro.csv" --no-progress </dev/null >"$name.gyro.log" 2>&1 ||
    { cat "$name.gyro.log" >&2; exit 1; }
  # The oracles: the constant bias fitted offline (gyro against AHRS, back-to-back 1 s windows)
  # given as gyro_bias, no estimate, the fixes as in (a).
  for oracle in "${oracles[@]}"; do
    read -r label statistic <<<"$oracle"
    tag="${label//[()]/}"
    bias="$(/usr/bin/python3 "$helper" fit "$derived" "$topic" "$name.gyro.csv" \
      --statistic "$statistic" 2>"$name.$tag.fit.log")"
    "$bin/propagate_bag" "$derived" --rates "$topic" --set "body_frame=$frame" \
      --fixes "$fix_topic" --set estimate_gyro_bias=false --set "gyro_bias=$bias" \
      --csv "$name.$tag.csv" --no-progress </dev/null >"$name.$tag.log" 2>&1 ||
      { cat "$name.$tag.log" >&2; exit 1; }
    echo "$label gyro_bias=$bias $(grep '^  fixes:' "$name.$tag.log" | sed 's/^  //')" \
      >>"$details"
    row_args+=("$label" "$name.$tag.csv" "$name.$tag.log" "-")
  done
  echo '```' >>"$details"
  /usr/bin/python3 "$helper" rows "$name.bag" "$derived" "$topic" "${row_args[@]}" \
    --fix-topic "$fix_topic" --verdict "$name.verdict.txt" --judge "$judged" \
    >>"$table" 2>"$name.rows.log" || { cat "$name.rows.log" >&2; exit 1; }
  { cat "$name.verdict.txt"; echo; } >>"$verdicts"
  {
    echo
    {
      sed -n "s/^real_bias: $name.bag \(([ac])\): \(.*\)/In \1: \2./p" "$name.rows.log"
      read -r label _ <<<"${oracles[0]}"
      printf 'The oracle %s is fitted %s.\n' "$label" \
        "$(sed -n 's/^real_bias: [a-z]* //p' "$name.${label//[()]/}.fit.log")"
      echo "Without fixes, the gyro's integration departs from the AHRS at (mean ± standard"
      echo "deviation over the windows, per body axis, in the sign of \`gyro_bias\`)"
      /usr/bin/python3 "$helper" drift "$derived" "$topic" "$name.gyro.csv" --window 10
      echo "and"
      printf '%s.\n' "$(/usr/bin/python3 "$helper" drift "$derived" "$topic" "$name.gyro.csv" \
        --window 60)"
    } | wrap
  } >>"$details"
done

default_label="none of the three"
for setting in "${settings[@]}"; do
  read -r label _ _ stddev walk <<<"$setting"
  if [ -n "$walk" ] && same_number "${stddev#*=}" "$default_stddev" &&
    same_number "${walk#*=}" "$default_walk"; then
    default_label="$label"
  fi
done

{
  cat <<EOF
Measured by \`bash bench/real_bias.sh [DATA_DIR]\`, which writes this section. Each recording
whose IMU messages carry the IMU's own AHRS orientation is copied with a fix topic
\`$fix_topic\` added (\`bench/real_bias.py derive\`): one of those messages per second (the
first at or after each whole second since the first), as it is (its orientation and
\`orientation_covariance\`; all zero: \`fix_stddev\`), recorded 0.1 s after its stamp.
propagate_bag runs over the copy with the IMU's frame as the body, as in

\`\`\`bash
propagate_bag test1_fixes.bag --rates /imu/data --set body_frame=imu_link --fixes $fix_topic \\
  --set estimate_gyro_bias=true --set gyro_bias_stddev=0.01 --set gyro_bias_random_walk=1e-5 \\
  --csv test1.c.csv
\`\`\`

in three settings and two oracles, every other parameter \`config/default.yaml\`'s (\`fix_mode\`
$fix_mode, \`fix_gate\` $fix_gate, \`fix_history\` $fix_history s, \`fix_stddev\` $fix_stddev rad):

EOF
  for setting in "${settings[@]}"; do
    read -r label _ rest <<<"$setting"
    echo "- $label \`$rest\`"
  done
  cat <<EOF
- (d) \`estimate_gyro_bias=false gyro_bias=[...]\`, the constant bias fitted offline: the mean,
  over back-to-back 1 s windows (the fixes' period), of the rate at which the gyro's integration
  departs from the AHRS (\`bench/real_bias.py fit\`, from the run without fixes), the
  least-squares constant
- (e) the same with the median of those rates per axis, the constant most seconds agree on
  (a few jumps of the AHRS do not move it)

(d) and (e) are the oracles: what an estimate that had the constant from the first state could
do at best, the fixes applied the same way.

The bias values of \`config/default.yaml\` (\`gyro_bias_stddev\` $default_stddev,
\`gyro_bias_random_walk\` $default_walk) are those of $default_label.

The error is the angle between the AHRS orientation at each stamp of the messages that were not
made fixes and the state there as published, with the fixes that had arrived by then (the rates
and the AHRS share the messages: no interpolation), in the AHRS's own world (the fixes put the
state there: no alignment, mount or time offset); from the first state whose orientation
variance (trace of P) is below 1 rad², where the first fix took hold, to the end of the run
(\`bench/real_bias.py rows\`). The fix counters and the bias estimate (body frame, its standard
deviation after ±) are the summary's; the last column is the standard deviation the prior grows
to by the random walk alone over the run, as if no fix had taught anything. Below the table, per
recording: for (a) and (c), the error's RMS by body axis (the components of Log(q_state^-1
q_AHRS)) and its RMS 0.1 to 0.2 s after a fix's stamp (the fix, 0.1 s late, has just arrived)
against the last 0.1 s before the next (what is there right after a fix no bias estimate
removes; what grows over the second is what one could); and, without fixes, how fast the gyro's
integration departs from the AHRS over 10 s and 60 s windows (\`bench/real_bias.py drift\`); a
constant gyro bias, what the estimate models, shows there as the mean, with a spread that shrinks
as the window grows.

| recording | setting | error RMS (rad) | largest (rad) | RMS against (a) | fixes accepted | rejected_gate | too_old | final bias estimate ± standard deviation (rad/s) | prior and random walk alone (rad/s) |
|---|---|---|---|---|---|---|---|---|---|
EOF
  cat "$table"
  echo
  wrap <"$verdicts"
  cat "$details"
} >"$work/section.md"

/usr/bin/python3 - "$doc" "$work/section.md" <<'PY'
import sys

doc, section = sys.argv[1], sys.argv[2]
begin, end = "<!-- real_bias: begin -->", "<!-- real_bias: end -->"
text = open(doc, encoding="utf-8").read()
body = open(section, encoding="utf-8").read().rstrip("\n")
block = begin + "\n" + body + "\n" + end
if begin in text and end in text:
    text = text[:text.index(begin)] + block + text[text.index(end) + len(end):]
else:
    text = text.rstrip("\n") + "\n\n## The gyro bias on the recordings\n\n" + block + "\n"
open(doc, "w", encoding="utf-8").write(text)
PY
echo "real_bias: wrote $doc (outputs in $work)" >&2
