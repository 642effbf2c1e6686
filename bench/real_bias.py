#!/usr/bin/python3
"""The gyro bias estimate on real recordings, the IMU's own AHRS as late fixes (docs/real_data.md).

Usage: real_bias.py derive BAG TOPIC OUT.bag [--fix-topic NAME] [--period S] [--delay S]
                           [--covariance XX,YY,ZZ]
       real_bias.py rows NAME OUT.bag TOPIC LABEL STATES.csv SUMMARY.log WALK [LABEL STATES.csv
                         SUMMARY.log WALK ...] [--fix-topic NAME] [--verdict FILE]
                         [--judge LABEL]
       real_bias.py drift BAG TOPIC STATES.csv [--window S]
       real_bias.py fit BAG TOPIC STATES.csv [--period S] [--statistic mean|median]

derive copies BAG into OUT.bag (every message at its record time, as recorded) and adds a fix
topic (default /ahrs_fix): one of TOPIC's sensor_msgs/Imu messages per PERIOD (default 1 s), the
first whose stamp is at or after each whole period since the first message's stamp, as it is
(its AHRS orientation and orientation_covariance, its header), recorded at its stamp plus DELAY
(default 0.1 s): the AHRS's orientation as an absolute fix that arrives late. --covariance
puts a diagonal orientation_covariance (rad², body axes) in the fixes instead of the message's
("0,0,0": none, fix_stddev's; a large variance on the body axis that is vertical: the heading
left out). Prints how many, and the diagonals of their orientation_covariance.

rows compares each STATES.csv (propagate_bag --csv over OUT.bag with --fixes: stamp, qx, qy,
qz, qw, P_xx, ...; body_frame the IMU's own) with the AHRS orientation of TOPIC at the stamps of
the messages that were not made fixes: the state at that very stamp (the rates and the AHRS
come in the same messages, so each such stamp has a state; none is interpolated) as published,
with the fixes that had arrived by then, in the AHRS's own world (the fixes put it there: no
alignment, mount or time offset). Compared from the first state whose orientation variance (the
trace of P) is below 1 rad², where the fixes have taken hold (before it the attitude is the
gyro's from the identity), to the end of the run. Prints one Markdown table row per LABEL: the
RMS and the largest angle (rad), the RMS's change from the first LABEL's, and from SUMMARY.log
(propagate_bag's output) the fixes accepted (as resets), rejected by the gate and too old, the
final bias estimate with its standard deviation, and the standard deviation the prior (the
summary's) would have grown to by the random walk WALK (rad/s/√s) alone over the run, as if the
fixes had taught nothing ("-" for a run without the estimate). With --verdict FILE, writes there
whether the RMS of LABEL --judge (default the last) is below the first's, with both figures,
and the RMS of the LABELs after it in the list (the oracles) against the first's. On
stderr: the samples compared and from when, the error's RMS by body axis (the component of
Log(q_state^-1 q_AHRS)), and its RMS 0.1 to 0.2 s after a fix's stamp (the fix, 0.1 s late,
has just arrived) and in the last 0.1 s before the next fix's stamp: what is there right after
a fix no bias estimate can remove, what grows over the second is what it could.

drift compares STATES.csv of a run without fixes with the AHRS over windows of S seconds
(default 10) ending at every 10th message: the rate at which the gyro's integration departs from
the AHRS, -log((q_a^-1 q_b)^-1 (t_a^-1 t_b)) / (b - a) in the body frame at b (rad/s, the bias
the gyro would have if the AHRS were right: the sign of gyro_bias), and prints its mean and
standard deviation over the windows per axis. A constant bias shows as the mean, with a spread
that shrinks as the window grows.

fit prints, as a gyro_bias value "[x,y,z]", the constant bias fitted offline from the same run
without fixes: over back-to-back windows of PERIOD (default 1 s, the fixes' period: what a bias
has to explain between two fixes), the mean of drift's rates (--statistic mean, the least-squares
constant) or their median per axis (--statistic median, the constant most seconds agree on,
which a few jumps of the AHRS do not move). propagate_bag with that gyro_bias and no estimate,
the fixes applied as in the other runs, is the oracle: what a bias estimate that had the
constant from the start could do at best. On stderr: the mean and the median without the windows
departing faster than 0.2 rad/s on an axis (a jump of the AHRS, not a bias).

Runs with Debian's /usr/bin/python3 and python3-rosbag; no other dependency.
"""
import bisect
import csv
import math
import re
import sys

import rosbag
import rospy

# The quaternion helpers of the window errors' script, beside this one.
from real_windows import angle, conj, log, mul, normalized

