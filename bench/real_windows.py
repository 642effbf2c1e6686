#!/usr/bin/python3
"""Relative (window) errors on a real recording against the IMU's own AHRS (docs/real_data.md).

Usage: real_windows.py BAG TRUTH_TOPIC EVALUATION.csv STATES_DIR --mount X Y Z W [--max-dt S]
                       [--lowest FILE]

evaluate_bag prints the relative rotation error over 1 s and 10 s only, and its series CSV holds
the absolute error angle alone, from which no relative error follows. This computes the figure
over 60 s from the states themselves: STATES_DIR/INTEGRATOR.RATE_SAMPLES.csv is propagate_bag's
--csv output for each row of evaluate_bag's EVALUATION.csv (stamp, qx, qy, qz, qw, ...;
body_frame the IMU's own), the truth is the orientation of TRUTH_TOPIC's sensor_msgs/Imu
messages, and the offset (truth - rates) and the mount (the sensor-to-truth-body rotation q_ST)
are the ones evaluate_bag found (its CSV's offset_s, its report's `mount q_ST`, given as
--mount). As evaluate_bag does: the states are read at each truth stamp less the offset (here by
a cubic through the four states around it, in the tangent space of the nearest, where
evaluate_bag takes six; none across a gap longer than --max-dt), the relative error of a window
is the angle between the truth's rotation over it and the estimate's (q_ST^-1 q(a)^-1 q(c)
q_ST), windows end at every 4th compared instant and start at the compared instant closest to
the window's length before, within 5 % of it (or 0.55 truth periods). Prints a Markdown table:
per method the RMS (and the largest) relative error in rad over 1 s and 10 s as evaluate_bag
printed them and over 60 s from here, and how far its own 1 s and 10 s RMS are from
evaluate_bag's (the check that the 60 s column measures the same thing); --lowest FILE also
writes there, in one line, the methods with the lowest RMS at each window. Runs with Debian's
/usr/bin/python3 and python3-rosbag; no other dependency.
"""
import bisect
import csv
import math
import re
import sys
import textwrap

import rosbag

STRIDE = 4  # evaluate_bag_core's kWindowStride


def mul(a, b):
    """Hamilton product of (w, x, y, z) quaternions."""
    aw, ax, ay, az = a
    bw, bx, by, bz = b
    return (aw * bw - ax * bx - ay * by - az * bz, aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx, aw * bz + ax * by - ay * bx + az * bw)


def conj(q):
    return (q[0], -q[1], -q[2], -q[3])


def normalized(q):
    n = math.sqrt(sum(x * x for x in q))
    return tuple(x / n for x in q)


def angle(a, b):
    """The rotation angle between two unit quaternions (rad)."""
    d = mul(conj(a), b)
    return 2.0 * math.atan2(math.sqrt(d[1] ** 2 + d[2] ** 2 + d[3] ** 2), abs(d[0]))


def log(q):
    """The rotation vector of a unit quaternion (w, x, y, z)."""
    if q[0] < 0:
        q = tuple(-x for x in q)
    v = math.sqrt(q[1] ** 2 + q[2] ** 2 + q[3] ** 2)
    if v < 1e-12:
        return (2 * q[1], 2 * q[2], 2 * q[3])
    f = 2.0 * math.atan2(v, q[0]) / v
    return (f * q[1], f * q[2], f * q[3])


def exp(r):
    a = math.sqrt(sum(x * x for x in r))
    if a < 1e-12:
        return normalized((1.0, 0.5 * r[0], 0.5 * r[1], 0.5 * r[2]))
    s = math.sin(0.5 * a) / a
    return (math.cos(0.5 * a), s * r[0], s * r[1], s * r[2])


def interpolate(stamps, quats, t):
    """A cubic through the (up to) four states around t, in the tangent space of the nearest."""
    near = min(range(len(stamps)), key=lambda i: abs(stamps[i] - t))
    base = quats[near]
    vectors = [log(mul(conj(base), q)) for q in quats]
    out = [0.0, 0.0, 0.0]
    for i, ti in enumerate(stamps):
        w = 1.0
        for j, tj in enumerate(stamps):
            if j != i:
                w *= (t - tj) / (ti - tj)
        out = [o + w * v for o, v in zip(out, vectors[i])]
    return mul(base, exp(out))


def read_truth(path, topic):
    stamps, quats = [], []
    with rosbag.Bag(path) as bag:
        for _, msg, _ in bag.read_messages(topics=[topic]):
            o = msg.orientation
            if o.x == 0 and o.y == 0 and o.z == 0 and o.w == 0:
                continue
            stamps.append(msg.header.stamp.to_sec())
            quats.append(normalized((o.w, o.x, o.y, o.z)))
    return stamps, quats


def read_states(path):
    stamps, quats = [], []
    with open(path, newline="") as f:
        for row in csv.DictReader(f):
            stamps.append(float(row["stamp"]))
            quats.append((float(row["qw"]), float(row["qx"]), float(row["qy"]), float(row["qz"])))
    return stamps, quats


