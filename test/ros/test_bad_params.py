#!/usr/bin/python3
"""Parameters at start (bad_params.test): a bad parameter stops the node with one error naming
it; good parameters give a node that works with them: their values on the parameter server,
the configured frames on attitude_state and /tf, the configured publish rate, states that
follow the closed form of the configured motion, and diagnostics OK.

Every case is its own test method: rosunit's XML reports a failing unittest subTest as a
failure of the suite only, with the test method marked passed, so a subTest failure would
not be counted against any test."""
import math
import os
import subprocess
import tempfile
import time
import unittest

import roslib.packages
import rospkg
import rospy
import rostest
import yaml
from attitude_propagator.cfg import AttitudePropagatorConfig as ReconfigureConfig
from attitude_propagator.msg import AttitudeState
from diagnostic_msgs.msg import DiagnosticStatus
from sensor_msgs.msg import Imu

from ap_test_util import (NS_PER_S, NodeDiagnostics, Recorder, TfRecorder, as_tuple, axis_angle,
                          make_imu, qconj, qmul, rotation_angle, time_ns, wait_connected,
                          wait_for)

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
    # Numbers that YAML 1.1 reads as strings (no dot, or no sign in the exponent), as a YAML
    # file gives them to the parameter server.
    ("inertia", yaml.safe_load("[1.0e12, 2.0e12, 2.0e12]"),
     "inertia: '1.0e12' is a string to YAML; write 1.0e+12"),
    ("max_dt", yaml.safe_load("1e-3"), "max_dt: '1e-3' is a string to YAML; write 1.0e-3"),
    ("max_dt", "0.5", "max_dt: '0.5' is a string to YAML; write 0.5 without quotes"),
    ("initial_orientation", [0, 0, 0, 0], "initial_orientation: zero quaternion"),
    ("accel_stddev", 0.0, "accel_stddev: invalid value 0.0; accepted: a number > 0"),
    ("body_frame", "world", "body_frame: equals fixed_frame"),
    ("body_frame", "base link", "body_frame: frame id 'base link' refused"),
    ("input_queue_size", 2.5, "input_queue_size: wrong type, got '2.5'; accepted: an integer"),
    ("output_queue_size", 0, "output_queue_size: invalid value 0; accepted: an integer in [1, "
     "1000000]"),
    ("gyro_bias_stddev", 300.0, "gyro_bias_stddev: invalid value 300.0; accepted: a finite "
     "number >= 0 and at most 10 (rad/s)"),
    ("max_future", 0.0, "max_future: invalid value 0.0; accepted: a number > 0 and at most 3600"),
    ("time_jump_threshold", 0.0, "time_jump_threshold: invalid value 0.0; accepted: a number in "
     "[1e-3, 3600] (s)"),
]

# A sphere turning at 0.5 rad/s about its z axis from a quarter turn about x: the exact model's
# state at t is q0 (x) Exp((t - t_anchor) w), so consecutive states differ by Exp(w / rate).
DYNAMIC = {
    "model": "dynamic",
    "rate_input": "none",
    "inertia": [1.5, 1.5, 1.5],
    "initial_orientation": [math.sin(math.pi / 4), 0.0, 0.0, math.cos(math.pi / 4)],
    "initial_angular_velocity": [0.0, 0.0, 0.5],
    "publish_rate": 20.0,
    "max_dt": 0.5,
    "tolerance": 1e-6,
    "torque_timeout": 2.0,
    "fixed_frame": "good_world",
    "body_frame": "good_body",
    "diagnostic_period": 0.5,
}
PERIOD_NS = 50 * 10 ** 6  # 1 / publish_rate

# IMU rates integrated by exp (exact for a constant rate), tf published reversed.
KINEMATIC = {
    "model": "kinematic",
    "integrator": "exp",
    "fixed_frame": "good_world_k",
    "body_frame": "good_body_k",
    "reverse_tf": True,
    "max_dt": 0.25,
    "angular_velocity_stddev": 0.02,
    "diagnostic_period": 0.5,
}
IMU_RATE = (0.0, 0.3, -0.4)
IMU_STEP_NS = 20 * 10 ** 6  # 50 Hz

TOL = 1e-9  # closed forms; only round-off remains


def run(command, timeout=30):
    return subprocess.run(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                          timeout=timeout, text=True)


