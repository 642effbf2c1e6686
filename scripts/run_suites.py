#!/usr/bin/env python3
"""Runs the package's tests as catkin's `run_tests` would (the same commands, the same JUnit
results), but two at a time where that is safe: the gtest suites, the repository checks and
the rostests that judge nothing by the clock share the cores; the rostests whose verdict
depends on wall time or CPU run afterwards, one at a time, with nothing beside them.

    run_suites.py BUILD [--jobs N] [--only NAME ...] [--list]

BUILD is the catkin workspace's build folder. The commands come from the targets catkin
generated for each test (build/attitude_propagator/CMakeFiles/_run_tests_<package>_<kind>_<name>
.dir/build.make): CMakeLists.txt stays the one list of tests. NAME selects tests by name as
printed by --list (e.g. `core_tests`, `attack.test`, `layer_dependencies`); each NAME must
select one, or nothing runs. Every rostest starts its own master on a free port, so two run at
once without sharing one. Exit status: 0 when every command ran (the verdicts are in the JUnit
files, which scripts/count_test_results.py counts), 1 when one did not, 2 on a usage error.
"""
import argparse
import concurrent.futures
import pathlib
import re
import subprocess
import sys
import threading
import time

PACKAGE = "attitude_propagator"
# Rostests whose verdict depends on the clock or the CPU: they run alone, after the rest.
SERIAL = {
    "attack.test": "hostile input in wall time; a flood must be answered within its time limits",
    "fix_flood.test": "a burst of fixes must outrun the node's replays to overflow its queue",
    "input_window.test": "judges one-second windows of wall time (lost samples per window)",
    "node_habits.test": "wall time: diagnostics of samples lost while it publishes at rate",
    "param_limits.test": "the extreme accepted parameters must run in bounded CPU",
    "tf_conflict.test": "the 2 s clearance of a conflict is measured in wall time",
    "two_clocks.test": "two /clock publishers paced in wall time must interleave their ticks",
}
# Started first so that the two workers end together: the longest commands.
FIRST = ("bag_tools_tests", "core_tests", "node_vs_bag.test", "kinematic.test")


class Test:
    def __init__(self, kind, name, command, directory):
        self.kind, self.name, self.command, self.directory = kind, name, command, directory


def discover(build):
    """The test commands catkin generated for the package, by kind (gtest, rostest, checks)."""
    folder = build / PACKAGE / "CMakeFiles"
    prefix = f"_run_tests_{PACKAGE}_"
    tests = []
    for make_file in sorted(folder.glob(f"{prefix}*.dir/build.make")):
        target = make_file.parent.name[: -len(".dir")][len(prefix):]
        kind, _, name = target.partition("_")
        if not name:
            continue  # the aggregate targets (gtest, rostest, checks)
        for line in make_file.read_text().splitlines():
            match = re.match(r"^\tcd (\S+) && (.*run_tests\.py .*)$", line)
            if match:
                name = re.sub(r"^test_ros_", "", name)  # a rostest by its file's name
                tests.append(Test(kind, name, match.group(2), match.group(1)))
                break
    return tests


def run(test, lock):
    start = time.monotonic()
    done = subprocess.run(test.command, shell=True, cwd=test.directory, stdout=subprocess.PIPE,
                          stderr=subprocess.STDOUT, text=True, errors="replace")
    seconds = time.monotonic() - start
    failed = re.search(r"FAILURES: [1-9]|ERRORS: [1-9]|\[  FAILED  \]|^FAILED|failed to run",
                       done.stdout, re.M)
    verdict = "failed" if failed or done.returncode != 0 else "ok"
    with lock:
        print(f"  {verdict:6} {test.kind:7} {test.name} ({seconds:.0f} s)", flush=True)
        if verdict != "ok":
            print("\n".join("    " + l for l in done.stdout.splitlines()[-25:]), flush=True)
    return done.returncode == 0


def main():
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("build")
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--only", action="append", default=[])
    parser.add_argument("--list", action="store_true")
    args = parser.parse_args()
    tests = discover(pathlib.Path(args.build).resolve())
    if not tests:
        print(f"run_suites: no tests configured in {args.build} (catkin_make tests first)")
        return 2
    names = {t.name for t in tests}
    stale = sorted(set(SERIAL) - names)
    if stale:  # the list must track the tests
        print(f"run_suites: SERIAL names rostests that do not exist: {' '.join(stale)}")
        return 2
    if args.list:
        for t in tests:
            where = "alone: " + SERIAL[t.name] if t.name in SERIAL else f"{args.jobs} at a time"
            print(f"{t.name:28} {t.kind:8} {where}")
        return 0
    unknown = [n for n in args.only if n not in names]
    if unknown:
        print(f"run_suites: no test named {' '.join(unknown)} (--list shows them)")
        return 2
    if args.only:
        tests = [t for t in tests if t.name in args.only]
    shared = sorted((t for t in tests if t.name not in SERIAL),
                    key=lambda t: FIRST.index(t.name) if t.name in FIRST else len(FIRST))
    alone = [t for t in tests if t.name in SERIAL]
    lock = threading.Lock()
    start = time.monotonic()
    print(f"run_suites: {len(shared)} tests {args.jobs} at a time, then {len(alone)} alone "
          "(they judge by the clock)", flush=True)
    with concurrent.futures.ThreadPoolExecutor(max_workers=max(args.jobs, 1)) as pool:
        ran = list(pool.map(lambda t: run(t, lock), shared))
    ran += [run(t, lock) for t in alone]
    print(f"run_suites: {len(ran)} tests in {time.monotonic() - start:.0f} s", flush=True)
    return 0 if all(ran) else 1


if __name__ == "__main__":
    sys.exit(main())
