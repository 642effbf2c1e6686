#!/usr/bin/python3
"""Dynamic model under sim time (dynamic.test). Tests run in name order on one clock."""
import math
import time
import unittest

import rospy
import rostest
import tf2_ros
from geometry_msgs.msg import (Quaternion, TransformStamped, TwistStamped, Vector3, Wrench,
                               WrenchStamped)
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import Imu

from ap_test_util import (Diagnostics, Node, Recorder, as_tuple, axis_angle, lookup, make_imu,
                          make_tf_buffer, rotation_angle, wait_connected, wait_for)

PERIOD_NS = 20 * 10 ** 6  # 1 / publish_rate (50 Hz)


def stamp(seconds):
    return rospy.Time(0, int(round(seconds * 1e9)))


class DynamicTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("test_dynamic")
        cls.clock_pub = rospy.Publisher("/clock", Clock, queue_size=10000)
        cls.now = 10.0
        wait_for(lambda: cls.clock_pub.get_num_connections() >= 5, 30.0, "5 nodes on /clock")
        cls.set_clock(cls.now)
        cls.tf_buffer, cls.tf_listener = make_tf_buffer()
        cls.diag = Diagnostics()
        cls.nodes = {ns: Node(ns) for ns in ("sph", "trq", "trqu", "rate", "late")}
        for node in cls.nodes.values():
            node.wait_ready()
        cls.torque_pub = rospy.Publisher("/trq/torque", WrenchStamped, queue_size=100)
        cls.torque_unstamped_pub = rospy.Publisher("/trqu/torque", Wrench, queue_size=100)
        cls.rate_pub = rospy.Publisher("/rate/body_twist", TwistStamped, queue_size=100)
        cls.imu_pub = rospy.Publisher("/late/imu/data_raw", Imu, queue_size=100)
        cls.imu_out = Recorder("/late/imu/data", Imu)
        for pub in (cls.torque_pub, cls.torque_unstamped_pub, cls.rate_pub, cls.imu_pub):
            wait_connected(pub)
        wait_for(lambda: cls.imu_out.sub.get_num_connections() > 0, 20.0, "/late/imu/data")

    @classmethod
    def set_clock(cls, seconds):
        cls.now = seconds
        cls.clock_pub.publish(Clock(clock=rospy.Time(0, int(round(seconds * 1e9)))))

    @classmethod
    def run_clock(cls, to, step=0.01):
        """Advances /clock to `to` in steps (a bag playing fast)."""
        n = int(round((to - cls.now) / step))
        start = cls.now
        for k in range(1, n + 1):
            cls.set_clock(start + k * step)
            time.sleep(0.001)

    def accepted(self, ns):
        return self.diag.counter("/%s/attitude_propagator" % ns, "accepted") or 0

    def assertRotation(self, actual, expected, tol):
        self.assertLess(rotation_angle(actual, expected), tol,
                        "got %s, expected %s" % (actual, expected))

    def test_1_sphere_turns_at_constant_rate(self):
        self.run_clock(100.0, step=1.0)
        node = self.nodes["sph"]
        # The node has seen /clock reach 100 s (its grid state there), so a state pinned there is
        # not ahead of its clock (max_future).
        node.state.wait_at(rospy.Time(100))
        response = node.set_state(rospy.Time(100), (0, 0, 0, 1), (0, 0, 0.5))
        self.assertTrue(response.success, response.message)
        self.run_clock(102.0)
        state = node.state.wait_at(rospy.Time(102))
        self.assertEqual(state.model, "exact_sphere")
        self.assertEqual(state.integrator, "exact")
        self.assertRotation(as_tuple(state.orientation), axis_angle((0, 0, 1), 1.0), 1e-9)
        self.assertRotation(lookup(self.tf_buffer, "world_sph", "body_sph", rospy.Time(102)),
                            axis_angle((0, 0, 1), 1.0), 1e-9)
        # Published on the grid of 1/publish_rate only, never twice for one stamp.
        stamps = [m.header.stamp.to_nsec() for m in node.state.messages]
        self.assertTrue(all(s % PERIOD_NS == 0 for s in stamps), stamps[:20])
        self.assertEqual(len(stamps), len(set(stamps)))

    def test_2_torque_from_rest(self):
        # From rest, a torque along a principal axis: w = T t / I, angle = T t^2 / (2 I).
        t0 = self.now
        trq, trqu = self.nodes["trq"], self.nodes["trqu"]
        self.assertTrue(trq.set_state(rospy.Time(t0)).success)
        response = trqu.set_state(rospy.Time(0))  # zero stamp: now, i.e. the clock's t0
        self.assertTrue(response.success, response.message)
        self.assertIn("%.1f" % t0, response.message)
        before = (self.accepted("trq"), self.accepted("trqu"))
        msg = WrenchStamped()
        msg.header.stamp = rospy.Time(t0)
        msg.header.frame_id = "body_trq"
        msg.wrench.torque = Vector3(0.4, 0.0, 0.0)       # I1 = 2: w_x = 0.2 t
        self.torque_pub.publish(msg)
        self.torque_unstamped_pub.publish(Wrench(torque=Vector3(0.0, 0.0, 0.8)))  # I3 = 4, fixed z
        self.diag.wait_counter("/trq/attitude_propagator", "accepted", before[0] + 1)
        self.diag.wait_counter("/trqu/attitude_propagator", "accepted", before[1] + 1)
        self.run_clock(t0 + 2.0)
        end = rospy.Time(0, int(round((t0 + 2.0) * 1e9)))
        state = trq.state.wait_at(end)
        self.assertEqual(state.model, "numerical_rk4")
        self.assertAlmostEqual(state.angular_velocity.x, 0.4, delta=1e-9)
        self.assertAlmostEqual(state.kinetic_energy, 0.5 * 2.0 * 0.4 ** 2, delta=1e-9)
        self.assertRotation(as_tuple(state.orientation), axis_angle((1, 0, 0), 0.4), 1e-7)
        self.assertRotation(lookup(self.tf_buffer, "world_trqu", "body_trqu", end),
                            axis_angle((0, 0, 1), 0.4), 1e-7)

    def test_3_rate_input_sets_the_body_rate_at_its_stamp(self):
        t0 = self.now
        node = self.nodes["rate"]
        self.assertTrue(node.set_state(rospy.Time(t0)).success)
        before = self.diag.counter("/rate/attitude_propagator", "received") or 0
        msg = TwistStamped()
        msg.header.stamp = rospy.Time(0, int(round((t0 + 0.5) * 1e9)))
        msg.twist.angular = Vector3(0.0, 0.0, 0.5)  # about the major axis: stays there
        self.rate_pub.publish(msg)
        # Stamped ahead of the clock, it waits in the node until the clock reaches it.
        self.diag.wait_counter("/rate/attitude_propagator", "received", before + 1)
        self.run_clock(t0 + 2.0)
        state = node.state.wait_at(rospy.Time(0, int(round((t0 + 2.0) * 1e9))))
        self.assertRotation(as_tuple(state.orientation), axis_angle((0, 0, 1), 0.75), 1e-7)
        self.assertTrue(state.model.startswith("exact"), state.model)

    def test_3b_torque_in_a_third_frame_goes_through_tf(self):
        # A torque sensor frame turned +90 degrees about the body's z axis: (0, 0.4, 0) there
        # is (-0.4, 0, 0) in the body. The node looks the frame up through tf when the first
        # such torque arrives, so the first ones may be dropped until tf has it.
        broadcaster = tf2_ros.StaticTransformBroadcaster()
        t = TransformStamped()
        t.header.stamp = rospy.Time(self.now)
        t.header.frame_id = "body_trq"
        t.child_frame_id = "trq_sensor"
        t.transform.rotation = Quaternion(*axis_angle((0, 0, 1), math.pi / 2))
        broadcaster.sendTransform(t)
        t0 = self.now
        node = self.nodes["trq"]
        self.assertTrue(node.set_state(rospy.Time(t0)).success)
        before = self.accepted("trq")
        msg = WrenchStamped()
        msg.header.stamp = rospy.Time(t0)
        msg.header.frame_id = "trq_sensor"
        msg.wrench.torque = Vector3(0.0, 0.4, 0.0)

        def applied():
            self.torque_pub.publish(msg)
            time.sleep(0.05)
            return self.accepted("trq") > before
        wait_for(applied, 10.0, "a torque in trq_sensor accepted")
        self.run_clock(t0 + 2.0)
        state = node.state.wait_at(rospy.Time(0, int(round((t0 + 2.0) * 1e9))))
        self.assertRotation(as_tuple(state.orientation), axis_angle((1, 0, 0), -0.4), 1e-7)

    def test_3c_a_late_rate_goes_out_with_the_orientation_at_its_own_stamp(self):
        # Spinning at 1 rad/s about z from the first rate; the grid reaches t0 + 0.1 s, then a
        # rate stamped t0 + 0.05 s arrives. It acts from the grid point, and its message goes
        # out on imu/data with the orientation at its own stamp: 0.05 rad about z (the closed
        # form), not the 0.1 rad of the model's time.
        self.run_clock(math.floor(self.now) + 1.0)
        t0 = self.now
        before = self.diag.counter("/late/attitude_propagator", "late") or 0
        self.imu_pub.publish(make_imu(stamp(t0), (0.0, 0.0, 1.0), frame_id="body_late"))
        self.imu_out.wait_at(stamp(t0))  # applied: it anchored the model
        self.run_clock(t0 + 0.1)
        self.nodes["late"].state.wait_at(stamp(t0 + 0.1))
        self.imu_pub.publish(make_imu(stamp(t0 + 0.05), (0.0, 0.0, 1.0), frame_id="body_late"))
        late = self.imu_out.wait_at(stamp(t0 + 0.05))
        self.diag.wait_counter("/late/attitude_propagator", "late", before + 1)
        self.assertRotation(as_tuple(late.orientation), axis_angle((0, 0, 1), 0.05), 1e-9)

    def test_4_clock_jumping_back_resets(self):
        node = self.nodes["sph"]
        before = self.diag.counter("/sph/attitude_propagator", "resets") or 0
        # A looped bag: back to before the first clock of this test (10 s), so the stamps
        # published now were never published before.
        self.set_clock(5.0)
        self.diag.wait_counter("/sph/attitude_propagator", "resets", before + 1)
        state = node.state.wait_at(rospy.Time(5))
        self.assertRotation(as_tuple(state.orientation), (0, 0, 0, 1), 1e-12)
        self.run_clock(6.0)
        # The initial state again: initial_angular_velocity 0.2 rad/s about z.
        state = node.state.wait_at(rospy.Time(6))
        self.assertRotation(as_tuple(state.orientation), axis_angle((0, 0, 1), 0.2), 1e-9)


if __name__ == "__main__":
    rostest.rosrun("attitude_propagator", "dynamic", DynamicTest)