def compared(truth, states, offset, mount, max_dt):
    """(stamp, truth, estimate in the truth's body) at each truth stamp the states meet."""
    t_stamps, t_quats = truth
    s_stamps, s_quats = states
    out = []
    for t, qt in zip(t_stamps, t_quats):
        ts = t - offset
        k = bisect.bisect_right(s_stamps, ts)
        if k == 0 or k == len(s_stamps):
            continue
        lo, hi = s_stamps[k - 1], s_stamps[k]
        if hi - lo > max_dt:
            continue
        # Two states on either side, fewer at the ends and at gaps longer than max_dt.
        first, last = k - 1, k
        while first > 0 and k - first < 2 and s_stamps[first] - s_stamps[first - 1] <= max_dt:
            first -= 1
        while (last + 1 < len(s_stamps) and last - k < 1 and
               s_stamps[last + 1] - s_stamps[last] <= max_dt):
            last += 1
        q = interpolate(s_stamps[first:last + 1], s_quats[first:last + 1], ts)
        out.append((t, qt, mul(q, mount)))
    return out


def windows(pairs, length, truth_period):
    errors = []
    k = 0
    tolerance = max(0.05 * length, 0.55 * truth_period)
    for i in range(STRIDE - 1, len(pairs), STRIDE):
        t, qt, qe = pairs[i]
        target = t - length
        while k + 1 < len(pairs) and pairs[k + 1][0] <= target:
            k += 1
        ta, qta, qea = pairs[k]
        if ta > target or target - ta > tolerance:
            continue
        errors.append(angle(mul(conj(qta), qt), mul(conj(qea), qe)))
    return errors


def main(argv):
    positional, mount, max_dt, lowest_file, i = [], None, 1.0, None, 0
    while i < len(argv):
        if argv[i] == "--mount":
            x, y, z, w = (float(v) for v in argv[i + 1:i + 5])
            mount = normalized((w, x, y, z))
            i += 5
        elif argv[i] == "--lowest":
            lowest_file = argv[i + 1]
            i += 2
        elif argv[i] == "--max-dt":
            max_dt = float(argv[i + 1])
            i += 2
        else:
            positional.append(argv[i])
            i += 1
    if len(positional) != 4 or mount is None:
        sys.exit(__doc__)
    bag, topic, evaluation, states_dir = positional
    with open(evaluation, newline="") as f:
        rows = list(csv.DictReader(f))
    truth = read_truth(bag, topic)
    intervals = sorted(b - a for a, b in zip(truth[0], truth[0][1:]))
    truth_period = intervals[len(intervals) // 2]
    print("| method | 1 s | 10 s | 60 s |")
    print("|---|---|---|---|")
    worst, windows_60, best = 0.0, 0, [[], [], []]
    for row in rows:
        path = "%s/%s.%s.csv" % (states_dir, row["integrator"], row["rate_samples"])
        pairs = compared(truth, read_states(path), float(row["offset_s"]), mount, max_dt)
        cells = []
        for n, (length, key) in enumerate(((1.0, "rpe_1s"), (10.0, "rpe_10s"), (60.0, None))):
            e = windows(pairs, length, truth_period)
            if not e:
                cells.append("none")
                continue
            rms = math.sqrt(sum(x * x for x in e) / len(e))
            if key:
                shown = float(row[key + "_rms_rad"])
                worst = max(worst, abs(rms - shown) / shown)
                cells.append("%.3g (%.3g)" % (shown, float(row[key + "_max_rad"])))
            else:
                windows_60 = len(e)
                shown = rms
                cells.append("%.3g (%.3g)" % (rms, max(e)))
            best[n].append((float("%.3g" % shown), row["method"]))
        print("| %s | %s |" % (row["method"], " | ".join(cells)))
    lowest = []
    for length, ranked in zip(("1 s", "10 s", "60 s"), best):
        if ranked:
            least = min(r for r, _ in ranked)
            names = [m for r, m in ranked if r == least]
            others = [m for r, m in ranked if r != least]
            if not others:
                names = ["every method"]
            elif len(names) > len(others):
                names = ["every method but " + ", ".join(others)]
            lowest.append("%s: %s (%.3g)" % (length, ", ".join(names), least))
    text = ("Lowest RMS (to three digits) over %s. 1 s and 10 s: evaluate_bag's; 60 s: "
            "bench/real_windows.py, over %d windows per method (the truth: %d samples, %.1f Hz); "
            "its own 1 s and 10 s RMS are within %.2f %% of evaluate_bag's." %
            ("; ".join(lowest), windows_60, len(truth[0]), 1.0 / truth_period, 100.0 * worst))
    # A number and its unit stay on one line.
    print()
    print(textwrap.fill(re.sub(r"(\d) (s|%|Hz)(?!\w)", "\\1\0\\2", text), 96).replace("\0", " "))
    if lowest_file:
        with open(lowest_file, "w") as f:
            f.write("; ".join(lowest) + "\n")


if __name__ == "__main__":
    main(sys.argv[1:])
