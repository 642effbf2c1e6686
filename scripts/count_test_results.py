#!/usr/bin/env python3
"""Counts the JUnit XML results in one or more folders (catkin's run_tests, the sanitized core
suite, the mutation check, the fuzz runs) and prints the closing line "N passed, M failed" (a folder without
results, or an unreadable result file, counts as a failure; the --stages folder holds only the
test command's failed stages and may be empty)."""
import argparse
import pathlib
import sys
import xml.etree.ElementTree as ET


def count_suite(suite, file_name):
    """The test cases directly in one <testsuite>. A suite may report more failures than its
    cases carry (rosunit marks a method whose unittest subTest failed as passed and counts the
    failure on the suite only); each such failure is counted too."""
    passed, failed, failures = 0, 0, []
    for case in suite.findall("testcase"):
        if case.find("skipped") is not None or case.get("status") == "notrun":
            continue
        bad = case.find("failure") is not None or case.find("error") is not None
        if bad:
            failed += 1
            failures.append(f"{file_name}: {case.get('classname')}.{case.get('name')}")
        else:
            passed += 1
    reported = int(suite.get("failures", 0) or 0) + int(suite.get("errors", 0) or 0)
    if suite.findall("testcase") and reported > failed:
        unattached = reported - failed
        failed += unattached
        failures.append(f"{file_name}: suite {suite.get('name')} reports {unattached} "
                        "failure(s) on no test case")
    return passed, failed, failures


def count(results_dir, may_be_empty=False):
    passed, failed, failures = 0, 0, []
    files = sorted(pathlib.Path(results_dir).glob("**/*.xml"))
    if not files and not may_be_empty:
        return 0, 1, [f"no test results in {results_dir}"]
    for path in files:
        try:
            root = ET.parse(path).getroot()
        except ET.ParseError as err:
            failed += 1
            failures.append(f"{path.name}: unreadable ({err})")
            continue
        for suite in root.iter("testsuite"):
            p, f, lines = count_suite(suite, path.name)
            passed, failed, failures = passed + p, failed + f, failures + lines
    return passed, failed, failures


def main():
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("results_dirs", nargs="*", metavar="results_dir")
    parser.add_argument("--stages", metavar="DIR",
                        help="failures of the test command's stages (none when all went well)")
    parser.add_argument("--extra-passed", type=int, default=0)
    parser.add_argument("--extra-failed", type=int, default=0)
    args = parser.parse_args()
    passed, failed, failures = 0, 0, []
    folders = [(d, False) for d in args.results_dirs]
    if args.stages:
        folders.append((args.stages, True))
    for results_dir, may_be_empty in folders:
        p, f, lines = count(results_dir, may_be_empty)
        passed, failed, failures = passed + p, failed + f, failures + lines
    passed += args.extra_passed
    failed += args.extra_failed
    for line in failures:
        print("FAILED:", line)
    print(f"{passed} passed, {failed} failed")
    return 0 if failed == 0 and passed > 0 else 1


if __name__ == "__main__":
    sys.exit(main())
