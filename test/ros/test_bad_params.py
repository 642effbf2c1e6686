#!/usr/bin/python3
"""A bad parameter stops the node at start with one error naming it (bad_params.test)."""
import subprocess
import unittest

import roslib.packages
import rospy
import rostest

# (private parameter, value set on the master, text the single error must contain)
CASES = [
    ("model", "bogus", "model: unknown value 'bogus'; accepted: auto kinematic dynamic"),
    ("modle", "auto", "modle: unknown parameter"),
    ("integrator", "leapfrog", "integrator: unknown value 'leapfrog'; accepted: auto euler"),
    ("integrator", "dopri5", "integrator: 'dopri5' does not drive the kinematic model"),
    ("inertia", [1.0, 1.0, 3.0], "inertia: "),
    ("inertia", [1.0, -1.0, 1.0], "inertia: invalid value [1.0, -1.0, 1.0]; accepted: 3 positive"),
    ("inertia", [1.0, 2.0], "inertia: invalid value [1.0, 2.0]"),
    ("inertia", [1.0, float("nan"), 1.0], "inertia: invalid value [1.0, nan, 1.0]"),
    ("torque_input", True, "torque_input: true needs the dynamic model"),
    ("rate_input", "gps", "rate_input: unknown value 'gps'; accepted: imu twist none"),
    ("publish_rate", -5.0, "publish_rate: invalid value -5.0; accepted: a finite number > 0"),
    ("max_dt", "soon", "max_dt: wrong type"),
    ("initial_orientation", [0, 0, 0, 0], "initial_orientation: zero quaternion"),
    ("body_frame", "world", "body_frame: equals fixed_frame"),
]


def run(command, timeout=30):
    return subprocess.run(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                          timeout=timeout, text=True)


class BadParametersTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("test_bad_params")
        cls.node = roslib.packages.find_node("attitude_propagator", "attitude_propagator_node")[0]
        cls.nodelet = roslib.packages.find_node("nodelet", "nodelet")[0]

    def test_node_refuses_each_bad_parameter(self):
        for i, (name, value, expected) in enumerate(CASES):
            with self.subTest(name=name, value=value):
                # Set on the master: roscpp reads "_name:=[1, 2]" arguments as strings.
                rospy.set_param("/bad_node_%d/%s" % (i, name), value)
                result = run([self.node, "__name:=bad_node_%d" % i])
                self.assertNotEqual(result.returncode, 0, result.stderr)
                self.assertIn(expected, result.stderr)
                errors = [line for line in result.stderr.splitlines()
                          if "[FATAL]" in line or "[ERROR]" in line]
                self.assertEqual(len(errors), 1, result.stderr)
                self.assertIn("accepted", errors[0])

    def test_nodelet_refuses_to_start(self):
        result = run([self.nodelet, "standalone", "attitude_propagator/AttitudePropagatorNodelet",
                      "__name:=bad_nodelet", "_model:=bogus"])
        self.assertNotEqual(result.returncode, 0, result.stderr)
        self.assertIn("model: unknown value 'bogus'", result.stderr)

    def test_good_parameters_start(self):
        # The same binary with valid parameters keeps running (until we stop it).
        process = subprocess.Popen([self.node, "__name:=good_node", "_model:=kinematic"],
                                   stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        try:
            rospy.wait_for_service("/good_node/reset", timeout=20.0)
            self.assertIsNone(process.poll())
        finally:
            process.terminate()
            process.wait(timeout=20)


if __name__ == "__main__":
    rostest.rosrun("attitude_propagator", "bad_params", BadParametersTest)