FIXED_VARIANCE = 1.0  # rad²: the trace of P below which the fixes have taken hold
STRIDE = 10  # drift: a window ends at every STRIDE-th message
JUMP_RATE = 0.2  # rad/s: fit: a window departing faster than this on an axis holds a jump


def options(argv, defaults):
    """Splits argv into positional arguments and --name value pairs (names from defaults)."""
    positional, values, i = [], dict(defaults), 0
    while i < len(argv):
        key = argv[i][2:].replace("-", "_") if argv[i].startswith("--") else None
        if key in values and i + 1 < len(argv):
            values[key] = type(defaults[key])(argv[i + 1])
            i += 2
        elif key is not None:
            sys.exit(__doc__)
        else:
            positional.append(argv[i])
            i += 1
    return positional, values


def has_orientation(msg):
    o = msg.orientation
    return not (o.x == 0 and o.y == 0 and o.z == 0 and o.w == 0)


def derive(argv):
    positional, o = options(argv, {"fix_topic": "/ahrs_fix", "period": 1.0, "delay": 0.1,
                                   "covariance": ""})
    if len(positional) != 3:
        sys.exit(__doc__)
    source, topic, target = positional
    start, due, fixes, covariances = None, None, 0, set()
    with rosbag.Bag(source) as bag:
        if o["fix_topic"] in bag.get_type_and_topic_info().topics:
            sys.exit("real_bias: %s has a topic %s already" % (source, o["fix_topic"]))
        with rosbag.Bag(target, "w") as out:
            for name, msg, t, header in bag.read_messages(return_connection_header=True):
                out.write(name, msg, t, connection_header=header)
                if name != topic or not has_orientation(msg):
                    continue
                stamp = msg.header.stamp.to_sec()
                if start is None:
                    start = due = stamp
                if stamp >= due:
                    if o["covariance"]:
                        xx, yy, zz = (float(v) for v in o["covariance"].split(","))
                        msg.orientation_covariance = [xx, 0, 0, 0, yy, 0, 0, 0, zz]
                    out.write(o["fix_topic"], msg, msg.header.stamp + rospy.Duration(o["delay"]))
                    fixes += 1
                    c = msg.orientation_covariance
                    covariances.add("[%.4g, %.4g, %.4g]" % (c[0], c[4], c[8]))
                    due = start + o["period"] * (math.floor((stamp - start) / o["period"]) + 1)
    print("%d fixes on %s, one per %g s, recorded %g s after their stamps; their "
          "orientation_covariance diagonal: %s" %
          (fixes, o["fix_topic"], o["period"], o["delay"],
           ", ".join(sorted(covariances)) or "none"))


def read_truth(path, topic, fix_topic):
    """The AHRS samples (stamp in ns, q) that were not made fixes, the first stamp, and the
    fixes' stamps in order."""
    truth, fixes = [], set()
    with rosbag.Bag(path) as bag:
        for name, msg, _ in bag.read_messages(topics=[topic, fix_topic]):
            if name == fix_topic:
                fixes.add(msg.header.stamp.to_nsec())
            elif has_orientation(msg):
                o = msg.orientation
                truth.append((msg.header.stamp.to_nsec(), normalized((o.w, o.x, o.y, o.z))))
    truth.sort()
    return [(t, q) for t, q in truth if t not in fixes], truth[0][0], sorted(fixes)


def read_states(path):
    stamps, quats, variances = [], [], []
    with open(path, newline="") as f:
        for row in csv.DictReader(f):
            stamps.append(float(row["stamp"]))
            quats.append((float(row["qw"]), float(row["qx"]), float(row["qy"]), float(row["qz"])))
            variances.append(float(row["P_xx"]) + float(row["P_yy"]) + float(row["P_zz"]))
    return stamps, quats, variances


def state_at(stamps, stamp_ns):
    """The index of the state at that stamp (the CSV's stamps are rounded to 0.1 µs), or None."""
    s = stamp_ns * 1e-9
    k = bisect.bisect_left(stamps, s - 1e-6)
    return k if k < len(stamps) and abs(stamps[k] - s) <= 1e-6 else None


