#!/usr/bin/python3
"""A flood of late fixes (fix_flood.test): every fix sent is accounted for by the node's
counters, those lost in its subscriber queue too (fixes_lost, docs/node.md)."""
import time
import unittest

import rospy
import rostest
from geometry_msgs.msg import PoseWithCovarianceStamped
from sensor_msgs.msg import Imu

from ap_test_util import (NS_PER_S, NodeDiagnostics, make_imu, make_pose_fix, time_ns,
                          wait_connected, wait_for)

RATES = 4000  # 4 s of 1 kHz rates, ending now
FIXES = 2000  # one burst, stamped within the last 3.5 s
COUNTERS = ("fixes_accepted", "fixes_rejected_gate", "fixes_too_old", "fixes_bad_quaternion",
            "fixes_bad_covariance", "fixes_queue_full", "fixes_future", "fixes_over_budget",
            "fixes_refused", "fixes_pending", "fixes_lost")


class FixFloodTest(unittest.TestCase):
    def test_every_fix_is_accounted_for(self):
        rospy.init_node("test_fix_flood")
        diag = NodeDiagnostics("/ff/attitude_propagator")
        imu = rospy.Publisher("/ff/imu/data_raw", Imu, queue_size=100000)
        fix = rospy.Publisher("/ff/orientation_fix", PoseWithCovarianceStamped,
                              queue_size=100000)
        wait_connected(imu)
        wait_connected(fix)
        now = rospy.Time.now().to_nsec()
        start = now - 4 * NS_PER_S
        # The first fix starts the history of rates kept for late fixes (none is kept before).
        fix.publish(make_pose_fix(time_ns(start), "world_ff", (0.0, 0.0, 0.0, 1.0)))
        time.sleep(0.5)
        for k in range(RATES):
            imu.publish(make_imu(time_ns(start + k * 10 ** 6), (0.0, 0.0, 0.1), "body_ff"))
        time.sleep(1.0)  # the rates in before the fixes
        for k in range(FIXES):
            stamp = start + NS_PER_S // 2 + k * (3 * NS_PER_S // FIXES)
            fix.publish(make_pose_fix(time_ns(stamp), "world_ff", (0.0, 0.0, 0.0, 1.0)))

        def account():
            latest = diag.get()
            if latest is None:
                return None
            values = latest[2]
            if any(c not in values for c in COUNTERS):
                return None
            return sum(int(values[c]) for c in COUNTERS), values
        # Settled: the account stops changing once the node has caught up.
        wait_for(lambda: account() and account()[0] == FIXES + 1, 60.0,
                 "every fix accounted for (now %s)" % (account(),))
        total, values = account()
        print("fix_flood: %d fixes sent, %s lost before the node, %s accepted, %s too old, "
              "%s over the replay budget"
              % (FIXES + 1, values["fixes_lost"], values["fixes_accepted"],
                 values["fixes_too_old"], values["fixes_over_budget"]))
        self.assertEqual(total, FIXES + 1, values)
        # Each fix replays seconds of 1 kHz rates: the replays one second of rates may cost
        # (replay_budget.h) run out long before the burst does, and the rest is refused.
        self.assertGreater(int(values["fixes_over_budget"]), 0,
                           "the replays were not bounded: %s" % values)


if __name__ == "__main__":
    rostest.rosrun("attitude_propagator", "fix_flood", FixFloodTest)
