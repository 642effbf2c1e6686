#!/usr/bin/env python3
"""The mutation check's driver (scripts/mutants.sh and scripts/mutants_ros.sh run it): plants
each mutant of a list in test/mutants/ in its source file, one at a time, and runs the tests
that must notice it.

  mutate.py list [--list NAME ...] [--only ID ...] [--root DIR]
                      the mutants of the lists (default: all); each must apply (exit 1 if not)
  mutate.py sync REPO SCRATCH     copy the sources the plain CMake build needs to SCRATCH
  mutate.py sync --package REPO SCRATCH   copy the whole package (but .git) to SCRATCH
  mutate.py schemata REPO SCRATCH BUILD [--list NAME ...] [--only ID ...] [--jobs N]
                      write each source file's mutants into one schema (schemata.py) in
                      SCRATCH, compiled with BUILD's commands; a mutant the compiler refuses
                      in a schema is built on its own by `run` (BUILD/schemata.json says which)
  mutate.py run BUILD RESULTS [--list NAME ...] [--only ID ...] [--jobs N] [--timeout S]
                [--bag-timeout S]
                      the gtest lists (default all three: mutants.txt,
                      mutants_messages.txt, mutants_tools.txt) against the plain CMake build
                      of test/mutants/CMakeLists.txt
  mutate.py ros WORKSPACE RESULTS [--only ID ...] [--timeout S] [--root REPO]
                      mutants_ros.txt in a scratch catkin workspace (scripts/mutants_ros.sh):
                      a mutant in a schema (`schemata --list mutants_ros.txt` on the
                      workspace's copy) runs its rostests with AP_MUTANT set, which roslaunch
                      passes on to the node; any other is written in, built and restored

The lists, by the files their mutants live in and the tests that must notice them:
  mutants.txt           src/core, src/config   the core suite (test/core)
  mutants_messages.txt  src/messages           the message layer's suite (test/messages)
  mutants_tools.txt     src/tools              the bag tools' suite (test/bag), run on the tools
                                               rebuilt with the mutant
  mutants_ros.txt       src/ros                the rostests named by the mutant's `tests:`

In the gtest lists most mutants cost no compile at all: `schemata` writes every mutant of a file
into one copy of it, each behind a run-time switch (AP_MUTANT=<number>), so one build of the
scratch copy serves them all, and each such mutant is one run of its suite with its number in
the environment. A mutant the compiler refuses inside a schema is built on its own: its mutated
file (the checkout's file with the mutant applied) goes to a
slot source in the build folder (mutant_slot<N>.cpp, one per parallel worker), which is
compiled alone and linked ahead of the unchanged archives, so that the linker takes the mutated
definitions and never pulls the original object. Each mutant thus costs one compile and one
link per program that holds its file, and there is nothing to restore. The node's list is
written into schemata in the scratch catkin workspace's copy of the package the same way; a
mutant of it the compiler refuses there is planted in the copy and restored after it.

A mutant is killed when its tests fail on it (the first failing test is recorded), crash, or
run past the timeout; it survives when they pass. A mutant whose original text does not occur
exactly once, or whose mutated file does not build, is an error of the list. The results go to
RESULTS/mutants.xml (mutants_ros.xml for the node's list; JUnit: one test case per mutant, a
survivor or an error fails).
"""
import argparse
import concurrent.futures
import dataclasses
import hashlib
import json
import os
import pathlib
import re
import signal
import subprocess
import sys
import threading
import time
import xml.etree.ElementTree as ET

import schemata

HERE = pathlib.Path(__file__).resolve().parent
KEYS = ("id", "file", "bug", "original", "mutant", "tests", "first")
# Each list and where its mutants may live.
LISTS = {
    "mutants.txt": re.compile(r"^src/(core|core/(numerics|time|estimation|models)|config)/[A-Za-z0-9_]+\.cpp$"),
    "mutants_messages.txt": re.compile(r"^src/messages/[A-Za-z0-9_]+\.cpp$"),
    "mutants_tools.txt": re.compile(r"^src/tools/[A-Za-z0-9_]+\.cpp$"),
    "mutants_ros.txt": re.compile(r"^src/ros/[A-Za-z0-9_]+\.cpp$"),
}
GTEST_LISTS = ("mutants.txt", "mutants_messages.txt", "mutants_tools.txt")
# What `run` runs unless told: every gtest list (the test command runs them all).
DEFAULT_LISTS = GTEST_LISTS
ROS_LIST = "mutants_ros.txt"
# The bag tools by their main files; every other file of src/tools is linked into both (an
# object a tool does not use costs nothing). alignment.cpp is also compiled into the bag suite.
TOOL_NAMES = ("propagate_bag", "evaluate_bag_core")
BAG_SUITE_FILES = ("alignment",)
# What the build and the suites read: the sources, the headers, the suites, this folder, the
# files the parameter and counter tests compare against (the tables in docs/parameters.md and
# docs/node.md, the summary's drops in docs/bag_tools.md, config/*.yaml),
# evaluate_bag (the bag suite runs it) and package.xml (the tools' --version).
SYNCED = ("src/core", "src/config", "src/messages", "src/tools", "include", "test/core",
          "test/messages", "test/bag", "test/mutants", "config", "nodes")
SYNCED_FILES = ("docs/parameters.md", "docs/node.md", "docs/bag_tools.md", "package.xml")


class ListError(Exception):
    """The mutant list is malformed, or a mutant does not apply to the code."""


