#!/usr/bin/python3
"""Gravity through the public interface (gravity.test): a static IMU tilted by roll 0.3 rad and
pitch -0.2 rad publishes zero rates and the specific force f_B = C_BW (0, 0, g) on
imu/data_raw; the roll and pitch of the published orientation are the tilt's.

The truth is the closed form q_WB = Rz(0) Ry(pitch) Rx(roll) (REP-103's ZYX angles); with
world_frame ned, the same attitude in NED/FRD axes, q_NF = q_NE q_WB q_FB (conventions.md §2.2).
The heading is unknown without a magnetometer, and roll and pitch do not depend on it. Every
wait is on an output (a state at a stamp, a counter), never on a duration."""
import math
import unittest

import rospy
import rostest
from geometry_msgs.msg import Vector3
from sensor_msgs.msg import Imu, MagneticField

from ap_test_util import (Diagnostics, Node, as_tuple, axis_angle, make_imu, qconj, qmul,
                          wait_connected)

NS_PER_S = 10 ** 9
H = 0.01  # sample spacing (s)
G = 9.80665
ROLL, PITCH = 0.3, -0.2
DECLINATION = 0.1  # rad, magnetic north east of true north
# The earth's field in ENU: 20 uT horizontal towards magnetic north, 40 uT down.
FIELD_W = (2e-5 * math.sin(DECLINATION), 2e-5 * math.cos(DECLINATION), -4e-5)
# The magnetometer's own field (hard iron, body frame), added to every read and given to the
# node as mag_bias (gravity.test): uncorrected it would turn the heading by about 13 degrees.
OWN_FIELD_B = (3e-6, -5e-6, 2e-6)
# Within 1e-3 rad: the tilt is set from the first sample (exact data) and fused since; the
# rates are zero, so nothing but round-off moves it.
TOLERANCE = 1e-3


def rotate(q, v):
    """C(q) v for q = (x, y, z, w)."""
    return qmul(qmul(q, (v[0], v[1], v[2], 0.0)), qconj(q))[:3]


def yaw(q):
    x, y, z, w = q
    return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


def roll_pitch(q):
    x, y, z, w = q
    roll = math.atan2(2.0 * (w * x + y * z), 1.0 - 2.0 * (x * x + y * y))
    pitch = math.asin(max(-1.0, min(1.0, 2.0 * (w * y - z * x))))
    return roll, pitch


Q_WB = qmul(axis_angle((0, 1, 0), PITCH), axis_angle((1, 0, 0), ROLL))
# NED from ENU: a half turn about (east + north)/sqrt(2); FLU from FRD: a half turn about x.
Q_NE = axis_angle((1, 1, 0), math.pi)
Q_FB = axis_angle((1, 0, 0), math.pi)


def specific_force():
    """f_B = C_BW (0, 0, g): at rest the accelerometer reads g along the body's up."""
    return rotate(qconj(Q_WB), (0.0, 0.0, G))


class GravityTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("test_gravity")
        cls.diag = Diagnostics()
        cls.nodes = {ns: Node(ns) for ns in ("ga", "gn", "gm")}
        cls.mag = rospy.Publisher("/gm/imu/mag", MagneticField, queue_size=10000)
        cls.imu = {ns: rospy.Publisher("/%s/imu/data_raw" % ns, Imu, queue_size=10000)
                   for ns in cls.nodes}
        for node in cls.nodes.values():
            node.wait_ready()
        for pub in list(cls.imu.values()) + [cls.mag]:
            wait_connected(pub)

    def static_imu(self, ns, count=50):
        """count samples of a static tilted IMU; the state at the last stamp."""
        base = rospy.Time.now().to_sec()
        f = specific_force()
        stamp = None
        for i in range(count):
            stamp = rospy.Time(0, int(round((base + i * H) * NS_PER_S)))
            msg = make_imu(stamp, (0.0, 0.0, 0.0), "body_" + ns)
            msg.linear_acceleration = Vector3(*f)
            self.imu[ns].publish(msg)
            if ns == "gm":
                field = MagneticField()
                field.header.stamp = stamp
                field.header.frame_id = "body_" + ns
                earth = rotate(qconj(Q_WB), FIELD_W)
                field.magnetic_field = Vector3(*(e + b for e, b in zip(earth, OWN_FIELD_B)))
                self.mag.publish(field)
        return self.nodes[ns].state.wait_at(stamp, timeout=30.0)

    def check_tilt(self, q, expected):
        roll, pitch = roll_pitch(q)
        roll0, pitch0 = roll_pitch(expected)
        self.assertLess(abs(roll - roll0), TOLERANCE, "roll %.6f, expected %.6f" % (roll, roll0))
        self.assertLess(abs(pitch - pitch0), TOLERANCE,
                        "pitch %.6f, expected %.6f" % (pitch, pitch0))

    def test_static_tilt_in_enu(self):
        state = self.static_imu("ga")
        self.check_tilt(as_tuple(state.orientation), Q_WB)
        roll, pitch = roll_pitch(as_tuple(state.orientation))
        self.assertLess(abs(roll - ROLL), TOLERANCE)
        self.assertLess(abs(pitch - PITCH), TOLERANCE)
        node = self.nodes["ga"].name
        self.diag.wait_counter(node, "accel_aligned", 1, timeout=10.0)
        self.diag.wait_counter(node, "accel_accepted", 1, timeout=10.0)
        self.assertEqual(self.diag.counter(node, "accel_rejected_gate"), 0)

    def test_static_tilt_in_ned(self):
        state = self.static_imu("gn")
        self.check_tilt(as_tuple(state.orientation), qmul(qmul(Q_NE, Q_WB), Q_FB))
        self.diag.wait_counter(self.nodes["gn"].name, "accel_aligned", 1, timeout=10.0)

    def test_static_tilt_and_north(self):
        """With the field, the heading too: the body's x points east (yaw 0 in ENU) once
        declination turns magnetic north into true north and mag_bias has taken the
        magnetometer's own field off every read."""
        state = self.static_imu("gm")
        q = as_tuple(state.orientation)
        self.check_tilt(q, Q_WB)
        self.assertLess(abs(yaw(q)), TOLERANCE, "yaw %.6f, expected 0" % yaw(q))
        node = self.nodes["gm"].name
        self.diag.wait_counter(node, "mag_accepted", 1, timeout=10.0)
        # The live sphere fit counts the reads; one read repeated fixes no sphere.
        self.diag.wait_counter(node, "mag_bias_fit_reads", 50, timeout=10.0)
        self.assertEqual(self.diag.get(node, "mag_bias_fit"), "none")
        self.assertEqual(self.diag.get(node, "mag_bias_fit_determined"), "False")
        self.assertIsNone(self.diag.get(self.nodes["ga"].name, "mag_bias_fit_reads"))


if __name__ == "__main__":
    rostest.rosrun("attitude_propagator", "gravity", GravityTest)
