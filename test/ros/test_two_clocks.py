#!/usr/bin/python3
"""Two /clock publishers taking turns (two_clocks.test): ROS time's rule of docs/node.md, one
reset at most, the later timeline followed, the other publisher named once in a warning and
in the diagnostics."""
import time
import unittest

import rospy
import rostest
from rosgraph_msgs.msg import Log
from sensor_msgs.msg import Imu
from std_msgs.msg import Float64

from ap_test_util import (NS_PER_S, NodeDiagnostics, RosoutLines, SimClock, TfRecorder,
                          make_imu, time_ns, wait_connected, wait_for)

LATER_S = 100  # the test's own clock; the stale one runs 5 s behind
APART_S = 5
TICKS = 300  # 3 s at 100 Hz


class TwoClocksTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("test_two_clocks")
        cls.rosout = RosoutLines()
        cls.tf = TfRecorder(["world_dyn", "world_kin"])
        cls.diag = {ns: NodeDiagnostics("/%s/attitude_propagator" % ns) for ns in ("dyn", "kin")}
        cls.imu = rospy.Publisher("/kin/imu/data_raw", Imu, queue_size=10000)
        cls.start = rospy.Publisher("/stale_clock/start", Float64, queue_size=1, latch=True)
        wait_connected(cls.imu)
        wait_connected(cls.start)
        cls.clock = SimClock(2, LATER_S * NS_PER_S)
        for ns in ("dyn", "kin"):
            wait_for(lambda ns=ns: cls.diag[ns].get() is not None, 20.0, ns + " diagnostics")
        # The later timeline alone first, then both for 3 s: ticks every 10 ms, an IMU message
        # at every tick of the later one.
        begin = time.monotonic()
        for k in range(TICKS):
            now_ns = LATER_S * NS_PER_S + k * 10 ** 7
            cls.clock.set(now_ns)
            cls.imu.publish(make_imu(time_ns(now_ns), (0.0, 0.0, 0.5), "body_kin"))
            if k == 20:
                cls.start.publish(Float64(data=(now_ns / NS_PER_S) - APART_S + 0.01))
            time.sleep(max(0.0, begin + 0.01 * (k + 1) - time.monotonic()))
        time.sleep(1.0)  # diagnostics every 0.2 s of wall time

    def values(self, ns):
        return wait_for(lambda: self.diag[ns].get(), 5.0, ns + " diagnostics")

    def test_one_reset_at_most_and_the_conflict_named(self):
        for ns in ("dyn", "kin"):
            level, message, values = self.values(ns)
            self.assertLessEqual(int(values["resets"]), 1, (ns, values))
            self.assertEqual(int(values["clock_conflicts"]), 1, (ns, values))
            # Named while the stale publisher went on; it stopped with the test's clock, so
            # the last status may have settled already: the counter is what stays.
            if "clock_sources" in values:
                self.assertIn("/stale_clock", values["clock_sources"])
                self.assertIn("two timelines", message)

    def test_one_warning_names_the_second_publisher(self):
        for ns in ("dyn", "kin"):
            name = "/%s/attitude_propagator" % ns
            lines = self.rosout.of(name, Log.WARN, "two timelines")
            self.assertEqual(len(lines), 1, lines)
            self.assertIn("/stale_clock", lines[0])
            self.assertIn("/two_clocks", lines[0])  # this test node, by its test-name
            self.assertLessEqual(len(self.rosout.of(name, Log.WARN, "ROS time jumped back")), 1)

    def test_tf_stamps_go_back_once_at_most(self):
        for world in ("world_dyn", "world_kin"):
            stamps = [t.header.stamp.to_nsec() for t in self.tf.transforms
                      if t.header.frame_id == world or t.child_frame_id == world]
            self.assertGreater(len(stamps), 100, world)
            back = sum(1 for a, b in zip(stamps, stamps[1:]) if b < a)
            self.assertLessEqual(back, 1, world)
            self.assertGreaterEqual(max(stamps), (LATER_S + 2) * NS_PER_S, world)

    def test_rates_on_the_later_timeline_are_used(self):
        _, _, values = self.values("kin")
        # Refused only between the jump back and the next tick of the later timeline.
        self.assertLessEqual(int(values["rejected_future"]), 2, values)
        self.assertGreaterEqual(int(values["accepted"]), TICKS - 3, values)


if __name__ == "__main__":
    rostest.rosrun("attitude_propagator", "two_clocks", TwoClocksTest)