@dataclasses.dataclass
class Mutant:
    id: str
    file: str
    bug: str
    pairs: list  # (original, replacement) in turn
    line: int  # of the block in the list
    list_name: str = "mutants.txt"
    tests: tuple = ()  # the rostests that must notice it (the node's list)
    first: tuple = ()  # gtest cases run before the whole suite (a gtest list's; a hint of speed)

    @property
    def group(self):
        """core, messages, tools or ros: the folder of its file."""
        folder = self.file.split("/")[1]
        return "core" if folder == "config" else folder

    def apply(self, text):
        for original, replacement in self.pairs:
            count = text.count(original)
            if count != 1:
                raise ListError(
                    f"{self.list_name}:{self.line}: {self.id}: the original text occurs {count} "
                    f"times in {self.file} "
                    f"(must be exactly once): {original!r}")
            text = text.replace(original, replacement)
        return text


# ---- The list ---------------------------------------------------------------------------------

def parse_list(path):
    """Blocks of 'key: value' lines separated by blank lines; '#' starts a comment line; a line
    starting with '|' continues the previous value on a new line (its text after the '|')."""
    blocks, block, start = [], [], 0
    for number, raw in enumerate(path.read_text().splitlines(), start=1):
        line = raw.rstrip()
        if line.startswith("#"):
            continue
        if not line:
            if block:
                blocks.append((start, block))
            block = []
            continue
        if not block:
            start = number
        if line.startswith("|"):
            if not block:
                raise ListError(f"{path.name}:{number}: a continuation line starts a block")
            key, value = block[-1]
            block[-1] = (key, value + "\n" + line[1:])
            continue
        key, colon, value = line.partition(":")
        if not colon or key not in KEYS:
            raise ListError(f"{path.name}:{number}: expected one of {', '.join(KEYS)}: {line!r}")
        block.append((key, value.strip()))
    if block:
        blocks.append((start, block))
    mutants, seen = [], set()
    for start, block in blocks:
        mutant = make_mutant(path.name, start, block)
        if mutant.id in seen:
            raise ListError(f"{path.name}:{start}: duplicate id {mutant.id}")
        seen.add(mutant.id)
        mutants.append(mutant)
    return mutants


