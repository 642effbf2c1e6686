#!/usr/bin/python3
"""fix_types.test: fixes arrive as PoseWithCovarianceStamped (the topic's type from its first
message); then another process publishes QuaternionStamped on the same topic. ROS 1 refuses that
connection, so none of its messages reach the node; the node finds the other type registered
with the master and names it, in a warning and in the diagnostics (fixes_other_type)."""
import subprocess
import time
import unittest

import rospy
import rostest
from geometry_msgs.msg import PoseWithCovarianceStamped
from sensor_msgs.msg import Imu

from ap_test_util import (NodeDiagnostics, RosoutLines, make_imu, make_pose_fix, wait_connected,
                          wait_for)

TOPIC = "/ft/orientation_fix"
OTHER = "geometry_msgs/QuaternionStamped"
WARN = 4  # rosgraph_msgs/Log.WARN
CHECK_PERIOD_S = 5.0  # kFixTypeCheckPeriod


class FixTypesTest(unittest.TestCase):
    def test_another_type_on_the_fix_topic_is_named(self):
        rospy.init_node("test_fix_types")
        rosout = RosoutLines()
        diag = NodeDiagnostics("/ft/attitude_propagator")
        imu = rospy.Publisher("/ft/imu/data_raw", Imu, queue_size=100)
        fix = rospy.Publisher(TOPIC, PoseWithCovarianceStamped, queue_size=10)
        wait_connected(imu)
        wait_connected(fix)
        now = rospy.Time.now()
        for k in range(0, 20):
            imu.publish(make_imu(now + rospy.Duration(0.01 * k), (0.0, 0.0, 0.1), "body_ft"))
        time.sleep(0.5)
        # Ahead of the rates: it waits for them, and is applied when they reach it.
        fix.publish(make_pose_fix(now + rospy.Duration(0.25), "world_ft", (0.0, 0.0, 0.0, 1.0)))
        time.sleep(0.5)
        for k in range(20, 40):
            imu.publish(make_imu(now + rospy.Duration(0.01 * k), (0.0, 0.0, 0.1), "body_ft"))
        wait_for(lambda: diag.get() and int(diag.get()[2].get("fixes_accepted", 0)) >= 1, 10.0,
                 "the first fix applied")
        self.assertEqual(diag.get()[2]["fixes_other_type"], "none")
        other = subprocess.Popen(
            ["rostopic", "pub", "-r", "2", TOPIC, OTHER,
             "{header: {frame_id: world_ft}, quaternion: {w: 1.0}}"],
            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        try:
            wait_for(lambda: diag.get() and diag.get()[2].get("fixes_other_type") == OTHER,
                     3 * CHECK_PERIOD_S + 10.0, "fixes_other_type %s" % OTHER)
            text = "orientation_fix: a publisher of %s is registered on %s" % (OTHER, TOPIC)
            wait_for(lambda: rosout.of("/ft/attitude_propagator", WARN, text), 10.0, text)
        finally:
            other.terminate()
            other.wait(10)


if __name__ == "__main__":
    rostest.rosrun("attitude_propagator", "fix_types", FixTypesTest)
