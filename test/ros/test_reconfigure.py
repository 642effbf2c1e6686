#!/usr/bin/python3
"""Live reconfiguration (reconfigure.test, sim time): every parameter of the reconfigure
server, changed through its service (dynamic_reconfigure.client), takes effect on the next
input or grid stamp, from the current state; an invalid value is refused and the one in force
shown again. After start the private namespace holds every parameter in use. Tests run in
name order."""
import math
import os
import subprocess
import time
import unittest

import rospkg
import rospy
import rostest
import yaml
from dynamic_reconfigure.client import Client
from geometry_msgs.msg import Vector3, WrenchStamped
from sensor_msgs.msg import Imu

from ap_test_util import (NS_PER_S, Diagnostics, Node, SimClock, Stamps, TfRecorder, as_tuple,
                          axis_angle, check_each, make_imu, qconj, rotation_angle, time_ns,
                          wait_connected, wait_for)

TOL = 1e-12  # exp and cf4 turn a constant rate exactly; only round-off remains
W = (0.3, -0.2, 0.5)
# What the launch file sets, per node (the rest must show the defaults).
GIVEN = {
    "kin": dict(max_future=3600.0, integrator="cf4", angular_velocity_stddev=0.01,
                fixed_frame="world_k", body_frame="body_k"),
    "trq": dict(rate_input="none", torque_input=True, inertia=[2.0, 3.0, 4.0], publish_rate=50.0,
                fixed_frame="world_t", body_frame="body_t"),
    "big": dict(torque_input=True, inertia=[2.0, 3.0, 4.0], publish_rate=10.0,
                torque_timeout=100.0, angular_velocity_stddev=50.0, fixed_frame="world_b",
                body_frame="body_b"),
}


def exp_rotation(w, t):
    n = math.sqrt(sum(c * c for c in w))
    return (0.0, 0.0, 0.0, 1.0) if n == 0.0 else axis_angle(w, n * t)


class ReconfigureTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("test_reconfigure")
        cls.clock = SimClock(3, 10 * NS_PER_S)
        cls.diag = Diagnostics()
        cls.tf = TfRecorder(["body_k"])
        cls.nodes = {ns: Node(ns) for ns in GIVEN}
        for node in cls.nodes.values():
            node.wait_ready()
        cls.imu_pub = rospy.Publisher("/kin/imu/data_raw", Imu, queue_size=1000)
        cls.torque_pubs = {ns: rospy.Publisher("/%s/torque" % ns, WrenchStamped, queue_size=100)
                           for ns in ("trq", "big")}
        for pub in [cls.imu_pub] + list(cls.torque_pubs.values()):
            wait_connected(pub)
        cls.clients = {ns: Client("/%s/attitude_propagator" % ns, timeout=30.0)
                       for ns in ("kin", "trq")}
        cls.stamps = Stamps(1000)

    # ---- helpers ---------------------------------------------------------------------------

    def counter(self, ns, key):
        return self.diag.counter("/%s/attitude_propagator" % ns, key) or 0

    def fresh_counter(self, ns, key):
        """The counter from a diagnostics message published after this call."""
        name = "/%s/attitude_propagator" % ns
        with self.diag.lock:
            for status in [k for k in self.diag.values if k.startswith(name.lstrip("/") + ":")]:
                del self.diag.values[status]
        wait_for(lambda: self.diag.get(name, key) is not None, 10.0, "diagnostics of " + name)
        return self.counter(ns, key)

    def reconfigure(self, ns, **changes):
        return self.clients[ns].update_configuration(changes)

    def sample(self, stamp, w=W):
        """A rate sample to the kinematic node; its state at the stamp."""
        self.imu_pub.publish(make_imu(stamp, w, "body_k"))
        return self.nodes["kin"].state.wait_at(stamp)

    def pin(self, w=W, q=(0.0, 0.0, 0.0, 1.0)):
        stamp = self.stamps.next()
        self.assertTrue(self.nodes["kin"].set_state(stamp, q, w).success)
        return stamp

    def assertRotation(self, actual, expected, tol):
        self.assertLess(rotation_angle(actual, expected), tol,
                        "got %s, expected %s" % (actual, expected))

    def torque_from_rest(self, ns, seconds, step_s):
        """From rest at a whole second t0, 0.4 N m about x (I1 = 2) stamped t0, the clock run
        for `seconds`; returns the state at t0 + seconds."""
        t0 = (self.clock.now_ns // NS_PER_S + 2) * NS_PER_S
        self.clock.set(t0)
        node = self.nodes[ns]
        self.assertTrue(node.set_state(time_ns(t0)).success)
        accepted = self.counter(ns, "accepted")
        msg = WrenchStamped()
        msg.header.stamp = time_ns(t0)
        msg.header.frame_id = "body_" + ns[0]
        msg.wrench.torque = Vector3(0.4, 0.0, 0.0)
        self.torque_pubs[ns].publish(msg)
        self.diag.wait_counter("/%s/attitude_propagator" % ns, "accepted", accepted + 1)
        end = t0 + int(round(seconds * NS_PER_S))
        self.clock.run(end, int(round(step_s * NS_PER_S)))
        return node.state.wait_at(time_ns(end), timeout=20.0)

    # ---- parameters on the server ------------------------------------------------------------

    def test_0_every_parameter_in_use_is_on_the_server(self):
        path = os.path.join(rospkg.RosPack().get_path("attitude_propagator"), "config",
                            "default.yaml")
        with open(path) as f:
            defaults = yaml.safe_load(f)
        shown = {}
        for ns in ("kin", "trq"):
            out = subprocess.run(["rosparam", "get", "/%s/attitude_propagator" % ns],
                                 stdout=subprocess.PIPE, text=True, timeout=30, check=True)
            shown[ns] = yaml.safe_load(out.stdout)

        def check(case):
            ns, name = case
            self.assertIn(name, shown[ns])
            self.assertEqual(shown[ns][name], GIVEN[ns].get(name, defaults[name]))
        check_each(self, [(ns, name) for ns in shown for name in defaults], check)

    def test_0b_start_values_beyond_the_reconfigure_ranges_are_kept(self):
        # torque_timeout 100 s and angular_velocity_stddev 50 rad/s are valid parameters
        # (at most 3600 s and 1000 rad/s); the reconfigure server must not cut them to its
        # sliders' ranges (60 s, 10 rad/s) behind the user's back.
        shown = rospy.get_param("/big/attitude_propagator")
        check_each(self, ("torque_timeout", "angular_velocity_stddev"),
                   lambda name: self.assertEqual(shown[name], GIVEN["big"][name]))

    def test_0c_a_torque_timeout_beyond_the_reconfigure_range_is_in_force(self):
        # The same torque_timeout (100 s) in effect: the torque still acts after 70 s.
        state = self.torque_from_rest("big", 70.0, 0.5)
        self.assertAlmostEqual(state.angular_velocity.x, 0.4 * 70.0 / 2.0, delta=1e-9)

    # ---- each live parameter -----------------------------------------------------------------

    def test_1_publish_tf_and_reverse_tf(self):
        a = self.stamps.next()
        self.sample(a)
        wait_for(lambda: self.tf.at(a), 10.0, "tf at the first sample")
        self.assertFalse(self.reconfigure("kin", publish_tf=False)["publish_tf"])
        b = self.stamps.next()
        self.sample(b)
        time.sleep(0.5)
        self.assertEqual(self.tf.since(b), [])
        config = self.reconfigure("kin", publish_tf=True, reverse_tf=True)
        self.assertTrue(config["publish_tf"] and config["reverse_tf"])
        c = self.stamps.next()
        state = self.sample(c)
        t = wait_for(lambda: self.tf.at(c), 10.0, "tf after publish_tf: true")[0]
        self.assertEqual((t.header.frame_id, t.child_frame_id), ("body_k", "world_k"))
        self.assertRotation(as_tuple(t.transform.rotation), qconj(as_tuple(state.orientation)),
                            1e-15)
        self.assertFalse(self.reconfigure("kin", reverse_tf=False)["reverse_tf"])
        d = self.stamps.next()
        self.sample(d)
        t = wait_for(lambda: self.tf.at(d), 10.0, "tf after reverse_tf: false")[0]
        self.assertEqual((t.header.frame_id, t.child_frame_id), ("world_k", "body_k"))

    def test_2_integrator_change_goes_on_from_the_current_state(self):
        s0 = self.pin()
        for k in range(1, 4):
            state = self.sample(self.stamps.next())
            self.assertEqual(state.integrator, "cf4")
            self.assertRotation(as_tuple(state.orientation), exp_rotation(W, 0.1 * k), TOL)
        self.assertEqual(self.reconfigure("kin", integrator="exp")["integrator"], "exp")
        for k in range(4, 7):
            state = self.sample(self.stamps.next())
            self.assertEqual(state.integrator, "exp")
            self.assertRotation(as_tuple(state.orientation), exp_rotation(W, 0.1 * k), TOL)
        self.assertEqual(self.nodes["kin"].state.at(s0)[0].integrator, "cf4")

    def test_3_an_invalid_integrator_is_refused(self):
        # dopri5 and exact drive the dynamic model only: refused, the value in force shown.
        def refused(bad):
            self.assertEqual(self.reconfigure("kin", integrator=bad)["integrator"], "exp")
            self.assertEqual(self.clients["kin"].get_configuration(5.0)["integrator"], "exp")
            state = self.sample(self.stamps.next())
            self.assertEqual(state.integrator, "exp")
            self.assertEqual(rospy.get_param("/kin/attitude_propagator/integrator"), "exp")
        check_each(self, ("dopri5", "exact"), refused)

    def test_4_a_smaller_max_dt_holds_a_gap_that_was_integrated(self):
        self.pin()
        gaps = self.fresh_counter("kin", "gaps")
        state = self.sample(self.stamps.next(5))  # 0.5 s, below max_dt = 1 s: integrated
        self.assertRotation(as_tuple(state.orientation), exp_rotation(W, 0.5), TOL)
        self.assertEqual(self.fresh_counter("kin", "gaps"), gaps)
        self.assertEqual(self.reconfigure("kin", max_dt=0.2)["max_dt"], 0.2)
        state = self.sample(self.stamps.next(5))  # 0.5 s again, now above max_dt: held
        self.assertRotation(as_tuple(state.orientation), exp_rotation(W, 0.5), TOL)
        self.assertEqual(self.fresh_counter("kin", "gaps"), gaps + 1)
        self.assertEqual(self.reconfigure("kin", max_dt=1.0)["max_dt"], 1.0)
        state = self.sample(self.stamps.next())  # re-anchored at the gap's end
        self.assertRotation(as_tuple(state.orientation), exp_rotation(W, 0.6), TOL)

    def test_5_rate_noise_changes_the_covariance_growth(self):
        # At rest the orientation variance grows by h^2 sigma^2 per sample (Phi = J_r = I):
        # 3 samples at sigma = 0.01, then 2 at sigma = 0.1, h = 0.1 s.
        self.pin(w=(0.0, 0.0, 0.0))
        h = 0.1
        for sigma, n, before in ((0.01, 3, 0.0), (0.1, 2, 3 * (h * 0.01) ** 2)):
            if sigma != 0.01:
                config = self.reconfigure("kin", angular_velocity_stddev=sigma)
                self.assertEqual(config["angular_velocity_stddev"], sigma)
            for k in range(1, n + 1):
                cov = self.sample(self.stamps.next(), (0.0, 0.0, 0.0)).orientation_covariance
                expected = before + k * (h * sigma) ** 2
                for i in range(9):
                    if i in (0, 4, 8):
                        self.assertAlmostEqual(cov[i] / expected, 1.0, delta=1e-12)
                    else:
                        self.assertEqual(cov[i], 0.0)
        self.reconfigure("kin", angular_velocity_stddev=0.01)

    def test_6_torque_timeout_ends_the_torque(self):
        # 0.4 N m about x (I1 = 2) for 1 s, then nothing: w = 0.2 rad/s from then on, the
        # angle 0.4 / (2 * 2) * 1^2 = 0.1 rad at 1 s, + 0.2 rad/s * 1 s = 0.3 rad at 2 s.
        self.assertEqual(self.reconfigure("trq", torque_timeout=1.0)["torque_timeout"], 1.0)
        state = self.torque_from_rest("trq", 2.0, 0.01)
        self.assertAlmostEqual(state.angular_velocity.x, 0.2, delta=1e-9)
        self.assertRotation(as_tuple(state.orientation), axis_angle((1, 0, 0), 0.3), 1e-7)
        self.reconfigure("trq", torque_timeout=0.0)


if __name__ == "__main__":
    rostest.rosrun("attitude_propagator", "reconfigure", ReconfigureTest)
