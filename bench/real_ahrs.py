#!/usr/bin/python3
"""The tilt on real recordings against the IMU's own AHRS (docs/real_data.md).

Usage: real_ahrs.py BAG IMU_TOPIC [--mag TOPIC] [--skip S] ESTIMATE.csv [ESTIMATE.csv ...]

Reads the IMU messages of BAG (their gyro, accelerometer and the AHRS orientation the sensor
itself computed) and each ESTIMATE.csv (propagate_bag --csv: stamp, qx, qy, qz, qw, ... in the
IMU's own frame, body_frame set to it), runs a Madgwick gradient-descent filter (imu_filter_
madgwick's update, with the magnetometer when --mag is given) on the same messages at the gains
0.01, 0.03, 0.1 and 0.3, and prints, after the first S seconds (default 10), the RMS and the
largest angle between the world's up seen in the body by each estimate and by the AHRS: a
Markdown table, one row per estimate and per gain.

The AHRS's world may point z up (ENU, NWU) or down (NED): the sign is taken from the first
second, where the accelerometer reads the body's up. Runs with Debian's /usr/bin/python3 and
python3-rosbag; no other dependency.
"""
import bisect
import csv
import math
import sys

import rosbag


def normalized(v):
    n = math.sqrt(sum(x * x for x in v))
    return [x / n for x in v] if n > 0 else v


def body_up(q):
    """The world's z seen in the body: the last row of R(q), q = (w, x, y, z) from body to world."""
    w, x, y, z = q
    return [2 * (x * z - w * y), 2 * (w * x + y * z), 1 - 2 * (x * x + y * y)]


