#!/usr/bin/env python3
"""Runs one repository check (a test/checks/*.sh script) and writes its outcome as a JUnit
result with one test case, so that catkin's run_tests counts it next to the gtest and rostest
results. The check's output goes to the terminal and, when it fails, into the result.

    junit.py CHECK.sh RESULT.xml
"""
import os
import pathlib
import subprocess
import sys
import time
import xml.etree.ElementTree as ET


def main():
    check, result = pathlib.Path(sys.argv[1]), pathlib.Path(sys.argv[2])
    name = check.stem
    start = time.monotonic()
    # catkin runs this in the environment of the workspace under test: the checks use it
    # instead of sourcing the workspace that scripts/common.sh would pick.
    env = dict(os.environ, AP_CATKIN_ENV="1")
    run = subprocess.run(["bash", str(check)], stdout=subprocess.PIPE,
                         stderr=subprocess.STDOUT, text=True, errors="replace", env=env)
    elapsed = time.monotonic() - start
    sys.stdout.write(run.stdout)

    failed = run.returncode != 0
    suite = ET.Element("testsuite", name="checks", tests="1", failures=str(int(failed)),
                       errors="0", time="%.3f" % elapsed)
    case = ET.SubElement(suite, "testcase", classname="checks", name=name,
                         time="%.3f" % elapsed)
    if failed:
        failure = ET.SubElement(case, "failure",
                                message="%s exited with %d" % (check.name, run.returncode))
        failure.text = run.stdout
    result.parent.mkdir(parents=True, exist_ok=True)
    ET.ElementTree(suite).write(result, encoding="utf-8", xml_declaration=True)
    print("check %s: %s" % (name, "FAILED" if failed else "passed"))
    return run.returncode


if __name__ == "__main__":
    sys.exit(main())
