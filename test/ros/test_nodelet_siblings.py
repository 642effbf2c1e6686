#!/usr/bin/python3
"""nodelet_siblings.test: two instances as nodelets in one manager, one IMU, the same child
frame under two parents. Each counts the other's transforms as a tf conflict (both publish
under the manager's node name, so the watch cannot skip by name), and each names itself in
its log lines."""
import time
import unittest

import rospy
import rostest
from sensor_msgs.msg import Imu

from ap_test_util import Diagnostics, RosoutLines, make_imu, wait_connected, wait_for

INSTANCES = {"first": "odom", "second": "map"}  # name: fixed_frame
WARN = 4  # rosgraph_msgs/Log.WARN


class NodeletSiblingsTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("test_nodelet_siblings")
        cls.rosout = RosoutLines()
        cls.diag = Diagnostics()
        for name in INSTANCES:
            rospy.wait_for_service("/%s/reset" % name, 30.0)
        cls.imu = rospy.Publisher("/imu/data_raw", Imu, queue_size=100)
        # One connection: the manager's process subscribes once for both nodelets.
        wait_connected(cls.imu)
        time.sleep(0.5)
        start = rospy.Time.now()
        for i in range(150):  # 3 s at 50 Hz
            cls.imu.publish(make_imu(start + rospy.Duration(0.02 * i), (0.0, 0.0, 0.1)))
            time.sleep(0.02)

    def test_each_counts_its_siblings_transforms_as_a_conflict(self):
        for name in INSTANCES:
            self.diag.wait_counter(name, "tf_conflicts", 1, timeout=10.0)

    def test_each_names_itself_and_the_sibling_in_its_warning(self):
        for name, fixed in INSTANCES.items():
            other_parent = [f for n, f in INSTANCES.items() if n != name][0]
            text = ("/%s: tf: another nodelet in manager /manager also publishes 'base_link' "
                    "as the child of '%s' on /tf (we publish %s -> base_link)"
                    % (name, other_parent, fixed))
            wait_for(lambda: self.rosout.of("/manager", WARN, text), 10.0, text)

    def test_its_own_transforms_are_not_counted(self):
        # Alone on its edge, each would count none: the count stays far below the transforms
        # each published (150), the sibling's only.
        self.diag.wait_counter("first", "tf_conflicts", 1, timeout=10.0)
        for name in INSTANCES:
            self.assertLessEqual(self.diag.counter(name, "tf_conflicts"), 160)


if __name__ == "__main__":
    rostest.rosrun("attitude_propagator", "nodelet_siblings", NodeletSiblingsTest)