def angle(a, b):
    c = [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
    return math.atan2(math.sqrt(sum(x * x for x in c)), sum(x * y for x, y in zip(a, b)))


def madgwick(samples, beta, use_mag):
    """imu_filter_madgwick's update (Madgwick 2010): q' = q/2 (x) (0, w) - beta grad/|grad|,
    one Euler step a sample, started from the first accelerometer (and magnetometer) sample."""
    q = initial(samples[0], use_mag)
    out = []
    previous = None
    for t, w, a, m, _ in samples:
        if previous is not None:
            q = madgwick_step(q, w, a, m if use_mag else None, beta, t - previous)
        previous = t
        out.append((t, q))
    return out


def initial(sample, use_mag):
    """Roll and pitch from the accelerometer, yaw from the tilt-compensated field (or zero)."""
    _, _, a, m, _ = sample
    ax, ay, az = a
    roll = math.atan2(ay, az)
    pitch = math.atan2(-ax, math.sqrt(ay * ay + az * az))
    yaw = 0.0
    if use_mag and m is not None:
        cr, sr, cp, sp = math.cos(roll), math.sin(roll), math.cos(pitch), math.sin(pitch)
        mx = m[0] * cp + m[1] * sr * sp + m[2] * cr * sp
        my = m[1] * cr - m[2] * sr
        yaw = math.atan2(-my, mx) + math.pi / 2  # ENU: magnetic north along +y
    cy, sy = math.cos(yaw / 2), math.sin(yaw / 2)
    cp, sp = math.cos(pitch / 2), math.sin(pitch / 2)
    cr, sr = math.cos(roll / 2), math.sin(roll / 2)
    return [cr * cp * cy + sr * sp * sy, sr * cp * cy - cr * sp * sy,
            cr * sp * cy + sr * cp * sy, cr * cp * sy - sr * sp * cy]


def madgwick_step(q, w, a, m, beta, dt):
    q0, q1, q2, q3 = q
    gx, gy, gz = w
    dot = [0.5 * (-q1 * gx - q2 * gy - q3 * gz), 0.5 * (q0 * gx + q2 * gz - q3 * gy),
           0.5 * (q0 * gy - q1 * gz + q3 * gx), 0.5 * (q0 * gz + q1 * gy - q2 * gx)]
    if a is not None and any(a):
        ax, ay, az = normalized(a)
        if m is None or not any(m):
            # The objective f = C_BW e_up - a and its Jacobian (imu_filter_madgwick, IMU only).
            f = [2 * (q1 * q3 - q0 * q2) - ax, 2 * (q0 * q1 + q2 * q3) - ay,
                 2 * (0.5 - q1 * q1 - q2 * q2) - az]
            J = [[-2 * q2, 2 * q3, -2 * q0, 2 * q1], [2 * q1, 2 * q0, 2 * q3, 2 * q2],
                 [0, -4 * q1, -4 * q2, 0]]
        else:
            mx, my, mz = normalized(m)
            # The field in the world through q, its horizontal part along the reference's x
            # (Madgwick's b = (bx, 0, bz)), then the earth's up and that field as objectives.
            hx = (mx * (q0 * q0 + q1 * q1 - q2 * q2 - q3 * q3) + 2 * my * (q1 * q2 - q0 * q3)
                  + 2 * mz * (q1 * q3 + q0 * q2))
            hy = (2 * mx * (q1 * q2 + q0 * q3) + my * (q0 * q0 - q1 * q1 + q2 * q2 - q3 * q3)
                  + 2 * mz * (q2 * q3 - q0 * q1))
            bx = math.sqrt(hx * hx + hy * hy)
            bz = (2 * mx * (q1 * q3 - q0 * q2) + 2 * my * (q2 * q3 + q0 * q1)
                  + mz * (q0 * q0 - q1 * q1 - q2 * q2 + q3 * q3))
            f = [2 * (q1 * q3 - q0 * q2) - ax, 2 * (q0 * q1 + q2 * q3) - ay,
                 2 * (0.5 - q1 * q1 - q2 * q2) - az,
                 2 * bx * (0.5 - q2 * q2 - q3 * q3) + 2 * bz * (q1 * q3 - q0 * q2) - mx,
                 2 * bx * (q1 * q2 - q0 * q3) + 2 * bz * (q0 * q1 + q2 * q3) - my,
                 2 * bx * (q0 * q2 + q1 * q3) + 2 * bz * (0.5 - q1 * q1 - q2 * q2) - mz]
            J = [[-2 * q2, 2 * q3, -2 * q0, 2 * q1], [2 * q1, 2 * q0, 2 * q3, 2 * q2],
                 [0, -4 * q1, -4 * q2, 0],
                 [-2 * bz * q2, 2 * bz * q3, -4 * bx * q2 - 2 * bz * q0, -4 * bx * q3 + 2 * bz * q1],
                 [-2 * bx * q3 + 2 * bz * q1, 2 * bx * q2 + 2 * bz * q0, 2 * bx * q1 + 2 * bz * q3,
                  -2 * bx * q0 + 2 * bz * q2],
                 [2 * bx * q2, 2 * bx * q3 - 4 * bz * q1, 2 * bx * q0 - 4 * bz * q2, 2 * bx * q1]]
        s = [sum(J[r][c] * f[r] for r in range(len(f))) for c in range(4)]
        s = normalized(s)
        dot = [d - beta * x for d, x in zip(dot, s)]
    q = [x + d * dt for x, d in zip(q, dot)]
    return normalized(q)


def read(bag_path, imu_topic, mag_topic):
    samples, mags = [], []
    with rosbag.Bag(bag_path) as bag:
        topics = [imu_topic] + ([mag_topic] if mag_topic else [])
        for topic, msg, _ in bag.read_messages(topics):
            t = msg.header.stamp.to_sec()
            if topic == mag_topic:
                mags.append((t, [msg.magnetic_field.x, msg.magnetic_field.y, msg.magnetic_field.z]))
                continue
            o = msg.orientation
            samples.append([t, [msg.angular_velocity.x, msg.angular_velocity.y, msg.angular_velocity.z],
                            [msg.linear_acceleration.x, msg.linear_acceleration.y,
                             msg.linear_acceleration.z], None, [o.w, o.x, o.y, o.z]])
    samples.sort(key=lambda s: s[0])
    mags.sort(key=lambda m: m[0])
    times = [m[0] for m in mags]
    for s in samples:  # the newest field sample at or before each IMU sample
        i = bisect.bisect_right(times, s[0]) - 1
        s[3] = mags[i][1] if i >= 0 else None
    return samples


def read_estimate(path):
    rows = []
    with open(path) as f:
        for row in csv.DictReader(f):
            rows.append((float(row["stamp"]), [float(row["qw"]), float(row["qx"]),
                                               float(row["qy"]), float(row["qz"])]))
    return rows


def ahrs_sign(samples):
    """+1 when the AHRS's world z is up (its up agrees with the accelerometer), -1 when down."""
    t0 = samples[0][0]
    dots = [sum(x * y for x, y in zip(body_up(s[4]), normalized(s[2])))
            for s in samples if s[0] - t0 < 1.0 and any(s[4])]
    return 1.0 if sum(dots) >= 0 else -1.0


def tilt_errors(estimate, samples, sign, skip):
    t0 = samples[0][0]
    truth = {round(s[0], 6): [sign * x for x in body_up(s[4])] for s in samples}
    errors = []
    for t, q in estimate:
        ref = truth.get(round(t, 6))
        if ref is None or t - t0 < skip:
            continue
        errors.append(math.degrees(angle(body_up(q), ref)))
    return errors


def summary(name, errors):
    if not errors:
        return "| %s | – | – | 0 |" % name
    rms = math.sqrt(sum(e * e for e in errors) / len(errors))
    return "| %s | %.2f | %.2f | %d |" % (name, rms, max(errors), len(errors))


def main(argv):
    args = list(argv[1:])
    mag_topic, skip = None, 10.0
    if "--mag" in args:
        i = args.index("--mag")
        mag_topic = args[i + 1]
        del args[i:i + 2]
    if "--skip" in args:
        i = args.index("--skip")
        skip = float(args[i + 1])
        del args[i:i + 2]
    if len(args) < 3:
        sys.exit(__doc__)
    bag, imu_topic, estimates = args[0], args[1], args[2:]
    samples = read(bag, imu_topic, mag_topic)
    sign = ahrs_sign(samples)
    print("%s %s: %d samples, the AHRS's world z %s; after %.0f s:\n" %
          (bag, imu_topic, len(samples), "up" if sign > 0 else "down", skip))
    print("| estimate | tilt RMS to the AHRS (deg) | max (deg) | samples |")
    print("|---|---|---|---|")
    for path in estimates:
        print(summary(path, tilt_errors(read_estimate(path), samples, sign, skip)))
    for beta in (0.01, 0.03, 0.1, 0.3):
        for use_mag in ([False, True] if mag_topic else [False]):
            est = madgwick(samples, beta, use_mag)
            print(summary("madgwick gain %.2f%s" % (beta, " + mag" if use_mag else ""),
                          tilt_errors(est, samples, sign, skip)))


if __name__ == "__main__":
    main(sys.argv)
