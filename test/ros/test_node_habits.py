#!/usr/bin/python3
"""ROS habits (node_habits.test, wall time): `rosparam get` shows the model and integrator in
use next to the parameters as given (`auto`), also after a live change of the integrator;
diagnostics turn WARN naming the cause when half or more of the rate samples of a second are lost (max_dt
below the input period) and OK again when it is fixed; a message's strings reach the log cut
to 64 bytes with their length, and without control characters; with world_frame ned the
state comes in NED/FRD, ~set_state takes it so, and tf gives the same between the named
frames."""
import math
import subprocess
import threading
import unittest

import rospy
import rostest
import yaml
from diagnostic_msgs.msg import DiagnosticStatus
from dynamic_reconfigure.client import Client
from geometry_msgs.msg import Vector3Stamped
from rosgraph_msgs.msg import Log
from sensor_msgs.msg import Imu

from ap_test_util import (Node, NodeDiagnostics, RosoutLines, as_tuple, axis_angle, lookup,
                          make_imu, make_tf_buffer, qmul, rotation_angle, wait_connected,
                          wait_for)

HAB = "/hab/attitude_propagator"
HABD = "/habd/attitude_propagator"
RATE_HZ = 200.0           # input period 5e-3 s
HUGE = 10 * 1000 * 1000   # bytes of the frame id in the attack


def rosparam_get(name):
    """What a user types: `rosparam get NAME`, its YAML answer read back."""
    out = subprocess.run(["rosparam", "get", name], stdout=subprocess.PIPE, text=True,
                         timeout=30, check=True).stdout
    return yaml.safe_load(out)


class ImuFeed:
    """IMU samples at RATE_HZ in wall time, stamped now, in body_h, until stop()."""

    def __init__(self, pub):
        self.pub = pub
        self.running = True
        self.thread = threading.Thread(target=self._run, daemon=True)
        self.thread.start()

    def _run(self):
        rate = rospy.Rate(RATE_HZ)
        while self.running and not rospy.is_shutdown():
            self.pub.publish(make_imu(rospy.Time.now(), (0.0, 0.0, 0.2), frame_id="body_h"))
            rate.sleep()

    def stop(self):
        self.running = False
        self.thread.join()


class NodeHabitsTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("test_node_habits")
        cls.rosout = RosoutLines()
        cls.status = NodeDiagnostics(HAB)
        cls.nodes = {ns: Node(ns) for ns in ("hab", "habd", "habn")}
        for node in cls.nodes.values():
            node.wait_ready()
        cls.imu = rospy.Publisher("/hab/imu/data_raw", Imu, queue_size=1000)
        cls.bias = rospy.Publisher("/hab/gyro_bias", Vector3Stamped, queue_size=10)
        wait_connected(cls.imu)
        wait_connected(cls.bias)
        cls.client = Client(HAB, timeout=30.0)
        cls.imu_ned = rospy.Publisher("/habn/imu/data_raw", Imu, queue_size=1000)
        wait_connected(cls.imu_ned)
        cls.tf_buffer, cls.tf_listener = make_tf_buffer()

    def test_world_frame_ned_publishes_ned_frd_and_tf_agrees(self):
        node = self.nodes["habn"]
        t0 = rospy.Time.now()
        # The state pinned in NED/FRD: level, heading 30 deg (z down: clockwise from north),
        # turning at -0.5 rad/s about down; then that yaw rate to the left measured in the FLU
        # frame body_n, (0, 0, 0.5), for 1 s: the heading falls by 0.5 rad. Had ~set_state's
        # rate not been read in FRD, the first intervals would show it.
        heading = axis_angle((0.0, 0.0, 1.0), math.radians(30.0))
        self.assertTrue(node.set_state(t0, heading, (0.0, 0.0, -0.5)).success)
        stamps = [t0 + rospy.Duration(0.01 * k) for k in range(1, 101)]
        for stamp in stamps:
            self.imu_ned.publish(make_imu(stamp, (0.0, 0.0, 0.5), frame_id="body_n"))
        last = node.state.wait_at(stamps[-1])
        self.assertEqual(last.header.frame_id, "world_n_ned")
        self.assertEqual(last.child_frame_id, "body_n_frd")
        expected = qmul(heading, axis_angle((0.0, 0.0, 1.0), -0.5))
        self.assertLess(rotation_angle(as_tuple(last.orientation), expected), 1e-9)
        self.assertAlmostEqual(last.angular_velocity.z, -0.5, places=12)
        # tf: REP-103 world_n -> body_n, with world_n_ned and body_n_frd on /tf_static.
        from_tf = lookup(self.tf_buffer, "world_n_ned", "body_n_frd", stamps[-1])
        self.assertLess(rotation_angle(from_tf, as_tuple(last.orientation)), 1e-9)

    def test_resolved_model_and_integrator_on_the_parameter_server(self):
        self.assertEqual(rosparam_get(HAB + "/model"), "auto")
        self.assertEqual(rosparam_get(HAB + "/integrator"), "auto")
        self.assertEqual(rosparam_get(HAB + "/resolved_model"), "kinematic")
        self.assertEqual(rosparam_get(HAB + "/resolved_integrator"), "cf4")
        self.assertEqual(rosparam_get(HABD + "/model"), "auto")
        self.assertEqual(rosparam_get(HABD + "/resolved_model"), "dynamic")
        self.assertEqual(rosparam_get(HABD + "/resolved_integrator"), "exact")
        # A live change of the integrator shows there too, and `auto` again resolves again.
        self.client.update_configuration({"integrator": "exp"})
        wait_for(lambda: rosparam_get(HAB + "/resolved_integrator") == "exp", 10.0,
                 "resolved_integrator exp")
        self.client.update_configuration({"integrator": "auto"})
        wait_for(lambda: rosparam_get(HAB + "/resolved_integrator") == "cf4", 10.0,
                 "resolved_integrator cf4")
        self.assertEqual(rosparam_get(HAB + "/model"), "auto")

    def test_max_dt_below_the_input_period_turns_diagnostics_warn_with_the_cause(self):
        feed = ImuFeed(self.imu)
        try:
            wait_for(lambda: (self.status.get() or (None, ""))[1] == "propagating", 10.0,
                     "diagnostics OK while fed at %g Hz" % RATE_HZ)
            self.assertEqual(self.client.update_configuration({"max_dt": 1e-6})["max_dt"], 1e-6)
            status = wait_for(lambda: self.status.get()[0] == DiagnosticStatus.WARN
                              and self.status.get(), 10.0, "diagnostics WARN")
            level, message, _ = status
            self.assertIn("rate samples of the last second were lost", message)
            self.assertIn("max_dt 1e-06 s is below the input period ", message)
            period = float(message.split("input period ")[1].split(" s")[0])
            # The period of arrival in the window: the feed's, slower on a loaded machine.
            self.assertTrue(0.5 / RATE_HZ < period < 4.0 / RATE_HZ, message)
            self.client.update_configuration({"max_dt": 1.0})
            wait_for(lambda: (self.status.get() or ())[:2] == (DiagnosticStatus.OK, "propagating"),
                     10.0,
                     "diagnostics OK again")
        finally:
            self.client.update_configuration({"max_dt": 1.0})
            feed.stop()

    def test_a_huge_frame_id_reaches_the_log_cut(self):
        self.imu.publish(make_imu(rospy.Time.now(), (0.0, 0.0, 0.2), frame_id="x" * HUGE))
        lines = wait_for(lambda: self.rosout.of(HAB, Log.WARN, "no transform from the rates' frame"),
                         20.0, "the warning about the huge frame")
        line = lines[0]
        self.assertIn("'%s...(%d bytes)'" % ("x" * 64, HUGE), line)
        # The frame id in 64 bytes each time it is named (the frame, the mount, the setting),
        # tf's error text quoting it in 256.
        self.assertLess(len(line), 1000, line[:2000])
        self.assertLessEqual(line.count("x"), 3 * 64 + 256)

    def test_control_characters_and_utf8_in_a_frame_id(self):
        # A newline would start a log line of its own. (Where the cut falls in UTF-8 text is
        # checked by test_log_text.cpp: rosconsole under the C locale shows each byte above
        # 0x7F as '?'.)
        frame = "evil\n[FATAL] fake line\x1b[31m" + "\u00e9" * 40
        msg = Vector3Stamped()
        msg.header.frame_id = frame
        self.bias.publish(msg)
        lines = wait_for(lambda: self.rosout.of(HAB, Log.WARN, "gyro_bias: frame id"), 20.0,
                         "the warning about the bias frame")
        line = lines[0]
        self.assertNotIn("\n", line)
        self.assertNotIn("\x1b", line)
        self.assertIn("evil?[FATAL] fake line?[31m", line)
        cut = line.split("gyro_bias: frame id '")[1].split("...(")[0]
        self.assertLessEqual(len(cut), 64)
        # A line break in a frame id: refused by the frame id rule, which the line names.
        self.assertIn("...(%d bytes)' refused; a frame id may not contain spaces"
                      % len(frame.encode("utf-8")), line)


if __name__ == "__main__":
    rostest.rosrun("attitude_propagator", "node_habits", NodeHabitsTest)
