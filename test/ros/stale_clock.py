#!/usr/bin/python3
"""A second /clock publisher for two_clocks.test (a stale simulator): on a start (std_msgs/
Float64 on ~start, in seconds) it publishes `ticks` ticks from there, 0.01 s apart, every
0.01 s of wall time, then stops."""
import time

import rospy
from rosgraph_msgs.msg import Clock
from std_msgs.msg import Float64

NS_PER_S = 10 ** 9


def main():
    rospy.init_node("stale_clock")
    pub = rospy.Publisher("/clock", Clock, queue_size=10000)
    starts = []
    rospy.Subscriber("~start", Float64, lambda msg: starts.append(msg.data), queue_size=10)
    ticks = rospy.get_param("~ticks", 300)
    while not rospy.is_shutdown():
        if not starts:
            time.sleep(0.01)  # wall time: ROS time is what this node publishes
            continue
        start_ns = int(round(starts.pop(0) * NS_PER_S))
        begin = time.monotonic()
        for k in range(ticks):
            pub.publish(Clock(clock=rospy.Time(0, 0) + rospy.Duration(0, start_ns + k * 10 ** 7)))
            time.sleep(max(0.0, begin + 0.01 * (k + 1) - time.monotonic()))


if __name__ == "__main__":
    main()
