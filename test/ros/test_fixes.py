#!/usr/bin/python3
"""Absolute attitude fixes through the public interface (fixes.test): orientation_fix in, the
attitude on tf and attitude_state, gyro_bias in AttitudeState, the fix counters in diagnostics.

The truth is the closed form of a constant body rate w from the identity at the first stamp,
q(t) = Exp(w t); the gyro reads w + b. Every wait is on an output (a state at a stamp, a
counter), never on a duration, so the test holds on a loaded machine."""
import math
import unittest

import rospy
import rostest
from geometry_msgs.msg import PoseWithCovarianceStamped, Quaternion, QuaternionStamped
from sensor_msgs.msg import Imu

from ap_test_util import (Diagnostics, Node, NodeDiagnostics, as_tuple, axis_angle, lookup,
                          make_imu, make_pose_fix, make_tf_buffer, qexp, qmul, rotation_angle,
                          wait_connected, wait_for)

NS_PER_S = 10 ** 9
H = 0.01  # rate sample spacing (s)


def stamp_at(base, seconds):
    return rospy.Time(0, int(round((base + seconds) * NS_PER_S)))


def scaled(v, s):
    return tuple(s * c for c in v)


class FixesTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("test_fixes")
        cls.tf_buffer, cls.tf_listener = make_tf_buffer()
        cls.diag = Diagnostics()
        cls.nodes = {ns: Node(ns) for ns in ("fx", "fu", "fr", "fn")}
        cls.imu = {ns: rospy.Publisher("/%s/imu/data_raw" % ns, Imu, queue_size=100000)
                   for ns in cls.nodes}
        # One type per topic here (rospy refuses a second): the type rule is test_fix_decoder.cpp's.
        cls.pose_fix = {ns: rospy.Publisher("/%s/orientation_fix" % ns, PoseWithCovarianceStamped,
                                            queue_size=1000)
                        for ns in ("fx", "fu")}
        cls.quaternion_fix = {ns: rospy.Publisher("/%s/orientation_fix" % ns, QuaternionStamped,
                                                  queue_size=1000)
                              for ns in ("fr", "fn")}
        for node in cls.nodes.values():
            node.wait_ready()
        for pub in (list(cls.imu.values()) + list(cls.pose_fix.values()) +
                    list(cls.quaternion_fix.values())):
            wait_connected(pub)

    def rates(self, ns, base, first, count, w):
        """Samples first .. first+count-1 of the rate w; returns the last stamp once the node
        has published the state there."""
        for i in range(first, first + count):
            self.imu[ns].publish(make_imu(stamp_at(base, i * H), w, "body_" + ns))
        last = stamp_at(base, (first + count - 1) * H)
        self.nodes[ns].state.wait_at(last, timeout=30.0)
        return last

    def quaternion_fix_msg(self, stamp, frame, q):
        msg = QuaternionStamped()
        msg.header.stamp = stamp
        msg.header.frame_id = frame
        msg.quaternion = Quaternion(*q)
        return msg

    def test_late_fixes_estimate_the_gyro_bias(self):
        """Fixes 100 ms late every 0.5 s (PoseWithCovarianceStamped, 1 mrad per axis) of a body
        turning at w, read by a gyro biased by b: the bias in AttitudeState converges to b and
        tf follows the closed form.

        Tolerances. The rates are exact but for b, the fixes exact: the estimate's error is
        what remains of the filter's transient, which it bounds by its own standard deviation
        (sent in AttitudeState): per axis within 3 sigma. Sigma itself: fitting the drift b t
        through N fixes T apart with error s is sigma_b ~ s sqrt(12 / N^3) / T, 2.7e-5 rad/s
        for N = 40, s = 1e-3, T = 0.5; we require under 1e-3 (4 % of |b|). The attitude right
        after a fix is within its covariance, at most the fix's (1e-6 rad^2 per axis), grown
        for 0.6 s by the bias' sigma and the rate noise (1e-3 rad/s at 100 Hz: 6e-9 rad^2):
        tf is within 3 sqrt(trace P) of the closed form, and sqrt(trace P) under 2e-3 rad.
        Without the fixes it would be off by |b| t = 0.5 rad."""
        ns, base = "fx", 1000.0
        w = (0.1, -0.2, 0.3)
        b = (0.02, -0.01, 0.015)
        gyro = tuple(wi + bi for wi, bi in zip(w, b))
        cov = [1e-6, 0, 0, 0, 1e-6, 0, 0, 0, 1e-6]
        chunk, fixes = 50, 40
        last = self.rates(ns, base, 0, 1, gyro)  # the anchor at base
        for k in range(fixes):
            last = self.rates(ns, base, 1 + k * chunk, chunk, gyro)
            t_fix = (k + 1) * chunk * H - 0.1
            self.pose_fix[ns].publish(
                make_pose_fix(stamp_at(base, t_fix), "world_fx", qexp(scaled(w, t_fix)), cov))
        # Every fix accounted for: the first comes before any history (too old, docs/design.md
        # §6.9); the gate may turn early ones away while the bias is unknown.
        name = self.nodes[ns].name
        wait_for(lambda: sum(self.diag.counter(name, key) or 0 for key in (
            "fixes_accepted", "fixes_rejected_gate", "fixes_too_old")) >= fixes, 30.0,
            "all %d fixes counted" % fixes)
        self.assertGreaterEqual(self.diag.counter(name, "fixes_accepted"), fixes // 2)
        n_end = 1 + fixes * chunk + chunk
        last = self.rates(ns, base, 1 + fixes * chunk, chunk, gyro)
        state = self.nodes[ns].state.wait_at(last)
        t_end = (n_end - 1) * H

        bias = (state.gyro_bias.x, state.gyro_bias.y, state.gyro_bias.z)
        sigma = (state.gyro_bias_stddev.x, state.gyro_bias_stddev.y, state.gyro_bias_stddev.z)
        for i in range(3):
            self.assertGreater(sigma[i], 0.0, "gyro_bias_stddev %s" % (sigma,))
            self.assertLess(sigma[i], 1e-3, "gyro_bias_stddev %s" % (sigma,))
            self.assertLessEqual(abs(bias[i] - b[i]), 3.0 * sigma[i],
                                 "gyro_bias %s, true %s, stddev %s" % (bias, b, sigma))
        P = state.orientation_covariance
        spread = math.sqrt(P[0] + P[4] + P[8])
        self.assertLess(spread, 2e-3, "orientation_covariance %s" % (P,))
        q_tf = lookup(self.tf_buffer, "world_fx", "body_fx", last)
        error = rotation_angle(q_tf, qexp(scaled(w, t_end)))
        rospy.loginfo("fixes: gyro_bias %s (true %s, stddev %s); tf off by %.3g rad, "
                      "3 sqrt(trace P) = %.3g rad; accepted %s, rejected by the gate %s, "
                      "too old %s",
                      bias, b, sigma, error, 3.0 * spread,
                      *(self.diag.get(name, k) for k in ("fixes_accepted", "fixes_rejected_gate",
                                                         "fixes_too_old")))
        self.assertLessEqual(error, 3.0 * spread, "tf off the closed form by %g rad" % error)
        self.assertLess(rotation_angle(as_tuple(state.orientation), q_tf), 1e-12)
        self.assertIsNotNone(self.diag.get(self.nodes[ns].name, "gyro_bias_estimate"))

    def test_fix_in_an_unknown_frame_is_refused(self):
        """Fixes in a frame tf does not know are refused and counted, the state unchanged; a
        run of them turns the diagnostics to WARN, naming them (rates keep coming meanwhile, so
        no other warning comes first)."""
        ns, base = "fu", 2000.0
        w = (0.0, 0.0, 0.5)
        name = self.nodes[ns].name
        status = NodeDiagnostics(name)
        n = [10]
        self.rates(ns, base, 0, n[0], w)
        wild = axis_angle((1, 0, 0), math.pi / 2)
        for k in range(3):
            self.pose_fix[ns].publish(make_pose_fix(stamp_at(base, 0.05 + k * H), "nowhere_fu",
                                                    wild, [1e-4, 0, 0, 0, 1e-4, 0, 0, 0, 1e-4]))
        self.diag.wait_counter(name, "fixes_refused_no_tf", 3, timeout=30.0)
        self.assertEqual(self.diag.counter(name, "fixes_accepted"), 0)
        self.assertEqual(self.diag.counter(name, "fixes_refused"), 3)

        def warned():
            self.imu[ns].publish(make_imu(stamp_at(base, n[0] * H), w, "body_" + ns))
            n[0] += 1
            latest = status.get()
            return latest and latest[0] == 1 and "not applied" in latest[1]
        wait_for(warned, 30.0, "WARN naming fixes not applied")
        last = self.rates(ns, base, n[0], 1, w)
        state = self.nodes[ns].state.wait_at(last)
        self.assertLess(rotation_angle(as_tuple(state.orientation), qexp(scaled(w, n[0] * H))),
                        1e-9)

    def test_reset_mode_replaces_the_attitude(self):
        """fix_mode reset: the attitude at the fix's stamp (100 ms before the newest rate)
        becomes the fix, and the rates since are integrated from it: q_fix Exp(w (t - t_fix)),
        exact for a constant rate but for round-off."""
        ns, base = "fr", 3000.0
        w = (0.1, 0.2, -0.3)
        # The first fix starts the history at the newest state (docs/design.md §6.9): one
        # stamped there, the closed form, changes nothing.
        last = self.rates(ns, base, 0, 10, w)
        self.quaternion_fix[ns].publish(self.quaternion_fix_msg(last, "world_fr",
                                                                qexp(scaled(w, 9 * H))))
        self.diag.wait_counter(self.nodes[ns].name, "fixes_reset", 1, timeout=30.0)
        self.rates(ns, base, 10, 10, w)
        t_fix = 0.09
        q_fix = axis_angle((0, 0, 1), math.pi / 2)
        self.quaternion_fix[ns].publish(self.quaternion_fix_msg(stamp_at(base, t_fix), "world_fr",
                                                                q_fix))
        self.diag.wait_counter(self.nodes[ns].name, "fixes_reset", 2, timeout=30.0)
        last = self.rates(ns, base, 20, 1, w)
        expected = qmul(q_fix, qexp(scaled(w, 20 * H - t_fix)))
        state = self.nodes[ns].state.wait_at(last)
        self.assertLess(rotation_angle(as_tuple(state.orientation), expected), 1e-8)
        self.assertLess(rotation_angle(lookup(self.tf_buffer, "world_fr", "body_fr", last),
                                       expected), 1e-8)

    def test_ned_fix_in_the_nodes_named_frames(self):
        """world_frame ned: a fix in world_fn_ned of body_fn_frd (fix_frame), both on the
        node's own /tf_static, is taken as AttitudeState gives the attitude: at rest, the next
        state's orientation is the fix. The node's tf listener starts at the first lookup, so
        the first fixes may be refused (no transform yet): fixes are sent until one is
        applied."""
        ns, base = "fn", 4000.0
        q_fix = axis_angle((0.2, -0.4, 1.0), 0.8)
        last = self.rates(ns, base, 0, 2, (0, 0, 0))
        name = self.nodes[ns].name
        for i in range(2, 200):
            self.quaternion_fix[ns].publish(
                self.quaternion_fix_msg(last - rospy.Duration(0.005), "world_fn_ned", q_fix))
            try:
                self.diag.wait_counter(name, "fixes_reset", 1, timeout=1.0)
                break
            except AssertionError:
                last = self.rates(ns, base, i, 1, (0, 0, 0))
        self.diag.wait_counter(name, "fixes_reset", 1, timeout=1.0)
        last = self.rates(ns, base, 1000, 1, (0, 0, 0))
        state = self.nodes[ns].state.wait_at(last)
        self.assertEqual(state.header.frame_id, "world_fn_ned")
        self.assertEqual(state.child_frame_id, "body_fn_frd")
        self.assertLess(rotation_angle(as_tuple(state.orientation), q_fix), 1e-9)


if __name__ == "__main__":
    rostest.rosrun("attitude_propagator", "fixes", FixesTest)
