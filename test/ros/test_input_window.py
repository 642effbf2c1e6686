#!/usr/bin/python3
"""Diagnostics and lost rate samples (input_window.test, wall time), by the rule of
docs/node.md: the status is WARN when more than half of the samples received in a one-second
window were lost, naming the commonest cause. The samples come in bursts of four, each burst
one window's share whatever the machine's load: one straggler in four (a quarter lost) must
leave the status OK, three in four must turn it WARN with the stragglers' cause. Neither
depends on how many bursts a window holds."""
import threading
import time
import unittest

import rospy
import rostest
from diagnostic_msgs.msg import DiagnosticStatus
from sensor_msgs.msg import Imu

from ap_test_util import Node, NodeDiagnostics, make_imu, wait_connected, wait_for

WIN = "/win/attitude_propagator"
BURST_PERIOD = 0.04  # s between bursts
WINDOW_S = 1.0  # the diagnostics' window of rate samples (kInputWindow)


class StragglerFeed:
    """Bursts of four IMU samples, stamped now + 0, 1, 2, 3 ms, of which the last `stale`
    repeat the first burst stamp (at or before the last one: dropped as stale), until stop()."""

    def __init__(self, pub, stale):
        self.pub = pub
        self.stale = stale
        self.running = True
        self.thread = threading.Thread(target=self._run, daemon=True)
        self.thread.start()

    def _run(self):
        while self.running and not rospy.is_shutdown():
            t0 = rospy.Time.now()
            for k in range(4):
                fresh = k < 4 - self.stale
                stamp = t0 + rospy.Duration(0.001 * k) if fresh else t0
                self.pub.publish(make_imu(stamp, (0.0, 0.0, 0.2), frame_id="body_w"))
            rospy.sleep(BURST_PERIOD)

    def stop(self):
        self.running = False
        self.thread.join()


class InputWindowTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("test_input_window")
        cls.status = NodeDiagnostics(WIN)
        Node("win").wait_ready()
        cls.imu = rospy.Publisher("/win/imu/data_raw", Imu, queue_size=1000)
        wait_connected(cls.imu)

    def test_a_quarter_lost_is_no_warning(self):
        feed = StragglerFeed(self.imu, stale=1)
        try:
            wait_for(lambda: int((self.status.get() or (0, "", {}))[2].get("dropped_stale", "0"))
                     > 0, 20.0, "stragglers counted")
            # Before a window holding stragglers has closed, OK would prove nothing: wait for
            # several windows (1 s each) to close first. Each holds a quarter of stragglers,
            # whatever the load, so the status is OK after any of them.
            time.sleep(3.0 * WINDOW_S)
            wait_for(lambda: (self.status.get() or ())[:2] == (DiagnosticStatus.OK, "propagating"),
                     20.0, "diagnostics OK with one straggler in four")
        finally:
            feed.stop()

    def test_three_quarters_lost_warn_naming_the_stragglers(self):
        feed = StragglerFeed(self.imu, stale=3)
        try:
            status = wait_for(lambda: (self.status.get() or (None,))[0] == DiagnosticStatus.WARN
                              and "rate samples of the last second were lost" in self.status.get()[1]
                              and self.status.get(), 20.0, "diagnostics WARN")
            self.assertIn("stamps at or before the previous one", status[1])
        finally:
            feed.stop()


if __name__ == "__main__":
    rostest.rosrun("attitude_propagator", "input_window", InputWindowTest)
