#!/usr/bin/python3
"""The node under <node ns="robot1"> with imu:=my_imu (remap.test): its IMU input and output
move to /robot1/my_imu/, everything else stays in /robot1/."""
import unittest

import rosgraph
import rospy
import rostest
from sensor_msgs.msg import Imu

from ap_test_util import (Diagnostics, Node, Recorder, Stamps, as_tuple, axis_angle, make_imu,
                          rotation_angle, wait_connected, wait_for)

NODE = "/robot1/attitude_propagator"


class RemapTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("test_remap")
        cls.node = Node("robot1")
        cls.node.wait_ready()
        cls.diag = Diagnostics()

    def topics_of(self, kind):
        """Topics the node publishes (kind 0) or subscribes to (kind 1), from the master."""
        state = rosgraph.Master("/test_remap").getSystemState()
        return {topic for topic, nodes in state[kind] if NODE in nodes}

    def test_topics_are_where_the_remap_puts_them(self):
        published, subscribed = self.topics_of(0), self.topics_of(1)
        self.assertIn("/robot1/my_imu/data_raw", subscribed)
        self.assertIn("/robot1/my_imu/data", published)
        self.assertIn("/robot1/attitude_state", published)
        self.assertIn("/robot1/gyro_bias", subscribed)
        for topic in published | subscribed:
            self.assertFalse(topic.startswith("/robot1/imu/"), topic)
            self.assertFalse(topic.startswith("/imu") or topic.startswith("/my_imu"), topic)
        wait_for(lambda: self.diag.get(NODE, "accepted") is not None, 10.0, "diagnostics")

    def test_data_flows_through_the_remapped_topics(self):
        pub = rospy.Publisher("/robot1/my_imu/data_raw", Imu, queue_size=100)
        out = Recorder("/robot1/my_imu/data", Imu)
        wait_connected(pub)
        wait_for(lambda: out.sub.get_num_connections() > 0, 20.0, "/robot1/my_imu/data")
        stamps = Stamps(1000)
        a, b = stamps.next(), stamps.next()
        pub.publish(make_imu(a, (0.0, 0.0, 1.0)))
        pub.publish(make_imu(b, (0.0, 0.0, 1.0)))
        # cf4 turns a constant rate exactly: 0.1 rad about z in 0.1 s.
        for msg in (out.wait_at(b), self.node.state.wait_at(b)):
            self.assertLess(rotation_angle(as_tuple(msg.orientation),
                                           axis_angle((0, 0, 1), 0.1)), 1e-9)


if __name__ == "__main__":
    rostest.rosrun("attitude_propagator", "remap", RemapTest)
