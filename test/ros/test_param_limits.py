#!/usr/bin/python3
"""Parameter values that would make the node crash, hang or burn a core are refused at start
(exit status 1, one FATAL naming the parameter and what is accepted); the extreme values that
are accepted run in bounded CPU and stop on SIGINT (param_limits.test)."""
import math
import os
import signal
import subprocess
import tempfile
import time
import unittest

import roslib.packages
import rospy
import rostest
from attitude_propagator.msg import AttitudeState
from geometry_msgs.msg import Vector3, WrenchStamped

from ap_test_util import Recorder, check_each, wait_connected, wait_for

BODY = {"inertia": [1.0, 2.0, 3.0]}
HUGE_RATE = [1e200, 1e200, 1e200]

# (parameters set on the master, the parameter the FATAL must name)
REFUSED = [
    (dict(BODY, initial_angular_velocity=HUGE_RATE), "initial_angular_velocity"),
    (dict(BODY, integrator="rk4", initial_angular_velocity=HUGE_RATE),
     "initial_angular_velocity"),
    (dict(BODY, initial_angular_velocity=[1e5, 1e5, 0.0]), "initial_angular_velocity"),
    (dict(BODY, integrator="rk4", max_step=1e-12), "max_step"),
    (dict(BODY, integrator="rk4", max_step=1e-5, max_dt=60.0), "max_step"),
    (dict(BODY, integrator="dopri5", tolerance=1e-300), "tolerance"),
    (dict(BODY, integrator="dopri5", tolerance=0.5), "tolerance"),
    (dict(publish_rate=1e9), "publish_rate"),
    (dict(BODY, publish_rate=1e9), "publish_rate"),
    (dict(inertia=[1e200, 1e200, 1e200]), "inertia"),
    (dict(inertia=[1e-300, 1e-300, 1e-300]), "inertia"),
    (dict(angular_velocity_stddev=-0.5), "angular_velocity_stddev"),
    (dict(angular_velocity_stddev=1e308), "angular_velocity_stddev"),
    (dict(max_dt=1e9), "max_dt"),
    (dict(BODY, torque_input=True, torque_timeout=1e12), "torque_timeout"),
    (dict(initial_orientation=[float("inf"), 0.0, 0.0, 1.0]), "initial_orientation"),
    (dict(gyro_bias=[1e200, 0.0, 0.0]), "gyro_bias"),
]

# Accepted extremes: the most work per second the validator lets through.
ACCEPTED = [
    dict(BODY, integrator="rk4", rate_input="none", publish_rate=1000.0, max_step=1e-5,
         initial_angular_velocity=[0.0, 100.0, 0.1]),
    # (At 1e5 rad/s dopri5 at 1e-12 needs about half a core: test_a_torque_spin_up_...)
    dict(BODY, integrator="dopri5", rate_input="none", tolerance=1e-12, publish_rate=1000.0,
         initial_angular_velocity=[0.0, 1e4, 0.0]),
    dict(BODY, integrator="implicit_midpoint", rate_input="none", publish_rate=1000.0,
         max_step=1e-5, initial_angular_velocity=[0.0, 1e5, 0.0]),
]
MEASURE_S = 3.0        # wall seconds of CPU measurement
MAX_CPU_SHARE = 0.5    # of one core
MAX_STOP_S = 2.0       # SIGINT to exit (one second asked, margin for a loaded machine)


def cpu_seconds(pid):
    """utime + stime of a process (/proc/<pid>/stat fields 14 and 15)."""
    with open("/proc/%d/stat" % pid) as f:
        fields = f.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


class ParameterLimitsTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("test_param_limits")
        cls.node = roslib.packages.find_node("attitude_propagator", "attitude_propagator_node")[0]

    def set_params(self, name, params):
        for key, value in params.items():
            rospy.set_param("/%s/%s" % (name, key), value)

    def test_refused_at_start(self):
        def check(case):
            i, (params, name) = case
            node = "limit_node_%d" % i
            self.set_params(node, params)
            result = subprocess.run([self.node, "__name:=" + node], stdout=subprocess.PIPE,
                                    stderr=subprocess.PIPE, timeout=30, text=True)
            self.assertEqual(result.returncode, 1, result.stderr)
            fatal = [line for line in result.stderr.splitlines() if "[FATAL]" in line]
            self.assertEqual(len(fatal), 1, result.stderr)
            self.assertIn("refusing to start: %s: " % name, fatal[0])
            self.assertIn("accepted", fatal[0])
        check_each(self, list(enumerate(REFUSED)), check)

    def test_accepted_extremes_run_in_bounded_cpu_and_stop_on_sigint(self):
        def check(case):
            i, params = case
            node = "extreme_node_%d" % i
            self.set_params(node, params)
            log = tempfile.TemporaryFile(mode="w+")
            process = subprocess.Popen([self.node, "__name:=" + node],
                                       stdout=subprocess.DEVNULL, stderr=log, text=True)
            try:
                rospy.wait_for_service("/%s/reset" % node, timeout=20.0)
                time.sleep(1.0)  # past start-up
                cpu0, wall0 = cpu_seconds(process.pid), time.monotonic()
                time.sleep(MEASURE_S)
                share = (cpu_seconds(process.pid) - cpu0) / (time.monotonic() - wall0)
                self.assertIsNone(process.poll(), "the node died")
                self.assertLess(share, MAX_CPU_SHARE, "CPU share of one core")
                start = time.monotonic()
                process.send_signal(signal.SIGINT)
                process.wait(timeout=10.0)
                stopped = time.monotonic() - start
                print("%s: CPU %.3f of a core, stopped %.3f s after SIGINT"
                      % (node, share, stopped), flush=True)
                self.assertLess(stopped, MAX_STOP_S, "seconds from SIGINT to exit")
            finally:
                if process.poll() is None:
                    process.kill()
                    process.wait()
                log.seek(0)
                print("%s: %s" % (node, log.read()[-2000:]), flush=True)
                log.close()

        check_each(self, list(enumerate(ACCEPTED)), check)
    def test_a_torque_spin_up_does_not_hang_the_node(self):
        # dopri5 and an accepted torque (1e6 N m per axis on moments 1, 2, 3) spin the body to
        # |w| ~ 1e6 rad/s within a second, so each adaptive grid step needs many sub-steps.
        # Whatever the node does about it (fail the steps, skip ticks), it must stay with ROS
        # time and answer SIGINT promptly.
        node = "spin_node"
        self.set_params(node, dict(BODY, integrator="dopri5", rate_input="none",
                                   torque_input=True, publish_rate=100.0))
        states = Recorder("/attitude_state", AttitudeState)
        torque = rospy.Publisher("/torque", WrenchStamped, queue_size=10)
        process = subprocess.Popen([self.node, "__name:=" + node], stdout=subprocess.DEVNULL,
                                   stderr=subprocess.DEVNULL)
        try:
            rospy.wait_for_service("/%s/reset" % node, timeout=20.0)
            wait_connected(torque)
            wait_for(lambda: states.count() > 0, 10.0, "a first state")
            msg = WrenchStamped()
            msg.header.stamp = rospy.Time.now()
            msg.header.frame_id = "base_link"
            msg.wrench.torque = Vector3(1e6, 1e6, 1e6)
            torque.publish(msg)
            time.sleep(5.0)
            with states.lock:
                latest = states.messages[-1]
            lag = (rospy.Time.now() - latest.header.stamp).to_sec()
            start = time.monotonic()
            process.send_signal(signal.SIGINT)
            process.wait(timeout=60.0)
            stopped = time.monotonic() - start
            print("%s: lag %.3f s behind ROS time, |w| %.3g rad/s, stopped %.3f s after SIGINT"
                  % (node, lag, math.sqrt(latest.angular_velocity.x ** 2 +
                                          latest.angular_velocity.y ** 2 +
                                          latest.angular_velocity.z ** 2), stopped), flush=True)
            self.assertLess(lag, 1.0, "seconds the published state lags ROS time")
            self.assertLess(stopped, MAX_STOP_S, "seconds from SIGINT to exit")
        finally:
            if process.poll() is None:
                process.kill()
                process.wait()


if __name__ == "__main__":
    rostest.rosrun("attitude_propagator", "param_limits", ParameterLimitsTest)