def summary(path):
    """The fixes line of a propagate_bag summary: counters and the bias estimate."""
    text = open(path, encoding="utf-8").read()
    line = next((l for l in text.splitlines() if l.strip().startswith("fixes:")), "")

    def count(pattern):
        m = re.search(pattern, line)
        return int(m.group(1)) if m else None

    vector = r"\[([^\]]*)\]"
    bias = re.search(r"gyro bias estimate " + vector + r" rad/s, standard deviation " + vector,
                     line)
    return {
        "read": count(r"fixes: (\d+) ="), "accepted": count(r"= (\d+) accepted"),
        "resets": count(r"\((\d+) as resets\)"), "gate": count(r"(\d+) rejected_gate"),
        "too_old": count(r"(\d+) too_old"), "refused": count(r"(\d+) refused"),
        "bias": [float(v) for v in bias.group(1).split(",")] if bias else None,
        "stddev": [float(v) for v in bias.group(2).split(",")] if bias else None,
        "prior": float(re.search(r"\(prior ([^)]*)\)", line).group(1)) if bias else None,
    }


def vector_text(v):
    return "[%s]" % ", ".join("%.3g" % x for x in v)


def rows(argv):
    positional, o = options(argv, {"fix_topic": "/ahrs_fix", "verdict": "", "judge": ""})
    if len(positional) < 7 or (len(positional) - 3) % 4:
        sys.exit(__doc__)
    name, path, topic = positional[:3]
    truth, first, fix_stamps = read_truth(path, topic, o["fix_topic"])
    results = []
    for i in range(3, len(positional), 4):
        label, states_path, log_path, walk = positional[i:i + 4]
        stamps, quats, variances = read_states(states_path)
        fixed = next((k for k, v in enumerate(variances) if v < FIXED_VARIANCE), len(stamps))
        errors, start, missing = [], None, 0
        axes, early, late = [], [], []
        for t, qt in truth:
            k = state_at(stamps, t)
            if k is None:
                missing += 1
            elif k >= fixed:
                errors.append(angle(qt, quats[k]))
                start = t if start is None else start
                # The error by body axis (state to AHRS), and by the time since the last fix's
                # stamp: 0.1 to 0.2 s after it (the fix, 0.1 s late, has arrived) against the
                # last 0.1 s before the next.
                axes.append(log(mul(conj(quats[k]), qt)))
                f = bisect.bisect_right(fix_stamps, t) - 1
                if f >= 0 and f + 1 < len(fix_stamps):
                    since = (t - fix_stamps[f]) * 1e-9
                    if 0.1 <= since < 0.2:
                        early.append(errors[-1])
                    elif (fix_stamps[f + 1] - t) * 1e-9 <= 0.1:
                        late.append(errors[-1])
        if not errors:
            sys.exit("real_bias: %s: no state below %g rad² of variance" %
                     (states_path, FIXED_VARIANCE))
        rms = math.sqrt(sum(x * x for x in errors) / len(errors))
        s = summary(log_path)
        bias, alone = "-", "-"
        if s["bias"]:
            bias = "%s ± %s" % (vector_text(s["bias"]), vector_text(s["stddev"]))
            # The prior grown by the random walk over the run, as if no fix had taught anything.
            grown = s["prior"] ** 2 + float(walk) ** 2 * (stamps[-1] - stamps[0])
            alone = "%.3g" % math.sqrt(grown)
        change = "%+.2f %%" % (100.0 * (rms / results[0][1] - 1.0)) if results else "-"
        print("| %s | %s | %.4f | %.3f | %s | %d of %d (%d as resets) | %d | %d | %s | %s |" %
              (name, label, rms, max(errors), change, s["accepted"],
               s["read"], s["resets"], s["gate"], s["too_old"], bias, alone))
        results.append((label, rms, max(errors)))
        root_mean_square = lambda v: math.sqrt(sum(x * x for x in v) / max(1, len(v)))
        print("real_bias: %s %s: %d AHRS samples compared, from %.2f s after the first on (%d "
              "without a state); RMS by body axis %s rad; RMS 0.1 to 0.2 s after a fix's stamp "
              "%.4f rad, in the last 0.1 s before the next %.4f rad" %
              (name, label, len(errors), (start - first) * 1e-9, missing,
               vector_text([root_mean_square([a[j] for a in axes]) for j in range(3)]),
               root_mean_square(early), root_mean_square(late)), file=sys.stderr)
    if o["verdict"]:
        judged = [r for r in results if r[0] == o["judge"]] or results[-1:]
        (first_label, first_rms, first_max), (label, rms, largest) = results[0], judged[0]
        with open(o["verdict"], "w") as f:
            f.write("On %s %s %s the error against %s: RMS %.4f rad against %.4f (%+.2f %%), "
                    "largest %.3f rad against %.3f.\n" %
                    (name, label, "reduces" if rms < first_rms else "does not reduce",
                     first_label, rms, first_rms, 100.0 * (rms / first_rms - 1.0), largest,
                     first_max))
            after = results[results.index(judged[0]) + 1:]
            if after:
                f.write("Against %s, the runs after %s in the table: %s.\n" %
                        (first_label, label, ", ".join("%s RMS %.4f rad (%+.2f %%)" %
                                          (l, r, 100.0 * (r / first_rms - 1.0))
                                          for l, r, _ in after)))