def default_parameters():
    """config/default.yaml: every parameter with its default (checked against the struct by
    the core tests)."""
    path = os.path.join(rospkg.RosPack().get_path("attitude_propagator"), "config",
                        "default.yaml")
    with open(path) as f:
        return yaml.safe_load(f)


class RunningNode:
    """The node binary in namespace ns with private parameters set on the master first;
    terminated on leaving the `with` block. Its output goes to a file (a pipe nobody reads
    could fill and block it)."""

    def __init__(self, binary, ns, name, parameters):
        self.private = "/%s/%s" % (ns, name)
        for key, value in parameters.items():
            rospy.set_param("%s/%s" % (self.private, key), value)
        self.log = tempfile.TemporaryFile(mode="w+")
        self.process = subprocess.Popen([binary, "__ns:=/" + ns, "__name:=" + name],
                                        stdout=self.log, stderr=subprocess.STDOUT, text=True)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.process.terminate()
        try:
            self.process.wait(timeout=20)
        except subprocess.TimeoutExpired:
            self.process.kill()
            self.process.wait()
        self.log.close()

    def output(self):
        self.log.flush()
        self.log.seek(0)
        return self.log.read()

    def running(self):
        return self.process.poll() is None


class BadParametersTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("test_bad_params")
        cls.node = roslib.packages.find_node("attitude_propagator", "attitude_propagator_node")[0]
        cls.nodelet = roslib.packages.find_node("nodelet", "nodelet")[0]

    def expect_refused(self, index, name, value, expected):
        # Set on the master: roscpp reads "_name:=[1, 2]" arguments as strings.
        rospy.set_param("/bad_node_%d/%s" % (index, name), value)
        result = run([self.node, "__name:=bad_node_%d" % index])
        self.assertNotEqual(result.returncode, 0, result.stderr)
        self.assertIn(expected, result.stderr)
        errors = [line for line in result.stderr.splitlines()
                  if "[FATAL]" in line or "[ERROR]" in line]
        self.assertEqual(len(errors), 1, result.stderr)
        self.assertIn("accepted", errors[0])

    def test_max_dt_minimum_is_the_reconfigure_minimum(self):
        """One minimum for max_dt: the validator refuses just below the slider's minimum in
        cfg/AttitudePropagator.cfg and starts at it."""
        minimum = ReconfigureConfig.min["max_dt"]
        self.expect_refused(90, "max_dt", minimum * (1 - 1e-9), "max_dt: invalid value")
        self.expect_refused(91, "max_dt", minimum * (1 - 1e-9), "accepted: a number in [%s, 60]"
                            % ("%g" % minimum).replace("e-0", "e-"))
        with RunningNode(self.node, "min_dt", "node", {"max_dt": minimum}) as node:
            wait_for(lambda: rospy.get_param("/min_dt/node/resolved_model", None), 20.0,
                     "the node started with max_dt %g" % minimum)
            self.assertEqual(rospy.get_param("/min_dt/node/max_dt"), minimum)
            self.assertTrue(node.running(), node.output())

    def test_an_output_on_an_input_topic_refuses_to_start(self):
        """A feedback loop: the rate input remapped onto the imu/data output (what
        standalone.launch imu_topic:=/imu/data does) stops the node with one FATAL naming
        both."""
        result = run([self.node, "__name:=loop_node", "imu/data_raw:=/imu/data"])
        self.assertNotEqual(result.returncode, 0, result.stderr)
        errors = [line for line in result.stderr.splitlines()
                  if "[FATAL]" in line or "[ERROR]" in line]
        self.assertEqual(len(errors), 1, result.stderr)
        self.assertIn("output imu/data and input imu/data_raw are both /imu/data", errors[0])

    def test_frames_with_a_leading_slash_are_read_without_it(self):
        """tf1's `body_frame: /imu`: the node starts with `imu`, written back so, and warns once
        naming the parameter."""
        with RunningNode(self.node, "slash", "node",
                         {"body_frame": "/slash_imu", "fixed_frame": "/slash_world"}) as node:
            wait_for(lambda: rospy.get_param("/slash/node/resolved_model", None), 20.0,
                     "the node started")
            self.assertEqual(rospy.get_param("/slash/node/body_frame"), "slash_imu")
            self.assertEqual(rospy.get_param("/slash/node/fixed_frame"), "slash_world")
            self.assertTrue(node.running(), node.output())
            self.assertIn("body_frame: frame id '/slash_imu' has a leading '/'", node.output())

    def test_a_node_name_that_is_no_ros_name_is_refused_with_one_fatal(self):
        # name:='a b' on roslaunch's command line: roscpp throws InvalidNameException in
        # ros::init; the node names it in one FATAL line and exits 1 instead of aborting.
        result = run([self.node, "__name:=a b"])
        self.assertEqual(result.returncode, 1, result.stderr)
        self.assertIn("invalid node name, namespace or remapping", result.stderr)
        self.assertNotIn("terminate called", result.stderr)

    def test_nodelet_refuses_to_start(self):
        result = run([self.nodelet, "standalone", "attitude_propagator/AttitudePropagatorNodelet",
                      "__name:=bad_nodelet", "_model:=bogus"])
        self.assertNotEqual(result.returncode, 0, result.stderr)
        self.assertIn("model: unknown value 'bogus'", result.stderr)

    def assert_parameters_on_server(self, private, given):
        """The node writes back every parameter in use: the given values unchanged, the rest
        at config/default.yaml's defaults."""
        expected = dict(default_parameters())
        expected.update({k: v for k, v in given.items() if k != "diagnostic_period"})
        for name, value in expected.items():
            self.assertEqual(rospy.get_param("%s/%s" % (private, name), "<not set>"), value, name)

    def assert_diagnostics_ok(self, diagnostics, model):
        status = wait_for(lambda: (diagnostics.get() or (None,))[0] == DiagnosticStatus.OK
                          and diagnostics.get(), 10.0, "diagnostics OK")
        _, message, values = status
        self.assertEqual(message, "propagating")
        self.assertEqual(values["model"], model)
        for counter in ("rejected_non_finite", "rejected_out_of_range", "failed_steps",
                        "callback_errors", "gaps", "resets"):
            self.assertEqual(values[counter], "0", counter)

    def test_good_dynamic_parameters_give_a_working_node(self):
        ns, name = "good_dyn", "node"
        states = Recorder("/%s/attitude_state" % ns, AttitudeState)
        tf = TfRecorder([DYNAMIC["fixed_frame"], DYNAMIC["body_frame"]])
        diagnostics = NodeDiagnostics("/%s/%s" % (ns, name))
        with RunningNode(self.node, ns, name, DYNAMIC) as node:
            wait_for(lambda: states.count() >= 10, 20.0, "10 attitude states")
            # The publish rate in wall time over 2 s: measured 20.0 Hz (one message is 0.5 Hz);
            # bound 4 Hz, for a loaded machine. The stamps below are checked exactly.
            first, start = states.count(), time.monotonic()
            time.sleep(2.0)
            rate = (states.count() - first) / (time.monotonic() - start)
            self.assertLess(abs(rate - 20.0), 4.0, "published at %.1f Hz, configured 20" % rate)
            self.assert_diagnostics_ok(diagnostics, "exact_sphere")
            self.assert_parameters_on_server(node.private, DYNAMIC)
            self.assertTrue(node.running(), node.output())
            log = node.output()
        self.assertNotIn("[ERROR]", log)
        self.assertNotIn("[WARN]", log)

        with states.lock:
            messages = list(states.messages)
        stamps = [m.header.stamp.to_nsec() for m in messages]
        # On the grid of 1 / publish_rate, every grid stamp once.
        self.assertTrue(all(s % PERIOD_NS == 0 for s in stamps), stamps[:10])
        self.assertEqual([b - a for a, b in zip(stamps, stamps[1:])],
                         [PERIOD_NS] * (len(stamps) - 1))
        q0 = tuple(DYNAMIC["initial_orientation"])
        w = DYNAMIC["initial_angular_velocity"]
        step = axis_angle(w, math.sqrt(sum(c * c for c in w)) * PERIOD_NS / NS_PER_S)
        for before, after in zip(messages, messages[1:]):
            self.assertLess(rotation_angle(as_tuple(after.orientation),
                                           qmul(as_tuple(before.orientation), step)), TOL)
        for m in messages:
            self.assertEqual(m.header.frame_id, DYNAMIC["fixed_frame"])
            self.assertEqual(m.child_frame_id, DYNAMIC["body_frame"])
            self.assertEqual(m.model, "exact_sphere")
            self.assertEqual((m.angular_velocity.x, m.angular_velocity.y, m.angular_velocity.z),
                             tuple(w))
            # E = 1/2 I |w|^2 with I = 1.5.
            self.assertAlmostEqual(m.kinetic_energy, 0.5 * 1.5 * 0.25, delta=1e-15)
            # q0^c q(t) turns about body z only: the initial orientation is the one given.
            d = qmul(qconj(q0), as_tuple(m.orientation))
            self.assertLess(math.hypot(d[0], d[1]), TOL, d)
        # /tf: fixed_frame -> body_frame at the states' stamps, with their rotations.
        for m in messages[:-1]:
            transforms = tf.at(m.header.stamp)
            self.assertEqual(len(transforms), 1, m.header.stamp)
            t = transforms[0]
            self.assertEqual((t.header.frame_id, t.child_frame_id),
                             (DYNAMIC["fixed_frame"], DYNAMIC["body_frame"]))
            self.assertLess(rotation_angle(as_tuple(t.transform.rotation),
                                           as_tuple(m.orientation)), TOL)

    def test_good_kinematic_parameters_give_a_working_node(self):
        ns, name = "good_kin", "node"
        states = Recorder("/%s/attitude_state" % ns, AttitudeState)
        tf = TfRecorder([KINEMATIC["fixed_frame"], KINEMATIC["body_frame"]])
        diagnostics = NodeDiagnostics("/%s/%s" % (ns, name))
        imu = rospy.Publisher("/%s/imu/data_raw" % ns, Imu, queue_size=1000)
        with RunningNode(self.node, ns, name, KINEMATIC) as node:
            wait_connected(imu)
            wait_for(lambda: states.sub.get_num_connections() > 0, 20.0, "attitude_state")
            # 2 s of samples at 50 Hz, stamped on their own grid, sent in wall time (the grid's
            # stamps at most one step behind it, as a sensor's would be).
            start_ns = rospy.Time.now().to_nsec() // IMU_STEP_NS * IMU_STEP_NS
            sent = []
            for k in range(100):
                sent.append(time_ns(start_ns + k * IMU_STEP_NS))
                imu.publish(make_imu(sent[-1], IMU_RATE, frame_id=KINEMATIC["body_frame"]))
                if k == 75:
                    self.assert_diagnostics_ok(diagnostics, "kinematic")
                time.sleep(IMU_STEP_NS / NS_PER_S)
            last = states.wait_at(sent[-1])
            self.assert_parameters_on_server(node.private, KINEMATIC)
            self.assertTrue(node.running(), node.output())
            log = node.output()
        self.assertNotIn("[ERROR]", log)
        self.assertNotIn("[WARN]", log)

        first = states.wait_at(sent[0])
        self.assertEqual(states.count(), len(sent))  # one state per sample
        # exp is exact for a constant rate: q(t) = q(t0) (x) Exp((t - t0) w).
        seconds = (sent[-1] - sent[0]).to_sec()
        norm = math.sqrt(sum(c * c for c in IMU_RATE))
        expected = qmul(as_tuple(first.orientation), axis_angle(IMU_RATE, norm * seconds))
        self.assertLess(rotation_angle(as_tuple(last.orientation), expected), TOL)
        for stamp in sent:
            m = states.at(stamp)[0]
            self.assertEqual((m.header.frame_id, m.child_frame_id),
                             (KINEMATIC["fixed_frame"], KINEMATIC["body_frame"]))
            self.assertEqual(m.integrator, "exp")
            # reverse_tf: body_frame -> fixed_frame, the inverse rotation.
            transforms = tf.at(stamp)
            self.assertEqual(len(transforms), 1, stamp)
            t = transforms[0]
            self.assertEqual((t.header.frame_id, t.child_frame_id),
                             (KINEMATIC["body_frame"], KINEMATIC["fixed_frame"]))
            self.assertLess(rotation_angle(as_tuple(t.transform.rotation),
                                           qconj(as_tuple(m.orientation))), TOL)


def _refusal_test(index, name, value, expected):
    def test(self):
        self.expect_refused(index, name, value, expected)
    test.__doc__ = "%s = %r stops the node with one error" % (name, value)
    return test


# One plain test method per bad value, so that each counts (and fails) on its own.
for _index, (_name, _value, _expected) in enumerate(CASES):
    setattr(BadParametersTest, "test_refuses_%02d_%s" % (_index, _name),
            _refusal_test(_index, _name, _value, _expected))


if __name__ == "__main__":
    rostest.rosrun("attitude_propagator", "bad_params", BadParametersTest)
