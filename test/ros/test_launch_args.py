#!/usr/bin/python3
"""Launch arguments (launch_args.test): each <arg> a launch file declares has a doc= text and a
default (or a fixed value), so `roslaunch --ros-args` explains every one and none is required;
a file that takes the rate input's topic takes the output topics too.
The <arg> elements inside an <include> pass values on; they are not declarations."""
import glob
import os
import subprocess
import unittest
import xml.etree.ElementTree as ET

import rospkg
import rostest

from ap_test_util import check_each


def launch_files():
    root = rospkg.RosPack().get_path("attitude_propagator")
    return sorted(glob.glob(os.path.join(root, "launch", "*.launch")) +
                  glob.glob(os.path.join(root, "launch", "examples", "*.launch")))


def declared_args(path):
    """(name, attributes) of every <arg> that declares an argument (not one in an <include>)."""
    tree = ET.parse(path)
    inside_include = {id(arg) for include in tree.iter("include") for arg in include.iter("arg")}
    return [(arg.get("name"), arg.attrib) for arg in tree.iter("arg")
            if id(arg) not in inside_include]


class LaunchArgsTest(unittest.TestCase):
    def test_there_are_launch_files(self):
        names = {os.path.basename(p) for p in launch_files()}
        self.assertTrue({"attitude_propagator.launch", "demo.launch", "standalone.launch",
                         "imu_on_robot.launch", "body_root.launch"} <= names, names)

    def test_every_arg_has_a_doc(self):
        def check(path):
            missing = [name for name, attrs in declared_args(path) if not attrs.get("doc")]
            self.assertEqual(missing, [], "args without doc= in %s" % path)
        check_each(self, launch_files(), check)

    def test_no_arg_is_required(self):
        def check(path):
            required = [name for name, attrs in declared_args(path)
                        if "default" not in attrs and "value" not in attrs]
            self.assertEqual(required, [], "args without a default in %s" % path)
        check_each(self, launch_files(), check)

    def test_an_input_topic_arg_comes_with_the_output_topic_args(self):
        """A launch file that takes the rate input's topic takes the outputs' too (with doc=),
        so a user who points the input at /imu/data can move the output off it."""
        def check(path):
            names = {name for name, _ in declared_args(path)}
            if "imu_topic" in names:
                self.assertTrue({"imu_out_topic", "state_topic"} <= names,
                                "%s takes imu_topic but not imu_out_topic, state_topic" % path)
        check_each(self, launch_files(), check)

    def test_the_frames_default_to_the_config_files(self):
        """attitude_propagator.launch's frame args leave the config file's frames (default
        `(config)`, not empty: roslaunch --ros-args shows an empty default as required), and
        each doc= names the node's own default for a file that sets none."""
        path = [p for p in launch_files() if p.endswith("/attitude_propagator.launch")][0]
        args = dict(declared_args(path))
        for name, default in (("fixed_frame", "world"), ("body_frame", "base_link"),
                              ("world_frame", "enu"), ("fix_frame", "body_frame")):
            self.assertEqual(args[name]["default"], "(config)", name)
            self.assertIn("default: the config file's %s, else %s" % (name, default),
                          args[name]["doc"], name)

    def test_ros_args_lists_no_required_argument(self):
        """What a user sees: `roslaunch --ros-args` names no argument as required."""
        def check(path):
            out = subprocess.run(["roslaunch", "--ros-args", path], stdout=subprocess.PIPE,
                                 stderr=subprocess.STDOUT, text=True, timeout=60).stdout
            self.assertNotIn("Required Arguments", out, out)
            self.assertNotIn("undocumented", out, out)
            self.assertIn("Optional Arguments", out, out)
        check_each(self, launch_files(), check)


if __name__ == "__main__":
    rostest.rosrun("attitude_propagator", "launch_args", LaunchArgsTest)
