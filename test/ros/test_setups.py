#!/usr/bin/python3
"""The launch examples of launch/examples on a robot's tf tree (setups_*.test): the tree stays
a tree (every frame has one parent, one root, no cycle, one node publishing each edge), it has
the edges the set-up promises, and the propagated attitude arrives where the set-up puts it. Private parameter ~setup:
standalone | robot | body_root."""
import math
import threading
import time
import unittest

import rospy
import rostest
from attitude_propagator.msg import AttitudeState
from sensor_msgs.msg import Imu
from std_srvs.srv import Empty
from tf2_msgs.msg import TFMessage

from ap_test_util import (Recorder, as_tuple, axis_angle, lookup, make_imu, make_tf_buffer,
                          qmul, rotation_angle, wait_connected, wait_for)

TOL = 1e-9  # the default integrator (cf4) is exact for a constant rate; only round-off remains
H = 0.01    # sample spacing (s)
N = 50      # samples after the anchor
W = 0.5     # rad/s about the IMU's x axis
NS_PER_S = 10 ** 9

# The .test files mount the IMU turned +90 degrees about base_link's z axis (yaw 1.5707963...),
# so the IMU's x axis is base_link's y axis; standalone stamps its rates in base_link itself.
YAW_90 = axis_angle((0, 0, 1), math.pi / 2)
IDENTITY = (0.0, 0.0, 0.0, 1.0)

# parent -> child edges of the whole tree; the frame the IMU stamps its rates in and its
# rotation into base_link; the tf that carries the attitude (None: attitude only on topics).
SETUPS = {
    "standalone": dict(edges={("world", "base_link")}, imu_frame="base_link", q_BI=IDENTITY,
                       fixed="world"),
    "robot": dict(edges={("odom", "base_link"), ("base_link", "imu_link")},
                  imu_frame="imu_link", q_BI=YAW_90, fixed=None),
    "body_root": dict(edges={("base_link", "imu_link"), ("base_link", "world")},
                      imu_frame="imu_link", q_BI=YAW_90, fixed="world"),
}


def stamp_at(base, seconds):
    return rospy.Time(0, int(round(base * NS_PER_S + seconds * NS_PER_S)))


def rotate(q, v):
    """v rotated by the unit quaternion q: q (v, 0) q^c."""
    p = qmul(qmul(q, (v[0], v[1], v[2], 0.0)), (-q[0], -q[1], -q[2], q[3]))
    return p[:3]


class TfEdges:
    """Every parent -> child pair seen on /tf and /tf_static since the test started, with the
    nodes that published it."""

    def __init__(self):
        self.lock = threading.Lock()
        self.parents = {}     # child -> set of parents
        self.publishers = {}  # (parent, child) -> set of node names
        self.subs = [rospy.Subscriber(topic, TFMessage, self._cb, queue_size=100000)
                     for topic in ("/tf", "/tf_static")]

    def _cb(self, msg):
        node = msg._connection_header["callerid"]
        with self.lock:
            for t in msg.transforms:
                parent, child = t.header.frame_id.lstrip("/"), t.child_frame_id.lstrip("/")
                self.parents.setdefault(child, set()).add(parent)
                self.publishers.setdefault((parent, child), set()).add(node)

    def edges(self):
        with self.lock:
            return {(p, c) for c, ps in self.parents.items() for p in ps}

    def parents_of(self):
        with self.lock:
            return {c: set(ps) for c, ps in self.parents.items()}

    def shared_edges(self):
        """Edges that more than one node publishes: two authorities for one frame's pose."""
        with self.lock:
            return {e: ns for e, ns in self.publishers.items() if len(ns) > 1}