def drift_rates(path, topic, states_path, window, stride=STRIDE):
    """The rates at which the gyro's integration departs from the AHRS over windows of `window`
    seconds ending at every `stride`-th message (rad/s, body frame at the window's end)."""
    truth = []
    with rosbag.Bag(path) as bag:
        for _, msg, _ in bag.read_messages(topics=[topic]):
            if has_orientation(msg):
                q = msg.orientation
                truth.append((msg.header.stamp.to_nsec(), normalized((q.w, q.x, q.y, q.z))))
    truth.sort()
    stamps, quats, _ = read_states(states_path)
    rates, k = [], 0
    for i in range(stride - 1, len(truth), stride):
        tb, qtb = truth[i]
        target = tb - window * 1e9
        while k + 1 < i and truth[k + 1][0] <= target:
            k += 1
        ta, qta = truth[k]
        if ta > target or target - ta > 0.05 * window * 1e9:
            continue
        a, b = state_at(stamps, ta), state_at(stamps, tb)
        if a is None or b is None:
            continue
        estimate = mul(conj(quats[a]), quats[b])
        e = log(mul(conj(estimate), mul(conj(qta), qtb)))
        rates.append([-x / ((tb - ta) * 1e-9) for x in e])
    if not rates:
        sys.exit("real_bias: no window of %g s" % window)
    return rates


def drift(argv):
    positional, o = options(argv, {"window": 10.0})
    if len(positional) != 3:
        sys.exit(__doc__)
    rates = drift_rates(*positional, o["window"])
    mean = [sum(r[j] for r in rates) / len(rates) for j in range(3)]
    spread = [math.sqrt(sum((r[j] - mean[j]) ** 2 for r in rates) / len(rates)) for j in range(3)]
    print("%s ± %s rad/s over %d windows of %g s" %
          (vector_text(mean), vector_text(spread), len(rates), o["window"]))


def fit(argv):
    positional, o = options(argv, {"period": 1.0, "statistic": "mean"})
    if len(positional) != 3 or o["statistic"] not in ("mean", "median"):
        sys.exit(__doc__)
    path, topic, states_path = positional
    # Back-to-back windows of one fix period: what a constant bias would have to explain
    # between two fixes. Their mean is the least-squares constant, their median the constant
    # most of the seconds agree on.
    truth_stamps = []
    with rosbag.Bag(path) as bag:
        for _, msg, _ in bag.read_messages(topics=[topic]):
            if has_orientation(msg):
                truth_stamps.append(msg.header.stamp.to_nsec())
    per_second = len(truth_stamps) / max(1e-9, (max(truth_stamps) - min(truth_stamps)) * 1e-9)
    stride = max(1, int(round(per_second * o["period"])))
    rates = drift_rates(path, topic, states_path, o["period"], stride)
    if o["statistic"] == "mean":
        value = [sum(r[j] for r in rates) / len(rates) for j in range(3)]
    else:
        value = [sorted(r[j] for r in rates)[len(rates) // 2] for j in range(3)]
    print("[%s]" % ",".join("%.4g" % x for x in value))
    # On stderr: how much of the mean a few seconds carry, those in which the AHRS jumped (a rate
    # no gyro bias comes near: more than JUMP_RATE on an axis).
    calm = [r for r in rates if max(abs(x) for x in r) <= JUMP_RATE]
    print("real_bias: %s over %d windows of %g s; without the %d beyond %g rad/s on an axis (the "
          "AHRS's jumps), the mean would be %s rad/s and the median %s rad/s" %
          (o["statistic"], len(rates), o["period"], len(rates) - len(calm), JUMP_RATE,
           vector_text([sum(r[j] for r in calm) / max(1, len(calm)) for j in range(3)]),
           vector_text([sorted(r[j] for r in calm)[len(calm) // 2] if calm else 0.0
                        for j in range(3)])), file=sys.stderr)


def main(argv):
    commands = {"derive": derive, "rows": rows, "drift": drift, "fit": fit}
    if not argv or argv[0] not in commands:
        sys.exit(__doc__)
    commands[argv[0]](argv[1:])


if __name__ == "__main__":
    main(sys.argv[1:])
