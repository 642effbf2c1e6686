#!/usr/bin/python3
"""Launches on one master (launch_compose.test): each roslaunch of the package's launch files
runs with exactly the parameters it sets, whatever an earlier launch on the same master set or
the node wrote back (`demo.launch` then `demo.launch scene:=t_handle`, and the reverse), and a
propagator refusing its parameters stops alone: the other nodes of an including launch keep
running. Only demo.launch ends with the propagator.

The launches run as a user runs them (`roslaunch` against rostest's master), one after another.
Every case is its own test method (rosunit counts test methods, not subTests)."""
import os
import signal
import subprocess
import tempfile
import time
import unittest
import xml.etree.ElementTree as ET

import rosgraph
import roslaunch.config
import roslaunch.xmlloader
import rospkg
import rostest
import yaml

from ap_test_util import wait_for

NODE = "/attitude_propagator"
START_S = 60.0  # a roslaunch and the node's start on a loaded machine, with margin


def package_path(*parts):
    return os.path.join(rospkg.RosPack().get_path("attitude_propagator"), *parts)


def master():
    return rosgraph.Master("/launch_compose_test")


def get_param(name):
    try:
        return master().getParam(name)
    except rosgraph.masterapi.MasterError:
        return None


def node_registered(name):
    try:
        master().lookupNode(name)
        return True
    except rosgraph.masterapi.MasterError:
        return False


def expected_parameters(scene):
    """config/default.yaml with the scene's file over it: what demo.launch scene:=... runs."""
    with open(package_path("config", "default.yaml")) as f:
        params = yaml.safe_load(f)
    with open(package_path("config", scene + ".yaml")) as f:
        params.update(yaml.safe_load(f))
    return params


class Launch:
    """One roslaunch as a user starts it, stopped with SIGINT (Ctrl-C)."""

    def __init__(self, args):
        self.log = tempfile.TemporaryFile(mode="w+")
        self.process = subprocess.Popen(["roslaunch"] + args, stdout=self.log,
                                        stderr=subprocess.STDOUT, start_new_session=True)

    def output(self):
        self.log.seek(0)
        return self.log.read()

    def alive(self):
        return self.process.poll() is None

    def stop(self):
        if self.alive():
            os.killpg(self.process.pid, signal.SIGINT)
            try:
                self.process.wait(timeout=30)
            except subprocess.TimeoutExpired:
                os.killpg(self.process.pid, signal.SIGKILL)
                self.process.wait()
        # Nodes roslaunch could not stop leave stale registrations; the next launch replaces them.


class LaunchComposeTest(unittest.TestCase):
    def run_demo(self, scene):
        """demo.launch scene:=<scene>: the node starts with default.yaml + the scene's file."""
        # resolved_model is what the node writes once it runs: forget the last launch's.
        for name in ("resolved_model", "resolved_integrator"):
            try:
                master().deleteParam(NODE + "/" + name)
            except rosgraph.masterapi.MasterError:
                pass
        launch = Launch(["attitude_propagator", "demo.launch", "scene:=" + scene])
        try:
            expected = expected_parameters(scene)
            model = "dynamic" if expected["model"] == "dynamic" else "kinematic"
            try:
                wait_for(lambda: get_param(NODE + "/resolved_model") is not None or
                         not launch.alive(), START_S, "the node to start (%s)" % scene)
                self.assertTrue(launch.alive(), launch.output())
                self.assertEqual(get_param(NODE + "/resolved_model"), model, launch.output())
            except AssertionError:
                raise AssertionError("demo.launch scene:=%s did not start:\n%s" %
                                     (scene, launch.output()))
            self.assertNotIn("FATAL", launch.output())
            params = get_param(NODE)
            for name, value in expected.items():
                self.assertEqual(params.get(name), value,
                                 "demo.launch scene:=%s: %s" % (scene, name))
        finally:
            launch.stop()

    def test_coning_then_t_handle(self):
        """`demo.launch` then `demo.launch scene:=t_handle`: the second leaves cf4 behind."""
        self.run_demo("coning")
        self.run_demo("t_handle")

    def test_t_handle_then_coning(self):
        """The reverse order: the second leaves the inertia and the dynamic model behind."""
        self.run_demo("t_handle")
        self.run_demo("coning")

    def test_spinning_top_then_coning(self):
        self.run_demo("spinning_top")
        self.run_demo("coning")

    def test_a_refused_parameter_stops_only_the_propagator(self):
        """A bringup including attitude_propagator.launch with a bad parameter: the node
        refuses to start (FATAL naming the parameter), the bringup's other nodes keep running."""
        tmp = tempfile.mkdtemp()
        bad = os.path.join(tmp, "bad.yaml")
        with open(bad, "w") as f:
            f.write("model: kinematic\nintegrator: dopri5\n")
        bringup = os.path.join(tmp, "bringup.launch")
        launch_xml = ET.Element("launch")
        include = ET.SubElement(launch_xml, "include", file=package_path(
            "launch", "attitude_propagator.launch"))
        ET.SubElement(include, "arg", name="config", value=bad)
        ET.SubElement(launch_xml, "node", pkg="tf2_ros", type="static_transform_publisher",
                      name="bystander", args="0 0 0 0 0 0 map bystander_frame")
        ET.ElementTree(launch_xml).write(bringup)
        launch = Launch([bringup])
        try:
            wait_for(lambda: "does not drive" in launch.output() or not launch.alive(),
                     START_S, "the propagator's refusal")
            self.assertIn("integrator: 'dopri5' does not drive", launch.output())
            wait_for(lambda: node_registered("/bystander") or not launch.alive(), START_S,
                     "the bystander node")
            time.sleep(3.0)  # roslaunch acts on a required node's exit within a second
            self.assertTrue(launch.alive(), "roslaunch ended:\n" + launch.output())
            self.assertTrue(node_registered("/bystander"), launch.output())
        finally:
            launch.stop()

    def test_only_the_demo_is_required(self):
        """required= as roslaunch reads it: the propagator ends the demo only."""
        def required(path, args=()):
            config = roslaunch.config.ROSLaunchConfig()
            roslaunch.xmlloader.XmlLoader().load(path, config, argv=["roslaunch"] + list(args),
                                                 verbose=False)
            return [n.required for n in config.nodes
                    if n.type == "attitude_propagator_node" or
                    (n.package == "nodelet" and "AttitudePropagatorNodelet" in n.args)]
        self.assertEqual(required(package_path("launch", "demo.launch")), [True])
        self.assertEqual(required(package_path("launch", "demo.launch"),
                                  ["use_nodelet:=true"]), [True])
        self.assertEqual(required(package_path("launch", "attitude_propagator.launch")),
                         [False])
        self.assertEqual(required(package_path("launch", "attitude_propagator.launch"),
                                  ["use_nodelet:=true"]), [False])
        self.assertEqual(required(package_path("launch", "attitude_propagator.launch"),
                                  ["required:=true"]), [True])
        for example in ("standalone", "imu_on_robot", "body_root"):
            self.assertEqual(required(package_path("launch", "examples", example + ".launch")),
                             [False], example)


if __name__ == "__main__":
    rostest.rosrun("attitude_propagator", "launch_compose", LaunchComposeTest)
