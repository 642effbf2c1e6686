#!/usr/bin/python3
"""tf_conflict (tf_conflict.test): the test publishes odom -> {warn,stop,ignore}_link on
/tf_static, a second parent of each node's body frame. `warn` counts it and keeps its tf,
`stop` counts it and publishes no more tf (attitude_state goes on) until publish_tf is switched
off and on with the static parent gone, `ignore` neither watches /tf nor counts. For stop_tf the
parent comes on /tf, from a publisher that stops and starts again: tf stops while it publishes
and resumes 2 s after it went quiet."""
import threading
import time
import unittest

import rosgraph
import rospy
import rostest
from geometry_msgs.msg import TransformStamped
from sensor_msgs.msg import Imu
from tf2_msgs.msg import TFMessage

from dynamic_reconfigure.client import Client

from ap_test_util import Diagnostics, Node, Stamps, TfRecorder, make_imu, wait_connected, wait_for

MODES = ("warn", "stop", "ignore", "stop_tf")
STATIC_MODES = ("warn", "stop", "ignore")
TRUE, FALSE = ("True", "true", "1"), ("False", "false", "0")
CLEARANCE_S = 2.0  # documented: tf resumes after this long without a parent on /tf


def conflicting_parents(modes=STATIC_MODES):
    msg = TFMessage()
    for mode in modes:
        t = TransformStamped()
        t.header.stamp = rospy.Time.now()
        t.header.frame_id = "odom"
        t.child_frame_id = "%s_link" % mode
        t.transform.rotation.w = 1.0
        msg.transforms.append(t)
    return msg


class TfConflictPublisher:
    """Another node's tf: odom -> stop_tf_link on /tf at 20 Hz, until stop(); unregistered
    then, so that start() again is a publisher that came back (a new connection)."""

    def __init__(self):
        self.pub = rospy.Publisher("/tf", TFMessage, queue_size=10)
        self.running = True
        self.last_sent = None
        self.thread = threading.Thread(target=self._run, daemon=True)
        self.thread.start()

    def _run(self):
        while self.running and not rospy.is_shutdown():
            self.pub.publish(conflicting_parents(("stop_tf",)))
            self.last_sent = time.monotonic()
            time.sleep(0.05)

    def stop(self):
        self.running = False
        self.thread.join()
        self.pub.unregister()
        return self.last_sent


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

    def stopped(self, mode):
        return self.diag.get(self.nodes[mode].name, "tf_stopped")

    def resumes(self, mode):
        return self.diag.counter(self.nodes[mode].name, "tf_resumes") or 0

    def publish_tf(self, client, on):
        self.assertEqual(client.update_configuration({"publish_tf": on})["publish_tf"], on)

    def test_stop_on_tf_resumes_when_the_other_publisher_is_gone(self):
        for cycle in (1, 2):  # the second time: the conflicting publisher came back
            conflict = TfConflictPublisher()
            wait_for(lambda: self.stopped("stop_tf") in TRUE, 20.0, "stop_tf stopped (%d)" % cycle)
            # While the other parent keeps coming (longer than the clearance), no tf of ours.
            stamp = self.feed(1)
            self.nodes["stop_tf"].state.wait_at(stamp)
            time.sleep(CLEARANCE_S + 1.0)
            self.nodes["stop_tf"].state.wait_at(self.feed(1))
            self.assertEqual(self.ours("stop_tf", stamp), [])
            self.assertIn(self.stopped("stop_tf"), TRUE)
            self.assertEqual(self.resumes("stop_tf"), cycle - 1)
            last_sent = conflict.stop()
            wait_for(lambda: self.stopped("stop_tf") in FALSE, 10.0, "stop_tf resumed (%d)" % cycle)
            # Not before the clearance (the diagnostics only make it look later).
            self.assertGreater(time.monotonic() - last_sent, CLEARANCE_S - 0.1)
            self.assertEqual(self.resumes("stop_tf"), cycle)
            stamp = self.feed(1)
            wait_for(lambda: self.ours("stop_tf", stamp), 10.0, "stop_tf's tf again (%d)" % cycle)

    def test_stop_resumes_when_publish_tf_is_switched_off_and_on(self):
        self.wait_conflict("stop")
        wait_for(lambda: self.stopped("stop") in TRUE, 10.0, "tf_stopped")
        client = Client(self.nodes["stop"].name, timeout=30.0)
        # The latched parent is still published: the watch, subscribed anew, sees it again.
        conflicts = self.diag.counter(self.nodes["stop"].name, "tf_conflicts")
        self.publish_tf(client, False)
        self.publish_tf(client, True)
        self.diag.wait_counter(self.nodes["stop"].name, "tf_conflicts", conflicts + 1, 10.0)
        wait_for(lambda: self.stopped("stop") in TRUE, 10.0, "stopped again")
        # Its publisher gone, switching publish_tf off and on resumes for good.
        self.__class__.static.unregister()
        try:
            self.publish_tf(client, False)
            self.publish_tf(client, True)
            wait_for(lambda: self.stopped("stop") in FALSE, 10.0, "stop resumed")
            stamp = self.feed(1)
            wait_for(lambda: self.ours("stop", stamp), 10.0, "stop's tf after the switch")
            time.sleep(CLEARANCE_S)
            self.assertIn(self.stopped("stop"), FALSE)
        finally:
            cls = self.__class__
            cls.static = rospy.Publisher("/tf_static", TFMessage, queue_size=1, latch=True)
            cls.static.publish(conflicting_parents())

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
