#!/usr/bin/python3
"""Hostile input through the public interface (attack.test, wall time). One test per kind of
input; each ends by showing the node alive (~reset answers, states keep coming) and its output
finite (unit quaternion, finite rate, energy and covariance), and the counter of the input's
outcome incremented. Refused parameters are checked in test_param_limits.py."""
import math
import subprocess
import threading
import time
import unittest

import rospy
import rostest
from geometry_msgs.msg import TwistStamped, Vector3
from rosgraph_msgs.msg import Log
from sensor_msgs.msg import Imu
from std_srvs.srv import Empty

from ap_test_util import (Diagnostics, Node, Recorder, RosoutLines, Stamps, as_tuple,
                          axis_angle, call_with_timeout, check_each, check_finite_state, make_imu,
                          qmul, rotation_angle, wait_connected, wait_for)

TOL = 1e-9  # cf4 is exact for a constant rate; only round-off remains
SQRT_HALF = math.sqrt(0.5)
# initial_orientation [1e300, 1e300, 0, 0] of the kin node, normalised.
KIN_Q0 = (SQRT_HALF, SQRT_HALF, 0.0, 0.0)
IDENTITY = (0.0, 0.0, 0.0, 1.0)
YEAR_2100_S = 4102444800  # 2100-01-01T00:00:00Z
PI2 = math.pi ** 2        # the ceiling of an orientation variance (rad^2)


def exp_rotation(w, t):
    """Exp(t w) as a quaternion: the rotation of a constant body rate w over t seconds."""
    n = math.sqrt(sum(c * c for c in w))
    return IDENTITY if n == 0.0 else axis_angle(w, n * t)


class AttackTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("test_attack")
        cls.diag = Diagnostics()
        cls.rosout = RosoutLines()
        cls.nodes = {ns: Node(ns) for ns in ("ex", "dp", "rk", "kin", "far", "rst", "tw")}
        cls.imu_pubs = {ns: rospy.Publisher("/%s/imu/data_raw" % ns, Imu, queue_size=100000)
                        for ns in ("ex", "dp", "kin", "far", "rst")}
        cls.twist_pub = rospy.Publisher("/tw/body_twist", TwistStamped, queue_size=1000)
        cls.kin_imu_out = Recorder("/kin/imu/data", Imu)
        for node in cls.nodes.values():
            node.wait_ready()
        for pub in list(cls.imu_pubs.values()) + [cls.twist_pub]:
            wait_connected(pub)
        wait_for(lambda: cls.kin_imu_out.sub.get_num_connections() > 0, 20.0, "/kin/imu/data")
        cls.stamps = {ns: Stamps(1000) for ns in ("kin", "far", "rst", "tw")}

    # ---- helpers ---------------------------------------------------------------------------

    def counter(self, ns, key):
        return self.diag.counter("/%s/attitude_propagator" % ns, key) or 0

    def wait_counter(self, ns, key, at_least, timeout=10.0):
        self.diag.wait_counter("/%s/attitude_propagator" % ns, key, at_least, timeout)

    def reset(self, ns):
        call_with_timeout(self.nodes[ns].reset, 5.0, "/%s ~reset" % ns)

    def set_state(self, ns, stamp, q, w=(0.0, 0.0, 0.0)):
        return call_with_timeout(lambda: self.nodes[ns].set_state(stamp, q, w), 5.0,
                                 "/%s ~set_state" % ns)

    def wall_stamp(self, ahead_s=0.0):
        return rospy.Time.now() + rospy.Duration(ahead_s)

    def new_states(self, ns, n=3, timeout=10.0):
        """The next n states the node publishes stamped after the present (ROS time), so
        published after everything the test did so far."""
        rec = self.nodes[ns].state
        start, now = rec.count(), rospy.Time.now()

        def later():
            with rec.lock:
                msgs = [m for m in rec.messages[start:] if m.header.stamp > now]
            return msgs[:n] if len(msgs) >= n else None
        return wait_for(later, timeout, "%d new states on /%s" % (n, ns))

    def assertRotation(self, actual, expected, tol):
        self.assertLess(rotation_angle(actual, expected), tol,
                        "got %s, expected %s" % (actual, expected))

    def send_rate(self, ns, stamp, w, covariance=None):
        if ns == "tw":
            msg = TwistStamped()
            msg.header.stamp = stamp
            msg.header.frame_id = "body_tw"
            msg.twist.angular = Vector3(*w)
            self.twist_pub.publish(msg)
        else:
            self.imu_pubs[ns].publish(make_imu(stamp, w, "body_" + ns, covariance))

    def assert_dynamic_alive(self, ns):
        """~reset answers, and the states after it are finite and keep coming."""
        self.reset(ns)
        for msg in self.new_states(ns, 3):
            check_finite_state(self, msg)

    def assert_kinematic_alive(self, ns, q0=IDENTITY):
        """~reset answers; the next input anchors at the initial orientation, the one after it
        turns from there exactly."""
        self.reset(ns)
        stamps = self.stamps[ns]
        a, b = stamps.next(), stamps.next()
        w = (0.0, 0.0, 1.0)
        self.send_rate(ns, a, w)
        self.send_rate(ns, b, w)
        rec = self.nodes[ns].state
        for stamp, expected in ((a, q0), (b, qmul(q0, exp_rotation(w, 0.1)))):
            msg = rec.wait_at(stamp)
            check_finite_state(self, msg)
            self.assertRotation(as_tuple(msg.orientation), expected, TOL)

    # ---- one test per row --------------------------------------------------------------------

    def test_row01_huge_imu_rate_on_the_exact_model_is_rejected(self):
        self.reset("ex")
        before = self.counter("ex", "rejected_out_of_range")
        self.send_rate("ex", self.wall_stamp(), (1e200, 1e200, 1e200))
        self.wait_counter("ex", "rejected_out_of_range", before + 1)
        for msg in self.new_states("ex", 3):
            check_finite_state(self, msg)
            self.assertEqual(msg.kinetic_energy, 0.0)  # still at rest
            self.assertEqual(msg.model, "exact_triaxial")
        self.assert_dynamic_alive("ex")

    def test_row01b_largest_accepted_rate_keeps_energy(self):
        # |w| = 8.7e4 rad/s, below the door's 1e5: accepted, and torque-free the exact model
        # keeps E = (1 + 2 + 3) (5e4)^2 / 2 (energy is conserved; each evaluation is exact).
        self.reset("ex")
        before = self.counter("ex", "accepted")
        self.send_rate("ex", self.wall_stamp(0.1), (5e4, 5e4, 5e4))
        self.wait_counter("ex", "accepted", before + 1)
        energy = 0.5 * (1.0 + 2.0 + 3.0) * 5e4 ** 2
        for msg in self.new_states("ex", 5):
            check_finite_state(self, msg)
            self.assertAlmostEqual(msg.kinetic_energy / energy, 1.0, delta=1e-9)
        self.assert_dynamic_alive("ex")

    def test_row02_set_state_with_a_huge_rate_is_refused(self):
        self.reset("ex")
        response = self.set_state("ex", rospy.Time(0), IDENTITY, (1e200, 1e200, 1e200))
        self.assertFalse(response.success, response.message)
        self.assertIn("angular velocity", response.message)
        for msg in self.new_states("ex", 3):
            check_finite_state(self, msg)
            self.assertEqual(msg.kinetic_energy, 0.0)
            self.assertRotation(as_tuple(msg.orientation), IDENTITY, 1e-15)
        self.assert_dynamic_alive("ex")

    def test_row04_dopri5_with_rates_beyond_the_door(self):
        self.reset("dp")
        before = self.counter("dp", "rejected_out_of_range")
        for k in range(3):
            self.send_rate("dp", self.wall_stamp(0.01 * k), (1e12, 0.0, 1.0))
        self.wait_counter("dp", "rejected_out_of_range", before + 3)
        for msg in self.new_states("dp", 3):
            check_finite_state(self, msg)
            self.assertEqual(msg.model, "numerical_dopri5")
        self.assertEqual(self.counter("dp", "callback_errors"), 0)
        self.assert_dynamic_alive("dp")

    def test_row05_a_stamp_in_the_year_2100(self):
        ns, stamps, rec = "far", self.stamps["far"], self.nodes["far"].state
        self.reset(ns)
        w = (0.3, -0.2, 0.5)
        a, b = stamps.next(), stamps.next()
        self.send_rate(ns, a, w)
        self.send_rate(ns, b, w)
        q_b = exp_rotation(w, 0.1)
        self.assertRotation(as_tuple(rec.wait_at(b).orientation), q_b, TOL)
        future = self.counter(ns, "rejected_future")
        # Far ahead of ROS time (more than max_future, 1 s): refused, never published, also at
        # the last second ROS time holds.
        for far in (rospy.Time(YEAR_2100_S, 123), rospy.Time(2 ** 32 - 1, 999999999)):
            self.send_rate(ns, far, w)
        self.wait_counter(ns, "rejected_future", future + 2)
        # (Diagnostics newer than the reset above: the counts to compare with.)
        gaps, resets = self.counter(ns, "gaps"), self.counter(ns, "resets")
        # The normal stamps go on as if those had never come: no gap, no reset, no state lost.
        for k in range(1, 6):
            stamp = stamps.next()
            self.send_rate(ns, stamp, w)
            msg = rec.wait_at(stamp)
            check_finite_state(self, msg)
            self.assertRotation(as_tuple(msg.orientation), exp_rotation(w, 0.1 + 0.1 * k), TOL)
        with rec.lock:
            ahead = [s for s in rec.by_stamp if s >= (YEAR_2100_S - 1) * 10 ** 9]
        self.assertEqual(ahead, [], "states published at the refused stamps")
        self.assertEqual(self.counter(ns, "gaps"), gaps)
        self.assertEqual(self.counter(ns, "resets"), resets)
        self.assert_kinematic_alive(ns)

    def test_row05b_dynamic_model_input_stamped_in_the_year_2100(self):
        # Stamped ahead of ROS time, it waits for the clock; meanwhile the grid goes on. (Sent
        # once the propagator is anchored again after the reset; an input far ahead arriving
        # before that is grid.test's test_3.)
        self.reset("ex")
        self.new_states("ex", 2)
        future = self.counter("ex", "rejected_future")
        self.send_rate("ex", rospy.Time(YEAR_2100_S), (0.0, 0.0, 1.0))
        self.wait_counter("ex", "rejected_future", future + 1)
        now = rospy.Time.now()
        for msg in self.new_states("ex", 3):
            check_finite_state(self, msg)
            self.assertGreater(msg.header.stamp, now - rospy.Duration(1.0))
            self.assertEqual(msg.kinetic_energy, 0.0)
        self.assert_dynamic_alive("ex")

    def test_row05c_a_flood_of_future_stamps_does_not_stop_the_dynamic_node(self):
        # More inputs stamped in the future than the node queues (4096): whatever it does with
        # the overflow, it keeps publishing the state at ROS time.
        self.reset("dp")
        received = self.counter("dp", "received")
        for k in range(5000):
            self.send_rate("dp", rospy.Time(YEAR_2100_S + k), (0.0, 0.0, 1.0))
        self.wait_counter("dp", "received", received + 5000, timeout=30.0)
        now = rospy.Time.now()
        msgs = self.new_states("dp", 3)
        for msg in msgs:
            check_finite_state(self, msg)
            self.assertLess(abs((msg.header.stamp - now).to_sec()), 5.0,
                            "state stamped %.3f, ROS time %.3f"
                            % (msg.header.stamp.to_sec(), now.to_sec()))
        self.assert_dynamic_alive("dp")

    def test_row09_rk4_at_the_largest_initial_rate_stays_finite(self):
        # 870 rad per rk4 step: the steps may fail (then the state is held, counted and
        # warned), but no state is ever non-finite.
        msgs = self.new_states("rk", 20)
        for msg in msgs:
            check_finite_state(self, msg)
            self.assertEqual(msg.model, "numerical_rk4")
        failed = self.counter("rk", "failed_steps")
        if failed > 0:
            wait_for(lambda: self.rosout.of("/rk/attitude_propagator", Log.WARN, "step"), 10.0,
                     "a warning about failed steps")
        self.assert_dynamic_alive("rk")

    def test_row10_reset_flood_logs_a_few_lines(self):
        ns, stamps = "rst", self.stamps["rst"]
        resets = self.counter(ns, "resets")
        stop = threading.Event()

        def stream():
            while not stop.is_set():
                self.send_rate(ns, stamps.next(), (0.0, 0.0, 0.5))
                time.sleep(0.002)
        streamer = threading.Thread(target=stream, daemon=True)
        streamer.start()
        try:
            proxy = rospy.ServiceProxy("/rst/attitude_propagator/reset", Empty, persistent=True)
            for _ in range(1000):
                proxy()
            proxy.close()
        finally:
            stop.set()
            streamer.join()
        self.wait_counter(ns, "resets", resets + 1000)
        time.sleep(1.0)  # rosout delivery
        lines = self.rosout.of("/rst/attitude_propagator", Log.INFO, "reset")
        self.assertGreaterEqual(len(lines), 1)
        self.assertLessEqual(len(lines), 5, lines[:10])
        self.assert_kinematic_alive(ns)

    def test_row11_rate_covariance_negative_or_huge_is_rejected(self):
        ns, stamps, rec = "kin", self.stamps["kin"], self.nodes["kin"].state
        self.reset(ns)
        w = (0.0, 0.4, 0.0)
        a = stamps.next()
        self.send_rate(ns, a, w)
        rec.wait_at(a)
        before = self.counter(ns, "rejected_covariance")
        bad = [[-0.5, 0, 0, 0, -0.5, 0, 0, 0, -0.5], [1e308, 0, 0, 0, 1e308, 0, 0, 0, 1e308]]
        for covariance in bad:
            self.send_rate(ns, stamps.next(), w, covariance)
        self.wait_counter(ns, "rejected_covariance", before + 2)
        # Nothing of them was used: the next sample continues from a, 0.3 s later.
        b = stamps.next()
        self.send_rate(ns, b, w)
        msg = rec.wait_at(b)
        self.assertRotation(as_tuple(msg.orientation), qmul(KIN_Q0, exp_rotation(w, 0.3)), TOL)
        # none given (attack.test: no default noise, a known start)
        self.assertTrue(all(c == 0.0 for c in msg.orientation_covariance))
        self.assert_kinematic_alive(ns, KIN_Q0)

    def test_row11b_orientation_covariance_growth_is_clamped(self):
        # The largest accepted rate variance (1e6 rad^2/s^2; 9e5 here), 0.5 s steps: h^2 R is
        # far above pi^2, where the orientation variance saturates (nothing known).
        ns, stamps, rec = "kin", self.stamps["kin"], self.nodes["kin"].state
        self.reset(ns)
        covariance = [9e5, 0, 0, 0, 9e5, 0, 0, 0, 9e5]
        sent = [stamps.next(5) for _ in range(6)]
        for stamp in sent:
            self.send_rate(ns, stamp, (0.1, 0.0, 0.0), covariance)
        for stamp in sent[1:]:
            for msg in (rec.wait_at(stamp), self.kin_imu_out.wait_at(stamp)):
                cov = msg.orientation_covariance
                self.assertTrue(all(math.isfinite(c) for c in cov), cov)
                for i in (0, 4, 8):
                    self.assertLessEqual(cov[i], PI2)
                    self.assertGreater(cov[i], 0.5 * PI2)
            check_finite_state(self, rec.wait_at(stamp))
        self.assert_kinematic_alive(ns, KIN_Q0)

    def test_row12_a_second_message_type_on_body_twist(self):
        # ROS 1 gives a topic connection one type: the node subscribes to any type, and its
        # first publisher's type becomes the subscription's (checked by md5 sum). A publisher of
        # another type that comes later is refused by the ROS transport itself, on its side
        # ("topic types do not match"), so its messages never reach the node and there is
        # nothing for it to count; one that does reach it (a first publisher of a wrong type)
        # is counted in rejected_type (kinematic.test). Here: the refusal is visible, and the
        # node's stream goes on untouched.
        ns, stamps, rec = "tw", self.stamps["tw"], self.nodes["tw"].state
        self.reset(ns)
        w = (0.0, 0.0, 0.5)
        a = stamps.next()
        self.send_rate(ns, a, w)  # TwistStamped first: the topic's type
        rec.wait_at(a)
        other = subprocess.Popen(["rostopic", "pub", "-r", "20", "/tw/body_twist",
                                  "geometry_msgs/Twist", "{angular: {x: 5.0}}"],
                                 stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        refusal = []

        def read_stderr():
            for line in other.stderr:
                refusal.append(line)
        reader = threading.Thread(target=read_stderr, daemon=True)
        reader.start()
        try:
            wait_for(lambda: any("topic types do not match" in line for line in refusal), 30.0,
                     "the Twist publisher to report the refused connection")
        finally:
            other.terminate()
            other.wait(timeout=10)
        # Whatever arrived was counted; nothing of it changed the state.
        b = stamps.next()
        self.send_rate(ns, b, w)
        msg = rec.wait_at(b)
        self.assertRotation(as_tuple(msg.orientation), exp_rotation(w, 0.1), TOL)
        time.sleep(0.5)  # a diagnostics period
        with self.diag.lock:
            values = [v for name, v in self.diag.values.items()
                      if name.startswith("tw/attitude_propagator:")][0]
            c = {k: int(v) for k, v in values.items() if v.isdigit()}
        self.assertEqual(c["received"] - c["accepted"] - c["dropped_stale"],
                         c["rejected_type"] + c["rejected_non_finite"],
                         "every message that reached the node is accounted for: %s" % c)
        self.assert_kinematic_alive(ns)

    def test_row13_set_state_quaternions_at_extreme_scales(self):
        cases = [((1e200, 0.0, 0.0, 1e200), (SQRT_HALF, 0.0, 0.0, SQRT_HALF)),
                 ((1e308, 1e308, 1e308, 1e308), (0.5, 0.5, 0.5, 0.5)),
                 ((-1e308, 0.0, 1e-300, 0.0), (-1.0, 0.0, 0.0, 0.0))]

        def dynamic(case):
            given, unit = case
            self.reset("ex")
            response = self.set_state("ex", rospy.Time(0), given)
            self.assertTrue(response.success, response.message)
            for msg in self.new_states("ex", 3):
                check_finite_state(self, msg)
                self.assertRotation(as_tuple(msg.orientation), unit, 1e-15)

        def kinematic(case):
            given, unit = case
            stamp = self.stamps["kin"].next()
            response = self.set_state("kin", stamp, given)
            self.assertTrue(response.success, response.message)
            msg = self.nodes["kin"].state.wait_at(stamp)
            check_finite_state(self, msg)
            self.assertRotation(as_tuple(msg.orientation), unit, 1e-15)
        check_each(self, cases, dynamic)
        check_each(self, cases, kinematic)
        self.assert_dynamic_alive("ex")
        self.assert_kinematic_alive("kin", KIN_Q0)

    def test_row14_tiny_and_huge_quaternions_are_not_zero(self):
        # initial_orientation [1e300, 1e300, 0, 0] was accepted (the node runs) and means
        # (x, y) = (1, 1)/sqrt(2); assert_kinematic_alive checks the anchor against it.
        self.assert_kinematic_alive("kin", KIN_Q0)
        stamp = self.stamps["kin"].next()
        response = self.set_state("kin", stamp, (1e-300, 0.0, 0.0, 0.0))
        self.assertTrue(response.success, response.message)
        msg = self.nodes["kin"].state.wait_at(stamp)
        check_finite_state(self, msg)
        self.assertRotation(as_tuple(msg.orientation), (1.0, 0.0, 0.0, 0.0), 1e-15)
        response = self.set_state("ex", rospy.Time(0), (0.0, 5e-324, 0.0, 0.0))
        self.assertTrue(response.success, response.message)
        for msg in self.new_states("ex", 3):
            check_finite_state(self, msg)
            self.assertRotation(as_tuple(msg.orientation), (0.0, 1.0, 0.0, 0.0), 1e-15)
        # A zero quaternion is still refused.
        response = self.set_state("kin", self.stamps["kin"].next(), (0.0, 0.0, 0.0, 0.0))
        self.assertFalse(response.success)
        self.assert_dynamic_alive("ex")
        self.assert_kinematic_alive("kin", KIN_Q0)

    def test_zz_no_callback_ever_threw(self):
        # Runs last (name order): every input above was an outcome, not an exception.
        for ns in self.nodes:
            wait_for(lambda: self.diag.get("/%s/attitude_propagator" % ns, "callback_errors")
                     is not None, 10.0, "diagnostics of /%s" % ns)
            self.assertEqual(self.counter(ns, "callback_errors"), 0, ns)


if __name__ == "__main__":
    rostest.rosrun("attitude_propagator", "attack", AttackTest)
