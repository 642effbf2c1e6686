#!/usr/bin/python3
"""tf_conflict (tf_conflict.test): the test publishes odom -> {warn,stop,ignore}_link on
/tf_static, a second parent of each node's body frame. `warn` counts it and keeps its tf,
`stop` counts it and publishes no more tf (attitude_state goes on), `ignore` neither watches
/tf nor counts."""
import unittest

import rosgraph
import rospy
import rostest
from geometry_msgs.msg import TransformStamped
from sensor_msgs.msg import Imu
from tf2_msgs.msg import TFMessage

from ap_test_util import Diagnostics, Node, Stamps, TfRecorder, make_imu, wait_connected, wait_for

MODES = ("warn", "stop", "ignore")


def conflicting_parents():
    msg = TFMessage()
    for mode in MODES:
        t = TransformStamped()
        t.header.stamp = rospy.Time.now()
        t.header.frame_id = "odom"
        t.child_frame_id = "%s_link" % mode
        t.transform.rotation.w = 1.0
        msg.transforms.append(t)
    return msg


class TfConflictTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("test_tf_conflict")
        cls.nodes = {mode: Node(mode) for mode in MODES}
        for node in cls.nodes.values():
            node.wait_ready()
        cls.diag = Diagnostics()
        cls.tf = TfRecorder(["%s_link" % mode for mode in MODES])
        cls.imu = {mode: rospy.Publisher("/%s/imu/data_raw" % mode, Imu, queue_size=100)
                   for mode in MODES}
        for pub in cls.imu.values():
            wait_connected(pub)
        cls.stamps = Stamps(1000)
        cls.feed(2)  # every node publishes its tf before the conflict appears
        for mode in MODES:
            wait_for(lambda mode=mode: cls.ours(mode), 10.0, "tf of %s" % mode)
        cls.static = rospy.Publisher("/tf_static", TFMessage, queue_size=1, latch=True)
        cls.static.publish(conflicting_parents())

    @classmethod
    def feed(cls, n):
        last = None
        for _ in range(n):
            last = cls.stamps.next()
            for mode, pub in cls.imu.items():
                pub.publish(make_imu(last, (0.0, 0.0, 0.5), frame_id="%s_link" % mode))
        return last

    @classmethod
    def ours(cls, mode, since=rospy.Time(0)):
        """The node's own transforms world -> <mode>_link (/tf only: ours), from `since`."""
        return [t for t in cls.tf.since(since)
                if t.child_frame_id == "%s_link" % mode and t.header.frame_id == "world"]

    def wait_conflict(self, mode):
        self.diag.wait_counter(self.nodes[mode].name, "tf_conflicts", 1, 20.0)

    def test_warn_counts_and_keeps_publishing(self):
        self.wait_conflict("warn")
        self.assertIn(self.diag.get(self.nodes["warn"].name, "tf_stopped"), ("False", "false", "0"))
        stamp = self.feed(1)
        wait_for(lambda: self.ours("warn", stamp), 10.0, "warn's tf after the conflict")

    def test_stop_counts_and_stops_its_tf_only(self):
        self.wait_conflict("stop")
        wait_for(lambda: self.diag.get(self.nodes["stop"].name, "tf_stopped")
                 in ("True", "true", "1"), 10.0, "tf_stopped")
        stamp = self.feed(3)
        self.nodes["stop"].state.wait_at(stamp)  # the state goes on
        wait_for(lambda: self.ours("warn", stamp), 10.0, "warn's tf at the same stamp")
        self.assertEqual(self.ours("stop", stamp), [])

    def test_ignore_does_not_watch(self):
        self.wait_conflict("warn")  # the conflicting parents have arrived
        master = rosgraph.Master("/test_tf_conflict")
        subscribed = {topic for topic, nodes in master.getSystemState()[1]
                      if self.nodes["ignore"].name in nodes}
        self.assertNotIn("/tf", subscribed)
        self.assertNotIn("/tf_static", subscribed)
        self.assertEqual(self.diag.counter(self.nodes["ignore"].name, "tf_conflicts"), 0)
        stamp = self.feed(1)
        wait_for(lambda: self.ours("ignore", stamp), 10.0, "ignore's tf")


if __name__ == "__main__":
    rostest.rosrun("attitude_propagator", "tf_conflict", TfConflictTest)