class SetupTest(unittest.TestCase):

    @classmethod
    def setUpClass(cls):
        rospy.init_node("test_setups")
        cls.name = rospy.get_param("~setup")
        cls.setup = SETUPS[cls.name]
        cls.tf = TfEdges()
        cls.tf_buffer, cls.tf_listener = make_tf_buffer()
        cls.imu_pub = rospy.Publisher("imu/data_raw", Imu, queue_size=1000)
        cls.imu_out = Recorder("imu/data", Imu)
        cls.state = Recorder("attitude_state", AttitudeState)
        rospy.wait_for_service("attitude_propagator/reset", 20.0)
        cls.reset = rospy.ServiceProxy("attitude_propagator/reset", Empty)
        wait_connected(cls.imu_pub)
        wait_for(lambda: cls.imu_out.sub.get_num_connections() > 0, 20.0, "imu/data")
        wait_for(lambda: cls.state.sub.get_num_connections() > 0, 20.0, "attitude_state")
        cls.warm_up()

    @classmethod
    def warm_up(cls):
        """Rates in imu_link wait for the static mount (dropped until the node has it): feed
        zero rates until the node publishes, then reset it, so the test starts anchored."""
        for k in range(1000):
            if cls.imu_out.count() > 0:
                cls.reset()
                return
            cls.imu_pub.publish(make_imu(stamp_at(100, k * H), (0, 0, 0), cls.setup["imu_frame"]))
            time.sleep(0.02)
        raise AssertionError("the node never published imu/data")

    def assertRotation(self, actual, expected):
        self.assertLess(rotation_angle(actual, expected), TOL,
                        "got %s, expected %s" % (actual, expected))

    def test_attitude_where_the_setup_puts_it_and_the_tree_stays_a_tree(self):
        base = 1000
        for k in range(N + 1):
            self.imu_pub.publish(make_imu(stamp_at(base, k * H), (W, 0, 0),
                                          self.setup["imu_frame"]))
        end = stamp_at(base, N * H)

        # Closed form: a constant rate W about the IMU's x axis, i.e. about q_BI x in base_link,
        # from the identity at the anchor (the first sample).
        q_BI = self.setup["q_BI"]
        q_WB = axis_angle(rotate(q_BI, (1, 0, 0)), W * N * H)
        self.assertRotation(as_tuple(self.state.wait_at(end).orientation), q_WB)
        # imu/data: the IMU's own orientation (REP-145), q_WB q_BI.
        self.assertRotation(as_tuple(self.imu_out.wait_at(end).orientation), qmul(q_WB, q_BI))
        # The tree first (let any late transform arrive before judging it), then what tf2
        # makes of it.
        wait_for(lambda: self.setup["edges"] <= self.tf.edges(), 10.0,
                 "edges %s (seen %s)" % (self.setup["edges"], self.tf.edges()))
        time.sleep(0.5)
        self.assertEqual(self.tf.edges(), self.setup["edges"])
        self.assertIsTree(self.tf.parents_of())
        self.assertEqual(self.tf.shared_edges(), {}, "edges with more than one publisher")
        if self.setup["fixed"]:
            # tf2 composes the tree (inverting base_link -> world for body_root).
            self.assertRotation(lookup(self.tf_buffer, self.setup["fixed"], "base_link", end),
                                q_WB)
        else:
            # No attitude on tf: the robot's own chain odom -> base_link -> imu_link is intact.
            self.assertRotation(lookup(self.tf_buffer, "odom", "imu_link", rospy.Time(0)), q_BI)

    def assertIsTree(self, parents):
        many = {c: ps for c, ps in parents.items() if len(ps) != 1}
        self.assertEqual(many, {}, "frames with more than one parent")
        frames = set(parents) | {p for ps in parents.values() for p in ps}
        roots = frames - set(parents)
        self.assertEqual(len(roots), 1, "roots %s" % roots)
        for frame in frames:
            seen = set()
            while frame in parents:
                self.assertNotIn(frame, seen, "a cycle through " + frame)
                seen.add(frame)
                frame = next(iter(parents[frame]))
            self.assertIn(frame, roots)


if __name__ == "__main__":
    rostest.rosrun("attitude_propagator", "test_setups", SetupTest)
