#!/usr/bin/python3
"""Frames from a parameter file (launch_frames.test): attitude_propagator.launch
config:=<file> runs with the file's frames when no frame argument is given (as a node and as a
nodelet), and with the arguments' when they are given. The node writes back what it runs with
(resolved_model once it has started), so the parameters read after that are the ones in use."""
import unittest

import rospy
import rostest

from ap_test_util import wait_for

FRAMES = ("world_frame", "fixed_frame", "body_frame", "fix_frame")
FROM_FILE = {"world_frame": "ned", "fixed_frame": "odom", "body_frame": "imu_body",
             "fix_frame": "imu_fix"}
FROM_ARGS = {"world_frame": "nwu", "fixed_frame": "map", "body_frame": "imu2",
             "fix_frame": "imu2_fix"}


class LaunchFramesTest(unittest.TestCase):
    def frames_of(self, node):
        wait_for(lambda: rospy.has_param(node + "/resolved_model"), 60.0,
                 "%s to start" % node)
        return {name: rospy.get_param(node + "/" + name) for name in FRAMES}

    def test_the_files_frames_win_without_arguments(self):
        self.assertEqual(self.frames_of("/a/attitude_propagator"), FROM_FILE)

    def test_the_files_frames_win_without_arguments_nodelet(self):
        self.assertEqual(self.frames_of("/c/attitude_propagator"), FROM_FILE)

    def test_given_arguments_win_over_the_file(self):
        self.assertEqual(self.frames_of("/b/attitude_propagator"), FROM_ARGS)


if __name__ == "__main__":
    rospy.init_node("launch_frames_test")
    rostest.rosrun("attitude_propagator", "launch_frames", LaunchFramesTest)
