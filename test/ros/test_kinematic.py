#!/usr/bin/python3
"""Kinematic model through the public interface (kinematic.test)."""
import collections
import math
import threading
import time
import unittest

import rospy
import rostest
import tf2_ros
from geometry_msgs.msg import Quaternion, TransformStamped, Twist, TwistStamped, Vector3
from sensor_msgs.msg import Imu
from std_msgs.msg import Float64
from tf2_msgs.msg import TFMessage

from ap_test_util import (Diagnostics, Node, Recorder, axis_angle, as_tuple, lookup,
                          make_imu, make_tf_buffer, qconj, qmul, rotation_angle, wait_connected,
                          wait_for)

TOL = 1e-9  # exp and cf4 are exact for constant rates; only round-off remains
H = 0.01    # sample spacing (s)
NS_PER_S = 10 ** 9


def stamp_at(base, seconds):
    return rospy.Time(0, int(round(base * NS_PER_S + seconds * NS_PER_S)))


class TfStamps:
    """Counts /tf transforms per (child frame, stamp)."""

    def __init__(self):
        self.lock = threading.Lock()
        self.counts = collections.Counter()
        self.sub = rospy.Subscriber("/tf", TFMessage, self._cb, queue_size=100000)

    def _cb(self, msg):
        with self.lock:
            for t in msg.transforms:
                self.counts[(t.child_frame_id, t.header.stamp.to_nsec())] += 1

    def repeated(self):
        with self.lock:
            return [k for k, n in self.counts.items() if n > 1]


def publish_static_mount():
    """The IMU of the mount node, turned +90 degrees about the body's z axis."""
    broadcaster = tf2_ros.StaticTransformBroadcaster()
    t = TransformStamped()
    t.header.stamp = rospy.Time.now()
    t.header.frame_id = "body_m"
    t.child_frame_id = "imu_m"
    t.transform.rotation = Quaternion(*axis_angle((0, 0, 1), math.pi / 2))
    broadcaster.sendTransform(t)
    return broadcaster


