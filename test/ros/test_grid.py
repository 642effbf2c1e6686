#!/usr/bin/python3
"""The dynamic model's publish grid under sim time (grid.test): every grid stamp at or before
the clock is published, once, whatever the phase of the clock's ticks or how late the node's
callbacks run; a gap is judged from the clock, never from a callback's lateness."""
import unittest

import rospy
import rostest
from geometry_msgs.msg import Vector3, WrenchStamped

from ap_test_util import (NS_PER_S, Diagnostics, Node, SimClock, as_tuple, axis_angle,
                          check_each, rotation_angle, time_ns, wait_connected,
                          wait_for)

PERIOD_NS = 10 ** 7  # 1 / publish_rate (100 Hz)
MS = 10 ** 6
# How long (wall) the stamp the clock stopped on may take to come out.
STOP_TIMEOUT = 3.0


class GridTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("test_grid")
        cls.clock = SimClock(2, 10 * NS_PER_S)
        cls.diag = Diagnostics()
        cls.nodes = {ns: Node(ns) for ns in ("sph", "trq")}
        for node in cls.nodes.values():
            node.wait_ready()
        cls.torque_pub = rospy.Publisher("/trq/torque", WrenchStamped, queue_size=100)
        wait_connected(cls.torque_pub)

    def counter(self, ns, key):
        return self.diag.counter("/%s/attitude_propagator" % ns, key) or 0

    def assertRotation(self, actual, expected, tol):
        self.assertLess(rotation_angle(actual, expected), tol,
                        "got %s, expected %s" % (actual, expected))

    def test_1_clock_stopping_on_a_grid_stamp_gets_it_published(self):
        # Ten times: the clock at t0 (a different phase against the grid each time), a jump
        # of 0.07 s, 0.01 s steps, the last one landing on a whole second W, and a stop.
        # The state at W must come out; the sphere turns at 0.5 rad/s about z from t0.
        node = self.nodes["sph"]
        w = 0.5
        def trial(i):
            whole_ns = (20 + 3 * i) * NS_PER_S
            t0 = whole_ns - NS_PER_S + i * MS + 300 * 1000 * i  # phase i.(1 + 0.3) ms
            self.clock.set(t0)
            response = node.set_state(time_ns(t0), (0, 0, 0, 1), (0, 0, w))
            self.assertTrue(response.success, response.message)
            self.clock.set(t0 + 70 * MS)
            self.clock.run(whole_ns, PERIOD_NS, pause=0.002)
            self.assertEqual(self.clock.now_ns, whole_ns)
            state = node.state.wait_at(time_ns(whole_ns), timeout=STOP_TIMEOUT)
            angle = w * (whole_ns - t0) / NS_PER_S
            self.assertRotation(as_tuple(state.orientation), axis_angle((0, 0, 1), angle),
                                1e-9)
            # Every grid stamp after the anchor up to W, each once.
            stamps = [m.header.stamp.to_nsec() for m in node.state.messages
                      if t0 < m.header.stamp.to_nsec() <= whole_ns]
            expected = list(range(t0 - t0 % PERIOD_NS + PERIOD_NS, whole_ns + 1, PERIOD_NS))
            self.assertEqual(sorted(stamps), expected)
        check_each(self, range(10), trial)

    def test_2_starved_callbacks_publish_every_grid_stamp_and_see_no_gap(self):
        # A torque at t0 from rest, then /clock as a burst of 300 ticks of 0.01 s with no
        # pause (3 s of sim time, longer than max_dt = 1 s, arriving faster than the node's
        # callbacks run). Closed form about the principal axis x (I1 = 2, T = 0.4 N m):
        # w = T t / I1, angle = T t^2 / (2 I1).
        node = self.nodes["trq"]
        t0 = 100 * NS_PER_S
        self.clock.set(t0)
        self.assertTrue(node.set_state(time_ns(t0)).success)
        accepted = self.counter("trq", "accepted")
        msg = WrenchStamped()
        msg.header.stamp = time_ns(t0)
        msg.header.frame_id = "body_trq"
        msg.wrench.torque = Vector3(0.4, 0.0, 0.0)
        self.torque_pub.publish(msg)
        self.diag.wait_counter("/trq/attitude_propagator", "accepted", accepted + 1)
        gaps = self.counter("trq", "gaps")
        end = t0 + 3 * NS_PER_S
        self.clock.run(end, PERIOD_NS, pause=0)
        state = node.state.wait_at(time_ns(end), timeout=20.0)
        stamps = [m.header.stamp.to_nsec() for m in node.state.messages
                  if t0 < m.header.stamp.to_nsec() <= end]
        self.assertEqual(len(stamps), 300)
        self.assertEqual(sorted(stamps), list(range(t0 + PERIOD_NS, end + 1, PERIOD_NS)))
        t = 3.0
        self.assertAlmostEqual(state.angular_velocity.x, 0.4 * t / 2.0, delta=1e-9)
        self.assertRotation(as_tuple(state.orientation),
                            axis_angle((1, 0, 0), 0.4 * t * t / 4.0), 1e-7)
        # No gap: wait for diagnostics from after the burst, then compare.
        with self.diag.lock:
            self.diag.values.clear()
        wait_for(lambda: self.diag.get("/trq/attitude_propagator", "gaps") is not None, 10.0,
                 "diagnostics after the burst")
        self.assertEqual(self.counter("trq", "gaps"), gaps)

    def test_3_an_input_far_ahead_does_not_stop_the_grid(self):
        # A torque stamped in the year 2100 arrives right after ~reset, before the next clock
        # tick anchors the propagator again. It must wait for the clock like any input stamped
        # ahead of it: the grid states at the clock keep coming.
        node = self.nodes["trq"]
        node.reset()
        msg = WrenchStamped()
        msg.header.stamp = rospy.Time(4102444800)
        msg.header.frame_id = "body_trq"
        msg.wrench.torque = Vector3(0.4, 0.0, 0.0)
        received = self.counter("trq", "received")
        self.torque_pub.publish(msg)
        self.diag.wait_counter("/trq/attitude_propagator", "received", received + 1)
        start = (self.clock.now_ns // NS_PER_S + 1) * NS_PER_S
        self.clock.set(start)
        self.clock.run(start + NS_PER_S // 2, PERIOD_NS)
        state = node.state.wait_at(time_ns(start + NS_PER_S // 2), timeout=STOP_TIMEOUT)
        self.assertEqual(state.angular_velocity.x, 0.0)  # the torque is not in force yet


if __name__ == "__main__":
    rostest.rosrun("attitude_propagator", "grid", GridTest)
