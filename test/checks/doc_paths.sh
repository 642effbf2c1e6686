#!/usr/bin/env bash
# The docs name files that exist: every repository path (include/..., src/..., test/...,
# config/..., ...) in the README, docs/*.md, config/*.yaml and the launch files outside code
# blocks is a file or folder of the checkout; and the commands the docs give (rosrun, roslaunch
# lines) pass no file by a path relative to the source root, which works from that folder only
# ($(rospack find attitude_propagator)/config/... works from anywhere). Reads the files only.
source "$(dirname "${BASH_SOURCE[0]}")/../../scripts/common.sh"
cd "$REPO_DIR" || exit 1
/usr/bin/python3 - <<'PY'
import glob
import os
import re
import sys

TOP = r"(?:include|src|test|config|launch|scripts|docs|bench|nodes|cfg|msg|srv|rviz)"
PATH = re.compile(r"(?<![\w./$)-])(" + TOP + r"/[\w./-]*[A-Za-z0-9])(?![\w./*<-])")
COMMAND_ARG = re.compile(r"\s(" + TOP + r"/[\w./-]+)")
files = (["README.md"] + sorted(glob.glob("docs/*.md")) + sorted(glob.glob("config/*.yaml")) +
         sorted(glob.glob("launch/*.launch") + glob.glob("launch/examples/*.launch")))
status = 0
for name in files:
    fenced = False
    for number, line in enumerate(open(name, encoding="utf-8"), 1):
        if line.lstrip().startswith("```"):
            fenced = not fenced
            continue
        if re.match(r"\s*(rosrun|roslaunch)\s", line):
            for path in COMMAND_ARG.findall(line):
                print("%s:%d: %s is relative to the source root; the command works from "
                      "anywhere with $(rospack find attitude_propagator)/%s" %
                      (name, number, path, path))
                status = 1
        if fenced:
            continue
        for path in PATH.findall(line):
            if not os.path.exists(path):
                print("%s:%d: %s does not exist" % (name, number, path))
                status = 1
sys.exit(status)
PY