class KinematicTest(unittest.TestCase):
    next_base = 1000

    @classmethod
    def setUpClass(cls):
        rospy.init_node("test_kinematic")
        cls.tf_buffer, cls.tf_listener = make_tf_buffer()
        cls.diag = Diagnostics()
        cls.tf_stamps = TfStamps()
        cls.nodes = {ns: Node(ns) for ns in ("kin", "rev", "mount", "nl", "tws", "twu", "twx")}
        cls.imu_pubs = {ns: rospy.Publisher("/%s/imu/data_raw" % ns, Imu, queue_size=100000)
                        for ns in ("kin", "rev", "mount", "nl")}
        cls.twist_stamped_pub = rospy.Publisher("/tws/body_twist", TwistStamped,
                                                queue_size=100000)
        cls.twist_pub = rospy.Publisher("/twu/body_twist", Twist, queue_size=100000)
        cls.wrong_type_pub = rospy.Publisher("/twx/body_twist", Float64, queue_size=10)
        cls.imu_out = Recorder("/kin/imu/data", Imu)
        for node in cls.nodes.values():
            node.wait_ready()
        for pub in list(cls.imu_pubs.values()) + [cls.twist_stamped_pub, cls.twist_pub,
                                                  cls.wrong_type_pub]:
            wait_connected(pub)
        wait_for(lambda: cls.imu_out.sub.get_num_connections() > 0, 20.0, "imu/data")
        cls.static_tf = publish_static_mount()
        cls.warm_up_mount()

    @classmethod
    def warm_up_mount(cls):
        """The mount node looks its static transform up at the first message; feed it until it
        publishes, so the tests see a node with the mount cached."""
        base = cls.take_base()
        for k in range(1000):
            if cls.nodes["mount"].state.count() > 0:
                return
            cls.imu_pubs["mount"].publish(make_imu(stamp_at(base, k * H), (0, 0, 0), "imu_m"))
            time.sleep(0.02)
        raise AssertionError("mount node never published")

    @classmethod
    def take_base(cls):
        base = cls.next_base
        cls.next_base += 100
        return base

    def setUp(self):
        for node in self.nodes.values():
            node.reset()
        self.base = self.take_base()

    def tearDown(self):
        self.assertEqual(self.tf_stamps.repeated(), [], "a transform was published twice")
        for node in self.nodes.values():
            stamps = collections.Counter(m.header.stamp.to_nsec() for m in node.state.messages)
            self.assertEqual([s for s, n in stamps.items() if n > 1], [],
                             node.name + " published twice for one stamp")

    def feed(self, ns, samples, frame_id=""):
        """samples: (seconds after base, rate, covariance or None)."""
        for seconds, w, cov in samples:
            self.imu_pubs[ns].publish(make_imu(stamp_at(self.base, seconds), w, frame_id, cov))

    def kin_state(self, seconds):
        return self.nodes["kin"].state.wait_at(stamp_at(self.base, seconds))

    def assertRotation(self, actual, expected, tol=TOL):
        self.assertLess(rotation_angle(actual, expected), tol,
                        "got %s, expected %s" % (actual, expected))

    # -- inputs and tf ------------------------------------------------------------------------

    def test_constant_rate_every_input_and_node(self):
        n = 100
        w = 0.5
        samples = [(k * H, (0, 0, w), None) for k in range(n + 1)]
        self.feed("kin", samples, "base_link")
        self.feed("rev", samples)
        self.feed("nl", samples)
        # The mount's IMU x axis is the body's y axis: w about IMU x turns the body about y.
        self.feed("mount", [(t, (w, 0, 0), None) for t, _, _ in samples], "imu_m")
        for t, rate, _ in samples:
            msg = TwistStamped()
            msg.header.stamp = stamp_at(self.base, t)
            msg.twist.angular = Vector3(*rate)
            self.twist_stamped_pub.publish(msg)

        end = stamp_at(self.base, n * H)
        expected = axis_angle((0, 0, 1), w * n * H)
        self.assertRotation(lookup(self.tf_buffer, "world", "base_link", end), expected)
        self.assertRotation(lookup(self.tf_buffer, "world_n", "body_n", end), expected)
        self.assertRotation(lookup(self.tf_buffer, "world_s", "body_s", end), expected)
        self.assertRotation(lookup(self.tf_buffer, "body_r", "world_r", end), qconj(expected))
        self.assertRotation(lookup(self.tf_buffer, "world_m", "body_m", end),
                            axis_angle((0, 1, 0), w * n * H))

        state = self.kin_state(n * H)
        self.assertEqual(state.header.frame_id, "world")
        self.assertEqual(state.child_frame_id, "base_link")
        self.assertEqual(state.model, "kinematic")
        self.assertEqual(state.integrator, "exp")
        self.assertAlmostEqual(state.angular_velocity.z, w)
        self.assertRotation(as_tuple(state.orientation), expected)

        # imu/data: the input with the orientation and its covariance. Rate noise along the
        # rotation axis accumulates exactly: P_zz = n h^2 sigma^2 (sigma = 0.01 rad/s).
        imu = self.imu_out.wait_at(end)
        self.assertRotation(as_tuple(imu.orientation), expected)
        self.assertAlmostEqual(imu.orientation_covariance[8], n * H * H * 1e-4, delta=1e-15)
        self.assertAlmostEqual(imu.orientation_covariance[0], n * H * H * 1e-4, delta=1e-8)

    def test_a_burst_is_not_dropped(self):
        # 3000 samples published as fast as rospy can: every one is integrated and published.
        n = 3000
        node = self.nodes["kin"]
        before = node.state.count()
        self.feed("kin", [(k * 1e-3, (0.0, 0.0, 0.3), None) for k in range(n + 1)])
        state = node.state.wait_at(stamp_at(self.base, n * 1e-3), timeout=30.0)
        self.assertRotation(as_tuple(state.orientation), axis_angle((0, 0, 1), 0.3 * n * 1e-3))
        wait_for(lambda: node.state.count() - before >= n + 1, 10.0, "every burst state")
        self.assertEqual(node.state.count() - before, n + 1)

    def test_octahedron_quarter_turns(self):
        # A quarter turn about body x, then one about body y: q = qx(pi/2) (x) qy(pi/2),
        # the 120 degree turn about (1, 1, 1) that maps x to y: (0.5, 0.5, 0.5, 0.5).
        q = math.pi / 2
        samples = [(k * H, (q, 0, 0) if k < 100 else (0, q, 0), None) for k in range(200)]
        samples.append((200 * H, (0, 0, 0), None))
        self.feed("kin", samples)
        actual = lookup(self.tf_buffer, "world", "base_link", stamp_at(self.base, 2.0))
        self.assertRotation(actual, (0.5, 0.5, 0.5, 0.5))
        self.assertRotation(lookup(self.tf_buffer, "world", "base_link",
                                   stamp_at(self.base, 1.0)), axis_angle((1, 0, 0), q))

    def test_unstamped_twist_gets_receipt_time(self):
        w = 0.8
        for _ in range(30):
            self.twist_pub.publish(Twist(angular=Vector3(0, 0, w)))
            time.sleep(0.02)
        states = wait_for(lambda: len(self.fresh_twu_states()) >= 30 and self.fresh_twu_states(),
                          10.0, "30 twist states")
        first, last = states[0], states[-1]
        self.assertLess(abs((first.header.stamp - rospy.Time.now()).to_sec()), 5.0)
        self.assertRotation(as_tuple(first.orientation), (0, 0, 0, 1))
        dt = (last.header.stamp - first.header.stamp).to_sec()
        self.assertGreater(dt, 0.3)
        self.assertRotation(as_tuple(last.orientation), axis_angle((0, 0, 1), w * dt), 1e-6)

    def fresh_twu_states(self):
        # States since this test's reset: the twist node's anchor has the identity.
        msgs = list(self.nodes["twu"].state.messages)
        start = max((i for i, m in enumerate(msgs)
                     if rotation_angle(as_tuple(m.orientation), (0, 0, 0, 1)) == 0.0),
                    default=None)
        return [] if start is None else msgs[start:]

    def test_covariance_from_the_message(self):
        # At rest J_r = I and Phi = I: P = n h^2 R exactly, R the message's covariance.
        cov = [4e-4, 0, 0, 0, 9e-4, 0, 0, 0, 1e-4]
        self.feed("kin", [(k * H, (0, 0, 0), cov) for k in range(51)])
        imu = self.imu_out.wait_at(stamp_at(self.base, 50 * H))
        for i in (0, 4, 8):
            self.assertAlmostEqual(imu.orientation_covariance[i], 50 * H * H * cov[i],
                                   delta=1e-15)
        self.assertEqual(imu.orientation_covariance[1], 0.0)

    def test_wrong_message_type_is_rejected(self):
        pub = self.wrong_type_pub
        before = self.diag.counter("/twx/attitude_propagator", "rejected_type") or 0
        pub.publish(Float64(1.0))
        self.diag.wait_counter("/twx/attitude_propagator", "rejected_type", before + 1)
        self.assertEqual(self.nodes["twx"].state.count(), 0)

    # -- docs/design.md §6–§7 ----------------------------------------------------------------------------

    def test_rep145_no_rate_is_rejected(self):
        before = self.diag.counter("/kin/attitude_propagator", "rejected_no_rate") or 0
        no_rate = [-1.0] + [0.0] * 8
        self.feed("kin", [(0.0, (0, 0, 1), None), (H, (0, 0, 1), no_rate),
                          (2 * H, (0, 0, 1), None)])
        self.assertRotation(as_tuple(self.kin_state(2 * H).orientation),
                            axis_angle((0, 0, 1), 2 * H))
        self.assertEqual(self.nodes["kin"].state.at(stamp_at(self.base, H)), [])
        self.diag.wait_counter("/kin/attitude_propagator", "rejected_no_rate", before + 1)

    def test_nan_and_inf_are_rejected(self):
        before = self.diag.counter("/kin/attitude_propagator", "rejected_non_finite") or 0
        self.feed("kin", [(0.0, (0, 0, 1), None), (H, (float("nan"), 0, 1), None),
                          (2 * H, (0, float("inf"), 1), None),
                          (3 * H, (0, 0, 1), [float("nan")] + [0.0] * 8),
                          (4 * H, (0, 0, 1), None)])
        state = self.kin_state(4 * H)
        self.assertRotation(as_tuple(state.orientation), axis_angle((0, 0, 1), 4 * H))
        for k in (1, 2, 3):
            self.assertEqual(self.nodes["kin"].state.at(stamp_at(self.base, k * H)), [])
        self.diag.wait_counter("/kin/attitude_propagator", "rejected_non_finite", before + 3)

    def test_stale_and_duplicate_stamps_are_dropped(self):
        before = self.diag.counter("/kin/attitude_propagator", "dropped_stale") or 0
        self.feed("kin", [(0.0, (0, 0, 1), None), (2 * H, (0, 0, 1), None),
                          (2 * H, (0, 0, 5), None),   # duplicate
                          (H, (0, 0, 5), None),       # older
                          (3 * H, (0, 0, 1), None)])
        self.assertRotation(as_tuple(self.kin_state(3 * H).orientation),
                            axis_angle((0, 0, 1), 3 * H))
        self.assertEqual(len(self.nodes["kin"].state.at(stamp_at(self.base, 2 * H))), 1)
        self.assertEqual(self.nodes["kin"].state.at(stamp_at(self.base, H)), [])
        self.diag.wait_counter("/kin/attitude_propagator", "dropped_stale", before + 2)

    def test_gap_longer_than_max_dt_holds_the_state(self):
        before = self.diag.counter("/kin/attitude_propagator", "gaps") or 0
        self.feed("kin", [(0.0, (0, 0, 1), None), (H, (0, 0, 1), None),
                          (H + 2.0, (0, 0, 1), None), (2 * H + 2.0, (0, 0, 1), None)])
        self.assertRotation(as_tuple(self.kin_state(H + 2.0).orientation),
                            axis_angle((0, 0, 1), H))
        self.assertRotation(as_tuple(self.kin_state(2 * H + 2.0).orientation),
                            axis_angle((0, 0, 1), 2 * H))
        self.diag.wait_counter("/kin/attitude_propagator", "gaps", before + 1)

    def test_backward_jump_in_stamps_resets(self):
        before = self.diag.counter("/kin/attitude_propagator", "resets") or 0
        self.feed("kin", [(k * H, (0, 0, 1), None) for k in range(51)])
        self.assertRotation(as_tuple(self.kin_state(50 * H).orientation),
                            axis_angle((0, 0, 1), 0.5))
        # A looped bag: 50 s back. The jump is recognised at the third stamp in a row from the
        # earlier time (the first two held until then); the state starts again from the
        # initial one at the first of them and all of them are integrated, as a fresh start.
        self.feed("kin", [(-50.0 + k * H, (0, 0, 1), None) for k in range(4)])
        self.assertRotation(as_tuple(self.kin_state(-50.0).orientation), (0, 0, 0, 1))
        self.assertRotation(as_tuple(self.kin_state(-50.0 + 2 * H).orientation),
                            axis_angle((0, 0, 1), 2 * H))
        self.assertRotation(as_tuple(self.kin_state(-50.0 + 3 * H).orientation),
                            axis_angle((0, 0, 1), 3 * H))
        # reset calls count too: this test's setUp reset it once, the jump once more.
        self.diag.wait_counter("/kin/attitude_propagator", "resets", before + 1)

    def test_set_state_pins_the_state(self):
        node = self.nodes["kin"]
        q0 = axis_angle((1, 0, 0), 0.3)
        response = node.set_state(stamp_at(self.base, 0.0), q0, (0, 0, 0))
        self.assertTrue(response.success, response.message)
        self.assertRotation(as_tuple(self.kin_state(0.0).orientation), q0)
        self.feed("kin", [(H, (0, 0, 1), None), (2 * H, (0, 0, 1), None)])
        # exp holds the rate of the sample opening the interval: zero (the set state's) on
        # [0, h], then 1 rad/s on [h, 2h].
        expected = axis_angle((1, 0, 0), 0.3)
        expected = qmul(expected, axis_angle((0, 0, 1), H))
        self.assertRotation(as_tuple(self.kin_state(2 * H).orientation), expected)
        # A zero quaternion is refused, and the state stays finite.
        bad = node.set_state(stamp_at(self.base, 3 * H), (0, 0, 0, 0), (0, 0, 0))
        self.assertFalse(bad.success)
        self.assertIn("quaternion", bad.message)


if __name__ == "__main__":
    rostest.rosrun("attitude_propagator", "kinematic", KinematicTest)