def make_mutant(name, start, block):
    where = f"{name}:{start}"
    single = {}
    pairs, pending = [], None
    for key, value in block:
        if key in ("id", "file", "bug", "tests", "first"):
            if key in single:
                raise ListError(f"{where}: '{key}' given twice")
            single[key] = value
        elif key == "original":
            if pending is not None:
                raise ListError(f"{where}: 'original' without its 'mutant'")
            pending = value
        else:
            if pending is None:
                raise ListError(f"{where}: 'mutant' without an 'original' before it")
            if value == pending:
                raise ListError(f"{where}: the mutant equals the original")
            pairs.append((pending, value))
            pending = None
    missing = [k for k in ("id", "file", "bug") if not single.get(k)]
    if missing or pending is not None or not pairs:
        raise ListError(f"{where}: needs id, file, bug and original/mutant pairs")
    if not re.fullmatch(r"[a-z0-9][a-z0-9-]*", single["id"]):
        raise ListError(f"{where}: id {single['id']!r}: lower case, digits and '-' only")
    if not LISTS[name].match(single["file"]):
        raise ListError(f"{where}: {single['file']}: not a file of this list "
                        f"({LISTS[name].pattern})")
    if any(not original for original, _ in pairs):
        raise ListError(f"{where}: empty original text")
    tests = tuple(single.get("tests", "").split())
    if (name == ROS_LIST) != bool(tests):
        raise ListError(f"{where}: 'tests' is given in {ROS_LIST}, and only there")
    bad = [t for t in tests if not re.fullmatch(r"[A-Za-z0-9_]+\.test", t)]
    if bad:
        raise ListError(f"{where}: tests: {' '.join(bad)}: not rostest file names")
    first = tuple(single.get("first", "").split())
    if first and name not in GTEST_LISTS:
        raise ListError(f"{where}: 'first' names gtest cases: only in {', '.join(GTEST_LISTS)}")
    bad = [t for t in first if not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*\.[A-Za-z_][A-Za-z0-9_/]*", t)]
    if bad:
        raise ListError(f"{where}: first: {' '.join(bad)}: not gtest case names (Suite.Name)")
    return Mutant(single["id"], single["file"], single["bug"], pairs, start, name, tests, first)


def read_lists(root, names):
    """The mutants of the named lists, in turn; an id is unique across all lists."""
    mutants, seen = [], {}
    for name in names:
        if name not in LISTS:
            raise ListError(f"no list {name} (the lists: {', '.join(LISTS)})")
        for mutant in parse_list(root / "test" / "mutants" / name):
            if mutant.id in seen:
                raise ListError(f"{name}:{mutant.line}: id {mutant.id} is also in {seen[mutant.id]}")
            seen[mutant.id] = name
            mutants.append(mutant)
    return mutants


def select(mutants, only):
    if not only:
        return mutants
    known = {m.id for m in mutants}
    unknown = [i for i in only if i not in known]
    if unknown:
        raise ListError("no mutant with id " + ", ".join(unknown))
    return [m for m in mutants if m.id in only]


# ---- The scratch copy -------------------------------------------------------------------------

def sync(repo, scratch, package=False):
    """Makes SCRATCH hold exactly the files the build reads (package: every file outside the
    hidden folders, .git and the scripts' .workspace),
    writing only those whose content differs (unchanged files keep their times, so the build
    stays incremental)."""
    wanted = {}
    folders = SYNCED
    if package:
        folders = sorted(p.name for p in repo.iterdir()
                         if p.is_dir() and not p.name.startswith("."))
        for path in repo.iterdir():
            if path.is_file():
                wanted[path.relative_to(repo)] = path
    for folder in folders:
        for path in (repo / folder).rglob("*"):
            if path.is_file() and "__pycache__" not in path.parts:
                wanted[path.relative_to(repo)] = path
    for name in () if package else SYNCED_FILES:
        wanted[pathlib.Path(name)] = repo / name
    written = 0
    for relative, source in wanted.items():
        target = scratch / relative
        data = source.read_bytes()
        mode = source.stat().st_mode & 0o777  # programs stay programs (nodes, rostest scripts)
        if target.is_file() and target.read_bytes() == data:
            if target.stat().st_mode & 0o777 != mode:
                target.chmod(mode)
            continue
        target.parent.mkdir(parents=True, exist_ok=True)
        target.write_bytes(data)
        target.chmod(mode)
        written += 1
    removed = 0
    for folder in folders:
        for path in sorted((scratch / folder).rglob("*"), reverse=True):
            if path.is_file() and path.relative_to(scratch) not in wanted:
                path.unlink()
                removed += 1
    print(f"mutants: scratch copy in {scratch}: {written} files written, {removed} removed")

# ---- Schemata ---------------------------------------------------------------------------------

def numbered(mutants):
    """Each mutant's switch number: its place in the run's list."""
    return {m.id: n for n, m in enumerate(mutants)}


def compile_entry(build, source, launcher=True):
    """The command CMake generated to compile SOURCE (AP_COMPILER_LAUNCHER in front unless
    told), and its folder."""
    commands = json.loads((build / "compile_commands.json").read_text())
    entry = next((c for c in commands if pathlib.Path(c["file"]) == source), None)
    if entry is None:
        return None
    command = entry["command"]
    prefix = os.environ.get("AP_COMPILER_LAUNCHER", "") if launcher else ""
    if prefix and not command.startswith(prefix):
        command = f"{prefix} {command}"
    return command, entry["directory"]


# Errors a switch causes by itself, never as a consequence of another error: a switch in a
# constant expression, and one whose two texts differ in type.
SELF_CONTAINED = ("constexpr", "constant expression", "static assertion failed",
                  "have different types")


def refused_lines(output, source):
    """The lines of SOURCE that the compiler's errors pin on a switch: those the first error
    names (its own line and the context before it; later errors may only follow from the
    first), and those of every error of a self-contained kind."""
    # By its name alone: with CCACHE_BASEDIR the compiler is given, and names, relative paths.
    pattern = re.compile(r"(?:^|[\s/])" + re.escape(source.name) + r":(\d+):")
    named, block, errors = set(), [], 0
    for line in output.splitlines():
        block += [int(n) for n in pattern.findall(line)]
        if " error: " in line or line.startswith("error:"):
            errors += 1
            if errors == 1 or any(kind in line for kind in SELF_CONTAINED):
                named.update(block)
            block = []
    return named


# The compiler's verdicts on schemata, kept between runs like the compiler cache (beside it,
# outside the checkout): checking a file's schema costs compiles, the verdict is a function of
# the inputs below, and a fresh clone of the same sources would otherwise pay them again.
VERDICTS = pathlib.Path(os.environ.get("AP_SCHEMATA_CACHE") or pathlib.Path(
    os.environ.get("XDG_CACHE_HOME") or pathlib.Path.home() / ".cache") /
    "attitude_propagator_schemata")


def verdict_key(repo, scratch, build, file, wraps, check):
    """What decides which switches the compiler refuses: the file, its switches, the headers of
    the checkout, the compile command (with the folders written as names) and the compiler."""
    digest = hashlib.sha256()
    digest.update(file.encode())
    digest.update((repo / file).read_bytes())
    for w in wraps:
        digest.update(f"{w.mutant_id} {w.start} {w.end} {w.text()}".encode())
    digest.update((HERE / "schemata.py").read_bytes())  # the schema's prelude
    for header in sorted(p for folder in ("include", "src", "test", "msg", "srv", "cfg")
                         for p in (repo / folder).rglob("*")
                         if p.is_file() and p.suffix in (".h", ".msg", ".srv", ".cfg")):
        digest.update(str(header.relative_to(repo)).encode())
        digest.update(header.read_bytes())
    for folder, name in ((scratch, "SCRATCH"), (build, "BUILD"), (repo, "REPO")):
        check = check.replace(str(folder), name)
    digest.update(check.encode())
    compiler = check.split()[0]
    version = subprocess.run([compiler, "--version"], stdout=subprocess.PIPE,
                             stderr=subprocess.DEVNULL, text=True).stdout
    digest.update(version.encode())
    return digest.hexdigest()


def schema_for_file(repo, scratch, build, file, mutants, numbers):
    """Writes FILE's schema into SCRATCH and compiles it, or takes the compiler's verdict on it
    from an earlier run (VERDICTS); the mutants left out (id: why)."""
    text = (repo / file).read_text()
    source = scratch / file
    left_out, wraps = {}, []
    for m in mutants:
        planned = schemata.plan(text, numbers[m.id], m.id, m.pairs)
        if planned is None:
            left_out[m.id] = "no expression or statement holds the change"
        elif schemata.overlapping(wraps, planned):
            left_out[m.id] = "overlaps another mutant's switch"
        else:
            wraps += planned
    entry = compile_entry(build, source)
    if entry is None:
        for w in wraps:
            left_out[w.mutant_id] = f"{build} has no compile command for {file}"
        source.write_text(text)
        return left_out
    (build / f"schemata_{source.stem}.log").unlink(missing_ok=True)
    # Checked without code generation (what refuses a switch is found before it); the build
    # compiles the schema that passes.
    check = re.sub(r" -o \S+", " -fsyntax-only", compile_entry(build, source, False)[0], count=1)
    key = verdict_key(repo, scratch, build, file, wraps, check)
    known = VERDICTS / f"{key}.json"
    if known.is_file():
        refused = json.loads(known.read_text())
        left_out.update(refused)
        kept = [w for w in wraps if w.mutant_id not in refused]
        source.write_text(schemata.build(text, kept)[0] if kept else text)
        return left_out
    verdict, lasting = compile_schema(text, source, build, entry, check, wraps)
    if lasting:
        VERDICTS.mkdir(parents=True, exist_ok=True)
        partial = known.with_suffix(f".{os.getpid()}.partial")
        partial.write_text(json.dumps(verdict))
        partial.replace(known)
    left_out.update(verdict)
    return left_out


def compile_schema(text, source, build, entry, check, wraps):
    """Compiles FILE's schema, leaving out each switch the compiler refuses, until it compiles;
    writes the schema that compiles (or the original text) to SOURCE. The switches left out
    (id: why), and whether that verdict lasts (not when a header was missing)."""
    left_out, lasting = {}, True
    for _ in range(len(wraps) + 1):
        if not wraps:
            break
        schema, spans = schemata.build(text, wraps)
        kinds = {w.mutant_id: w.kind for w in wraps}
        source.write_text(schema)
        done = subprocess.run(check, shell=True, cwd=entry[1], stdout=subprocess.PIPE,
                              stderr=subprocess.STDOUT, text=True, errors="replace")
        if done.returncode == 0:
            return left_out, lasting
        with open(build / f"schemata_{source.stem}.log", "a") as log:  # why, for the reader
            log.write(done.stdout)
        named = refused_lines(done.stdout, source)
        refused = {i for i, ranges in spans.items()
                   if any(a <= n <= b for n in named for a, b in ranges)}
        if "fatal error" in done.stdout:  # a header missing: nothing here can be judged
            refused, lasting = set(spans), False
        if not refused:  # the error names no switch: most likely a statement switch that put
            # a declaration in a block of its own, so the nearest one before the error goes
            first = min(named, default=None)
            before = [(ranges[-1][1], i) for i, ranges in spans.items()
                      if first is not None and kinds[i] == "statement" and ranges[0][0] < first]
            refused = {max(before)[1]} if before else set(spans)
        for i in refused:
            left_out[i] = "the compiler refuses it in a schema"
        wraps = [w for w in wraps if w.mutant_id not in refused]
    for w in wraps:
        left_out[w.mutant_id] = "the schema did not compile"
    source.write_text(text)
    return left_out, lasting


def command_schemata(args):
    repo, scratch = pathlib.Path(args.repo).resolve(), pathlib.Path(args.scratch).resolve()
    build = pathlib.Path(args.build).resolve()
    mutants = select(read_lists(repo, args.list or DEFAULT_LISTS), args.only)
    numbers = numbered(mutants)
    by_file = {}
    for m in mutants:
        by_file.setdefault(m.file, []).append(m)
    start = time.monotonic()
    with concurrent.futures.ThreadPoolExecutor(max_workers=args.jobs) as pool:
        futures = {f: pool.submit(schema_for_file, repo, scratch, build, f, ms, numbers)
                   for f, ms in by_file.items()}
        left_out = {}
        for f in by_file:
            left_out.update(futures[f].result())
    in_schema = [m.id for m in mutants if m.id not in left_out]
    (build / "schemata.json").write_text(json.dumps(
        {"numbers": numbers, "in_schema": in_schema, "on_their_own": left_out}, indent=1))
    print(f"mutants: {len(in_schema)} of {len(in_schema) + len(left_out)} mutants in the schemata "
          f"of {len(by_file)} files ({time.monotonic() - start:.0f} s); "
          f"{len(left_out)} built on their own")
    for i, why in left_out.items():
        print(f"  on its own: {i}: {why}")
    return 0


def read_schemata(build):
    path = build / "schemata.json"
    if not path.is_file():
        return {}, set()
    data = json.loads(path.read_text())
    return data["numbers"], set(data["in_schema"])


# ---- Running ----------------------------------------------------------------------------------

@dataclasses.dataclass
class Outcome:
    mutant: Mutant
    verdict: str  # killed, survived, error
    detail: str
    build_seconds: float = 0.0
    run_seconds: float = 0.0


def run_command(command, directory):
    """Runs a build command: None, or the lines that say why it failed."""
    done = subprocess.run(command, shell=True, cwd=directory, stdout=subprocess.PIPE,
                          stderr=subprocess.STDOUT, text=True)
    if done.returncode == 0:
        return None
    lines = done.stdout.splitlines()
    errors = [line for line in lines if "error" in line] or lines
    return "\n".join(errors[:10])


class Slot:
    """One worker's mutant source in the build folder, with the commands CMake generated to
    compile it and to link each program that may hold it ahead of the archives."""

    def __init__(self, build, index):
        self.build = build
        self.index = index
        self.source = build / f"mutant_slot{index}.cpp"
        self.tools = build / f"slot{index}"  # this slot's propagate_bag and evaluate_bag_core
        self.compile = compile_entry(build, self.source)
        if self.compile is None:
            raise ListError(f"{build} has no slot {index}: configure it with MUTANT_SLOTS "
                            "at least --jobs (the Unix Makefiles generator)")

    def link_command(self, target):
        link = self.build / "CMakeFiles" / f"{target}.dir" / "link.txt"
        if not link.is_file():
            raise ListError(f"{self.build} has no target {target}: configure it with "
                            "MUTANTS_MESSAGE_INCLUDE for the message layer and the tools")
        return link.read_text().strip()

    def programs(self, mutant):
        """(targets to link, suite to run, environment) for the mutant's group."""
        n = self.index
        if mutant.group == "core":
            return [f"core_tests_slot{n}"], self.build / f"core_tests_slot{n}", {}
        if mutant.group == "messages":
            return [f"messages_tests_slot{n}"], self.build / f"messages_tests_slot{n}", {}
        stem = pathlib.Path(mutant.file).stem
        targets, environment = [], {}
        for tool in TOOL_NAMES:
            variable = "AP_" + tool.upper()
            if stem in TOOL_NAMES and stem != tool:  # the other tool's main file
                environment[variable] = str(self.build / "tools" / tool)
                continue
            targets.append(f"{tool}_slot{n}_{'main' if stem == tool else 'lib'}")
            environment[variable] = str(self.tools / tool)
        suite = self.build / "bag_tools_tests_mutants"
        if stem in BAG_SUITE_FILES:
            targets.append(f"bag_tools_tests_slot{n}")
            suite = self.build / f"bag_tools_tests_slot{n}"
        return targets, suite, environment

    def output_of(self, target):
        """Where a target's program is written: a tool into the slot's folder."""
        tool = next((t for t in TOOL_NAMES if target.startswith(t + "_slot")), None)
        return self.tools / tool if tool else self.build / target

    def build_mutant(self, text, targets):
        self.source.write_text(text)
        problem = run_command(*self.compile)
        for target in targets:
            if problem is not None:
                break
            self.output_of(target).unlink(missing_ok=True)  # a failed link leaves nothing stale
            problem = run_command(self.link_command(target), str(self.build))
        return problem


def run_suite(binary, cwd, timeout, fail_fast, environment=None, only=()):
    """Runs the suite (`only`: those cases alone): (passed, why it failed, seconds)."""
    command = [str(binary), "--gtest_color=no"] + (["--gtest_fail_fast"] if fail_fast else [])
    if only:
        command.append("--gtest_filter=" + ":".join(only))
    env = dict(os.environ, **(environment or {}))
    start = time.monotonic()
    process = subprocess.Popen(command, cwd=cwd, stdout=subprocess.PIPE,
                               stderr=subprocess.STDOUT, text=True, env=env,
                               start_new_session=True)
    try:
        output, _ = process.communicate(timeout=timeout)
        timed_out = False
    except subprocess.TimeoutExpired:
        # The suite we started and the programs it runs: its own process group.
        os.killpg(process.pid, signal.SIGKILL)
        output, _ = process.communicate()
        timed_out = True
    seconds = time.monotonic() - start
    # "[  FAILED  ] Suite.Name (3 ms)", or "..., where GetParam() = ..." for a parameterised one.
    failed = re.findall(r"^\[  FAILED  \] ([A-Za-z_][^\s,]*)", output, re.M)
    running = re.findall(r"^\[ RUN      \] (\S+)", output, re.M)
    last = running[-1] if running else "startup"
    if timed_out:
        return False, f"timeout after {timeout:g} s in {last}", seconds
    if process.returncode < 0:
        return False, f"signal {-process.returncode} in {last}", seconds
    if process.returncode != 0:
        if failed:
            return False, ", ".join(dict.fromkeys(failed)), seconds
        return False, f"exit {process.returncode} after {last}", seconds
    return True, "", seconds


def run_for_mutant(mutant, binary, cwd, timeout, environment):
    """The mutant's `first` cases, then (if they all pass) the whole suite to its first failure:
    the verdict is the whole suite's either way; `first` only finds the failure sooner."""
    seconds = 0.0
    if mutant.first:
        passed, why, seconds = run_suite(binary, cwd, timeout, True, environment, mutant.first)
        if not passed:
            return passed, why, seconds
    passed, why, more = run_suite(binary, cwd, timeout, True, environment)
    return passed, why, seconds + more


def mutated_text(root, mutant):
    """The mutated file, or the Outcome of a mutant that does not apply."""
    try:
        return mutant.apply((root / mutant.file).read_text()), None
    except ListError as error:
        return None, Outcome(mutant, "error", str(error))


def switched_on(build, mutant, number, timeouts):
    """Runs the suite of the schema build with the mutant's switch on."""
    suites = {"core": build / "core_tests_mutants", "messages": build / "messages_tests_mutants",
              "tools": build / "bag_tools_tests_mutants"}
    environment = {"AP_MUTANT": str(number),
                   "AP_PROPAGATE_BAG": str(build / "tools" / "propagate_bag"),
                   "AP_EVALUATE_BAG_CORE": str(build / "tools" / "evaluate_bag_core")}
    passed, why, seconds = run_for_mutant(mutant, suites[mutant.group], build,
                                          timeouts[mutant.group], environment)
    if passed:
        return Outcome(mutant, "survived", f"the {SUITES[mutant.group]} passes", 0.0, seconds)
    return Outcome(mutant, "killed", why, 0.0, seconds)


def run_mutant(slot, root, mutant, timeouts):
    text, failed = mutated_text(root, mutant)
    if failed:
        return failed
    # #line keeps compiler messages and __FILE__ pointing at the file the mutant stands for.
    text = f'#line 1 "{root / mutant.file}"\n' + text
    targets, suite, environment = slot.programs(mutant)
    start = time.monotonic()
    problem = slot.build_mutant(text, targets)
    built = time.monotonic() - start
    if problem is not None:
        return Outcome(mutant, "error", f"does not build: {problem}", built)
    passed, why, seconds = run_for_mutant(mutant, suite, slot.build, timeouts[mutant.group],
                                          environment)
    if passed:
        return Outcome(mutant, "survived", f"the {SUITES[mutant.group]} passes", built, seconds)
    return Outcome(mutant, "killed", why, built, seconds)


SUITES = {"core": "core suite", "messages": "message layer's suite", "tools": "bag tools' suite",
          "ros": "rostests"}


def report_line(outcome):
    m = outcome.mutant
    timing = f"build {outcome.build_seconds:.1f} s, run {outcome.run_seconds:.1f} s"
    first = outcome.detail.splitlines()[0] if outcome.detail else ""
    return f"  {outcome.verdict.upper():8} {m.id} ({m.file}; {timing}): {first}"


def write_junit(path, outcomes, seconds, name="mutants"):
    suite = ET.Element("testsuite", name=name, tests=str(len(outcomes)),
                       failures=str(sum(o.verdict == "survived" for o in outcomes)),
                       errors=str(sum(o.verdict == "error" for o in outcomes)),
                       time=f"{seconds:.1f}")
    for o in outcomes:
        stem = pathlib.Path(o.mutant.file).stem
        case = ET.SubElement(suite, "testcase", classname=f"{name}.{stem}", name=o.mutant.id,
                             time=f"{o.build_seconds + o.run_seconds:.1f}")
        if o.verdict == "survived":
            ET.SubElement(case, "failure", message="survived: " + o.mutant.bug).text = (
                f"{o.mutant.file}: {o.mutant.bug}\n"
                f"The {SUITES[o.mutant.group]} passes with this bug planted.")
        elif o.verdict == "error":
            error = ET.SubElement(case, "error", message="the mutant does not apply or build")
            error.text = o.detail
        else:
            ET.SubElement(case, "system-out").text = f"{o.mutant.bug}\nkilled: {o.detail}"
    root = ET.Element("testsuites")
    root.append(suite)
    ET.ElementTree(root).write(path, encoding="utf-8", xml_declaration=True)


def write_baseline_failure(path, why, name="mutants"):
    root = ET.Element("testsuites")
    suite = ET.SubElement(root, "testsuite", name=name, tests="1", failures="0", errors="1")
    case = ET.SubElement(suite, "testcase", classname=name, name="baseline")
    ET.SubElement(case, "error", message="an unmutated suite fails").text = why
    ET.ElementTree(root).write(path, encoding="utf-8", xml_declaration=True)


def summarise(outcomes, total, xml):
    killed = [o for o in outcomes if o.verdict == "killed"]
    survived = [o for o in outcomes if o.verdict == "survived"]
    errors = [o for o in outcomes if o.verdict == "error"]
    per = sum(o.build_seconds + o.run_seconds for o in outcomes) / max(len(outcomes), 1)
    for group in SUITES:
        mine = [o for o in outcomes if o.mutant.group == group]
        if mine:
            print(f"mutants: {group}: {sum(o.verdict == 'killed' for o in mine)} killed of "
                  f"{len(mine)}")
    print(f"mutants: {len(killed)} killed, {len(survived)} survived of {len(outcomes)} "
          f"({total:.0f} s, {per:.1f} s per mutant and worker; results {xml})")
    for o in survived:
        print(f"  survivor {o.mutant.id} ({o.mutant.file}): {o.mutant.bug}")
    for o in errors:
        print(f"  error {o.mutant.id} ({o.mutant.file}): {o.detail}")
    return 0 if not survived and not errors else 1


def command_run(args):
    build = pathlib.Path(args.build).resolve()
    results = pathlib.Path(args.results).resolve()
    results.mkdir(parents=True, exist_ok=True)
    xml = results / "mutants.xml"
    xml.unlink(missing_ok=True)
    root = pathlib.Path(args.root).resolve()
    mutants = select(read_lists(root, args.list or DEFAULT_LISTS), args.only)
    if any(m.group == "ros" for m in mutants):
        raise ListError(f"{ROS_LIST} runs with `mutate.py ros` (scripts/mutants_ros.sh)")
    timeouts = {"core": args.timeout, "messages": args.timeout, "tools": args.bag_timeout}
    os.environ.pop("AP_MUTANT", None)  # the unmutated suites run with every switch off
    numbers, in_schema = read_schemata(build)
    if in_schema and numbers != numbered(select(read_lists(root, args.list or DEFAULT_LISTS),
                                                args.only)):
        raise ListError(f"{build}/schemata.json was written for another selection of mutants")

    # Without a passing suite every mutant would look killed (in the schemata: with every
    # switch off, the schema build must be the unmutated code).
    suites = {"core": build / "core_tests_mutants", "messages": build / "messages_tests_mutants",
              "tools": build / "bag_tools_tests_mutants"}
    for group in dict.fromkeys(m.group for m in mutants):
        if not suites[group].is_file():
            raise ListError(f"{suites[group]} is not built (scripts/mutants.sh builds it)")
        environment = {"AP_PROPAGATE_BAG": str(build / "tools" / "propagate_bag"),
                       "AP_EVALUATE_BAG_CORE": str(build / "tools" / "evaluate_bag_core")}
        passed, why, seconds = run_suite(suites[group], build, timeouts[group], False,
                                         environment)
        if not passed:
            print(f"mutants: the unmutated {SUITES[group]} fails ({why}); no mutant was run")
            write_baseline_failure(xml, f"{SUITES[group]}: {why}")
            return 2
        print(f"mutants: the unmutated {SUITES[group]} passes in {seconds:.1f} s")
    print(f"mutants: running {len(mutants)} mutants ({sum(m.id in in_schema for m in mutants)} "
          f"switched on in the schemata, the rest built on their own), {args.jobs} at a time (timeout "
          f"{args.timeout:g} s each, {args.bag_timeout:g} s for the bag tools' suite)")

    start = time.monotonic()
    slots = [Slot(build, i) for i in range(args.jobs)]
    free = list(slots)
    lock = threading.Lock()

    def work(mutant):
        if mutant.id in in_schema:
            outcome = switched_on(build, mutant, numbers[mutant.id], timeouts)
            with lock:
                print(report_line(outcome), flush=True)
            return outcome
        with lock:
            slot = free.pop()
        try:
            outcome = run_mutant(slot, root, mutant, timeouts)
        finally:
            with lock:
                free.append(slot)
        with lock:  # one line at a time from the workers
            print(report_line(outcome), flush=True)
        return outcome

    # The slowest first (built on their own, then the bag tools' suite), so that the workers
    # finish together.
    order = sorted(mutants, key=lambda m: (m.id in in_schema, m.group != "tools"))
    with concurrent.futures.ThreadPoolExecutor(max_workers=args.jobs) as pool:
        done = {o.mutant.id: o for o in pool.map(work, order)}
    outcomes = [done[m.id] for m in mutants]
    total = time.monotonic() - start
    write_junit(xml, outcomes, total)
    return summarise(outcomes, total, xml)


# ---- The node's list: rostests in a scratch catkin workspace ----------------------------------

def rostest_failures(output):
    """The failing test cases rostest's summary names, or the last lines of its output."""
    output = re.sub(r"\x1b\[[0-9;]*m", "", output)  # the summary's colours
    # rosunit's junitxml summary heads each failed case "[name][FAILURE]---"; its bare runner's
    # summary lists them after the count.
    failed = (re.findall(r"^\[([^\]]+)\]\[(?:FAILURE|ERROR)\]", output, re.M) or
              re.findall(r"^\s*\* (?:ERRORS|FAILURES): \d+ \[([^\]]+)\]", output, re.M))
    if failed:
        return ", ".join(dict.fromkeys(failed))
    lines = [line for line in output.splitlines() if line.strip()]
    return " / ".join(lines[-3:]) if lines else "no output"


def run_rostest(workspace, name, timeout, environment=None):
    """Runs one rostest of the package in the scratch workspace: (passed, why, seconds). Not
    with --text: rostest then cannot read the test's results, and exits 0 whatever they say."""
    setup = workspace / "devel" / "setup.bash"
    command = (f"source {setup} && export ROS_HOME={workspace / 'ros_home'} && "
               f"rostest attitude_propagator {name}")
    start = time.monotonic()
    process = subprocess.Popen(["/bin/bash", "-c", command], stdout=subprocess.PIPE,
                               stderr=subprocess.STDOUT, text=True, start_new_session=True,
                               env=dict(os.environ, **(environment or {})))
    try:
        output, _ = process.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        os.killpg(process.pid, signal.SIGKILL)  # rostest and the nodes it started
        process.communicate()
        return False, f"{name}: timeout after {timeout:g} s", time.monotonic() - start
    seconds = time.monotonic() - start
    if process.returncode == 0 and "RESULT: SUCCESS" in output:
        return True, "", seconds
    return False, f"{name}: {rostest_failures(output)}", seconds


def command_ros(args):
    workspace = pathlib.Path(args.workspace).resolve()
    package = workspace / "src" / "attitude_propagator"
    results = pathlib.Path(args.results).resolve()
    results.mkdir(parents=True, exist_ok=True)
    xml = results / "mutants_ros.xml"
    xml.unlink(missing_ok=True)
    root = pathlib.Path(args.root).resolve()  # the checkout: each mutant applies to its text
    mutants = select(read_lists(root, [ROS_LIST]), args.only)
    os.environ.pop("AP_MUTANT", None)  # the unmutated rostests run with every switch off
    numbers, in_schema = read_schemata(workspace / "build")
    if in_schema and numbers != numbered(mutants):
        raise ListError(f"{workspace}/build/schemata.json was written for another selection")
    build = f"catkin_make -j{os.cpu_count() or 2} {' '.join(args.target)}"
    # Without passing rostests every mutant would look killed: each one named, unmutated, once
    # (in the schemata: with every switch off, the node must be the unmutated one).
    for test in dict.fromkeys(t for m in mutants for t in m.tests):
        passed, why, seconds = run_rostest(workspace, test, args.timeout)
        if not passed:
            print(f"mutants: the unmutated {test} fails ({why}); no mutant was run")
            write_baseline_failure(xml, why, name="mutants_ros")
            return 2
        print(f"mutants: the unmutated {test} passes in {seconds:.0f} s", flush=True)
    print(f"mutants: running {len(mutants)} mutants of the node ({sum(m.id in in_schema for m in mutants)} "
          f"switched on in the schemata), one at a time (rostests: timeout {args.timeout:g} s "
          "each)", flush=True)
    start = time.monotonic()
    outcomes = []

    def rostests(mutant, environment=None):
        why, seconds = "", 0.0
        for test in mutant.tests:
            passed, why, spent = run_rostest(workspace, test, args.timeout, environment)
            seconds += spent
            if not passed:
                break
        verdict = "killed" if why else "survived"
        return verdict, why or f"{' '.join(mutant.tests)} pass", seconds

    # Those in the schemata first: a mutant built on its own leaves the node built from its
    # file without the schema until the rebuild at the end.
    for mutant in sorted(mutants, key=lambda m: m.id not in in_schema):
        if mutant.id in in_schema:
            verdict, why, seconds = rostests(mutant, {"AP_MUTANT": str(numbers[mutant.id])})
            outcome = Outcome(mutant, verdict, why, 0.0, seconds)
            outcomes.append(outcome)
            print(report_line(outcome), flush=True)
            continue
        text, failed = mutated_text(root, mutant)
        if failed:
            outcomes.append(failed)
            print(report_line(failed), flush=True)
            continue
        path = package / mutant.file
        original = path.read_text()  # the schema, when the file has one
        began = time.monotonic()
        try:
            path.write_text(text)
            problem = run_command(build, str(workspace))
            built = time.monotonic() - began
            if problem is not None:
                outcome = Outcome(mutant, "error", f"does not build: {problem}", built)
            else:
                verdict, why, seconds = rostests(mutant)
                outcome = Outcome(mutant, verdict, why, built, seconds)
        finally:
            path.write_text(original)
        outcomes.append(outcome)
        print(report_line(outcome), flush=True)
    # The workspace ends built from the unmutated sources, for the next run.
    problem = run_command(build, str(workspace))
    if problem is not None:
        print(f"mutants: rebuilding the unmutated package failed: {problem}")
    total = time.monotonic() - start
    write_junit(xml, outcomes, total, name="mutants_ros")
    return summarise(outcomes, total, xml)


def command_groups(args):
    """The groups of the selected mutants, one a line (scripts/mutants.sh builds their suites)."""
    root = pathlib.Path(args.root).resolve()
    mutants = select(read_lists(root, args.list or DEFAULT_LISTS), args.only)
    for group in dict.fromkeys(m.group for m in mutants):
        print(group)
    return 0


def command_list(args):
    root = pathlib.Path(args.root).resolve()
    mutants = select(read_lists(root, args.list or list(LISTS)), args.only)
    bad = 0
    for m in mutants:
        try:
            m.apply((root / m.file).read_text())
            status = ""
        except (ListError, OSError) as error:
            status = f"   ERROR: {error}"
            bad += 1
        tests = f" [{' '.join(m.tests)}]" if m.tests else ""
        print(f"{m.id:36} {m.file:38} {m.bug}{tests}{status}")
    counts = ", ".join(f"{name} {sum(m.list_name == name for m in mutants)}" for name in LISTS
                       if any(m.list_name == name for m in mutants))
    print(f"{len(mutants)} mutants ({counts}), {len(mutants) - bad} apply")
    return 1 if bad else 0


def main():
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    commands = parser.add_subparsers(dest="command", required=True)
    listing = commands.add_parser("list")
    listing.add_argument("--list", action="append", default=[])
    listing.add_argument("--only", action="append", default=[])
    listing.add_argument("--root", default=str(HERE.parent.parent))
    groups = commands.add_parser("groups")
    groups.add_argument("--list", action="append", default=[])
    groups.add_argument("--only", action="append", default=[])
    groups.add_argument("--root", default=str(HERE.parent.parent))
    copy = commands.add_parser("sync")
    copy.add_argument("--package", action="store_true")
    copy.add_argument("repo")
    copy.add_argument("scratch")
    schema = commands.add_parser("schemata")
    schema.add_argument("repo")
    schema.add_argument("scratch")
    schema.add_argument("build")
    schema.add_argument("--list", action="append", default=[])
    schema.add_argument("--only", action="append", default=[])
    schema.add_argument("--jobs", type=int, default=2)
    run = commands.add_parser("run")
    run.add_argument("build")
    run.add_argument("results")
    run.add_argument("--list", action="append", default=[])
    run.add_argument("--only", action="append", default=[])
    run.add_argument("--jobs", type=int, default=2)
    run.add_argument("--timeout", type=float, default=30.0)
    run.add_argument("--bag-timeout", type=float, default=300.0)
    run.add_argument("--root", default=str(HERE.parent.parent))
    ros = commands.add_parser("ros")
    ros.add_argument("workspace")
    ros.add_argument("results")
    ros.add_argument("--only", action="append", default=[])
    ros.add_argument("--timeout", type=float, default=300.0)
    ros.add_argument("--target", action="append", default=[])
    ros.add_argument("--root", default=str(HERE.parent.parent))
    args = parser.parse_args()
    try:
        if args.command == "list":
            return command_list(args)
        if args.command == "groups":
            return command_groups(args)
        if args.command == "sync":
            sync(pathlib.Path(args.repo).resolve(), pathlib.Path(args.scratch).resolve(),
                 args.package)
            return 0
        if args.command == "ros":
            return command_ros(args)
        if args.command == "schemata":
            return command_schemata(args)
        if args.jobs < 1:
            raise ListError("--jobs: at least 1")
        return command_run(args)
    except ListError as error:
        print(f"mutants: {error}")
        return 2


if __name__ == "__main__":
    sys.exit(main())
