#!/usr/bin/env python3
"""The mutation check's driver (scripts/mutants.sh runs it): plants each mutant of
test/mutants/mutants.txt in the core sources, one at a time, and runs the core gtest suite on it.

  mutate.py list [--only ID ...] [--root DIR]   the mutants; each must apply (exit 1 if not)
  mutate.py sync REPO SCRATCH                   copy the sources the build needs to SCRATCH
  mutate.py run BUILD RESULTS [--only ID ...] [--jobs N] [--timeout S]

A mutant is never written into a source tree: its mutated file goes to a slot source in the
build folder (mutant_slot<N>.cpp, one per parallel worker), which is compiled alone and linked
ahead of the unchanged core archive, so that the linker takes the mutated definitions and
never pulls the original object. Each mutant thus costs one compile and one link, and there is
nothing to restore.

A mutant is killed when the suite fails on it (the first failing test is recorded), crashes, or
runs past the timeout; it survives when the suite passes. A mutant whose original text does not
occur exactly once, or whose mutated file does not build, is an error of the list. The results
go to RESULTS/mutants.xml (JUnit: one test case per mutant, a survivor or an error fails).
"""
import argparse
import concurrent.futures
import dataclasses
import json
import pathlib
import re
import subprocess
import sys
import threading
import time
import xml.etree.ElementTree as ET

HERE = pathlib.Path(__file__).resolve().parent
LIST_NAME = "mutants.txt"
KEYS = ("id", "file", "bug", "original", "mutant")
# Where a mutant may live: a source file compiled into the core or config library.
MUTABLE = re.compile(r"^src/(core|config)/[A-Za-z0-9_]+\.cpp$")
# What the build and the core suite read: the sources, the headers, the suite, this folder,
# and the files the parameter tests compare against (the table in docs/parameters.md,
# config/*.yaml).
SYNCED = ("src/core", "src/config", "include", "test/core", "test/mutants", "config")
SYNCED_FILES = ("docs/parameters.md",)


class ListError(Exception):
    """The mutant list is malformed, or a mutant does not apply to the code."""


@dataclasses.dataclass
class Mutant:
    id: str
    file: str
    bug: str
    pairs: list  # (original, replacement) in turn
    line: int  # of the block in the list

    def apply(self, text):
        for original, replacement in self.pairs:
            count = text.count(original)
            if count != 1:
                raise ListError(
                    f"{LIST_NAME}:{self.line}: {self.id}: the original text occurs {count} "
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
        if key in ("id", "file", "bug"):
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
    if not MUTABLE.match(single["file"]):
        raise ListError(f"{where}: {single['file']}: not a src/core or src/config .cpp file")
    if any(not original for original, _ in pairs):
        raise ListError(f"{where}: empty original text")
    return Mutant(single["id"], single["file"], single["bug"], pairs, start)


def select(mutants, only):
    if not only:
        return mutants
    known = {m.id for m in mutants}
    unknown = [i for i in only if i not in known]
    if unknown:
        raise ListError("no mutant with id " + ", ".join(unknown))
    return [m for m in mutants if m.id in only]


# ---- The scratch copy -------------------------------------------------------------------------

def sync(repo, scratch):
    """Makes SCRATCH hold exactly the files the build reads, writing only those whose content
    differs (unchanged files keep their times, so the build stays incremental)."""
    wanted = {}
    for folder in SYNCED:
        for path in (repo / folder).rglob("*"):
            if path.is_file() and "__pycache__" not in path.parts:
                wanted[path.relative_to(repo)] = path
    for name in SYNCED_FILES:
        wanted[pathlib.Path(name)] = repo / name
    written = 0
    for relative, source in wanted.items():
        target = scratch / relative
        data = source.read_bytes()
        if target.is_file() and target.read_bytes() == data:
            continue
        target.parent.mkdir(parents=True, exist_ok=True)
        target.write_bytes(data)
        written += 1
    removed = 0
    for folder in SYNCED:
        for path in sorted((scratch / folder).rglob("*"), reverse=True):
            if path.is_file() and path.relative_to(scratch) not in wanted:
                path.unlink()
                removed += 1
    print(f"mutants: scratch copy in {scratch}: {written} files written, {removed} removed")


# ---- Running ----------------------------------------------------------------------------------

@dataclasses.dataclass
class Outcome:
    mutant: Mutant
    verdict: str  # killed, survived, error
    detail: str
    build_seconds: float = 0.0
    run_seconds: float = 0.0


class Slot:
    """One worker's mutant source in the build folder, with the commands CMake generated to
    compile it and to link it ahead of the core archive."""

    def __init__(self, build, index):
        self.build = build
        self.source = build / f"mutant_slot{index}.cpp"
        self.binary = build / f"core_tests_slot{index}"
        commands = json.loads((build / "compile_commands.json").read_text())
        entry = next((c for c in commands if pathlib.Path(c["file"]) == self.source), None)
        link = build / "CMakeFiles" / f"core_tests_slot{index}.dir" / "link.txt"
        if entry is None or not link.is_file():
            raise ListError(f"{build} has no slot {index}: configure it with MUTANT_SLOTS "
                            "at least --jobs (the Unix Makefiles generator)")
        self.compile = (entry["command"], entry["directory"])
        self.link = (link.read_text().strip(), str(build))

    def build_mutant(self, text):
        self.source.write_text(text)
        self.binary.unlink(missing_ok=True)
        for command, directory in (self.compile, self.link):
            done = subprocess.run(command, shell=True, cwd=directory, stdout=subprocess.PIPE,
                                  stderr=subprocess.STDOUT, text=True)
            if done.returncode != 0:
                lines = done.stdout.splitlines()
                errors = [line for line in lines if "error" in line] or lines
                return "\n".join(errors[:10])
        return None


def run_suite(binary, cwd, timeout, fail_fast):
    """Runs the suite: (passed, why it failed, seconds)."""
    command = [str(binary), "--gtest_color=no"] + (["--gtest_fail_fast"] if fail_fast else [])
    start = time.monotonic()
    process = subprocess.Popen(command, cwd=cwd, stdout=subprocess.PIPE,
                               stderr=subprocess.STDOUT, text=True)
    try:
        output, _ = process.communicate(timeout=timeout)
        timed_out = False
    except subprocess.TimeoutExpired:
        process.kill()  # the suite we started, by its handle
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


def run_mutant(slot, root, mutant, timeout):
    original = (root / mutant.file).read_text()
    try:
        text = mutant.apply(original)
    except ListError as error:
        return Outcome(mutant, "error", str(error))
    # #line keeps compiler messages and __FILE__ pointing at the file the mutant stands for.
    text = f'#line 1 "{root / mutant.file}"\n' + text
    start = time.monotonic()
    problem = slot.build_mutant(text)
    built = time.monotonic() - start
    if problem is not None:
        return Outcome(mutant, "error", f"does not build: {problem}", built)
    passed, why, seconds = run_suite(slot.binary, slot.build, timeout, fail_fast=True)
    if passed:
        return Outcome(mutant, "survived", "the core suite passes", built, seconds)
    return Outcome(mutant, "killed", why, built, seconds)


def report_line(outcome):
    m = outcome.mutant
    timing = f"build {outcome.build_seconds:.1f} s, run {outcome.run_seconds:.1f} s"
    first = outcome.detail.splitlines()[0] if outcome.detail else ""
    return f"  {outcome.verdict.upper():8} {m.id} ({m.file}; {timing}): {first}"


def write_junit(path, outcomes, seconds):
    suite = ET.Element("testsuite", name="mutants", tests=str(len(outcomes)),
                       failures=str(sum(o.verdict == "survived" for o in outcomes)),
                       errors=str(sum(o.verdict == "error" for o in outcomes)),
                       time=f"{seconds:.1f}")
    for o in outcomes:
        stem = pathlib.Path(o.mutant.file).stem
        case = ET.SubElement(suite, "testcase", classname="mutants." + stem, name=o.mutant.id,
                             time=f"{o.build_seconds + o.run_seconds:.1f}")
        if o.verdict == "survived":
            ET.SubElement(case, "failure", message="survived: " + o.mutant.bug).text = (
                f"{o.mutant.file}: {o.mutant.bug}\nThe core suite passes with this bug planted.")
        elif o.verdict == "error":
            error = ET.SubElement(case, "error", message="the mutant does not apply or build")
            error.text = o.detail
        else:
            ET.SubElement(case, "system-out").text = f"{o.mutant.bug}\nkilled: {o.detail}"
    root = ET.Element("testsuites")
    root.append(suite)
    ET.ElementTree(root).write(path, encoding="utf-8", xml_declaration=True)


def write_baseline_failure(path, why):
    root = ET.Element("testsuites")
    suite = ET.SubElement(root, "testsuite", name="mutants", tests="1", failures="0", errors="1")
    case = ET.SubElement(suite, "testcase", classname="mutants", name="baseline")
    ET.SubElement(case, "error", message="the unmutated core suite fails").text = why
    ET.ElementTree(root).write(path, encoding="utf-8", xml_declaration=True)


def command_run(args):
    build = pathlib.Path(args.build).resolve()
    results = pathlib.Path(args.results).resolve()
    results.mkdir(parents=True, exist_ok=True)
    xml = results / "mutants.xml"
    xml.unlink(missing_ok=True)
    root = pathlib.Path(args.root).resolve()
    mutants = select(parse_list(root / "test" / "mutants" / LIST_NAME), args.only)

    # Without a passing suite every mutant would look killed.
    passed, why, seconds = run_suite(build / "core_tests_mutants", build, args.timeout, False)
    if not passed:
        print(f"mutants: the unmutated core suite fails ({why}); no mutant was run")
        write_baseline_failure(xml, why)
        return 2
    print(f"mutants: the unmutated suite passes in {seconds:.1f} s; running {len(mutants)} "
          f"mutants, {args.jobs} at a time (timeout {args.timeout:g} s each)")

    start = time.monotonic()
    slots = [Slot(build, i) for i in range(args.jobs)]
    free = list(slots)
    lock = threading.Lock()

    def work(mutant):
        with lock:
            slot = free.pop()
        try:
            outcome = run_mutant(slot, root, mutant, args.timeout)
        finally:
            with lock:
                free.append(slot)
        with lock:  # one line at a time from the workers
            print(report_line(outcome), flush=True)
        return outcome

    with concurrent.futures.ThreadPoolExecutor(max_workers=args.jobs) as pool:
        outcomes = list(pool.map(work, mutants))
    total = time.monotonic() - start
    write_junit(xml, outcomes, total)

    killed = [o for o in outcomes if o.verdict == "killed"]
    survived = [o for o in outcomes if o.verdict == "survived"]
    errors = [o for o in outcomes if o.verdict == "error"]
    per = sum(o.build_seconds + o.run_seconds for o in outcomes) / max(len(outcomes), 1)
    print(f"mutants: {len(killed)} killed, {len(survived)} survived of {len(outcomes)} "
          f"({total:.0f} s, {per:.1f} s per mutant and worker; results {xml})")
    for o in survived:
        print(f"  survivor {o.mutant.id} ({o.mutant.file}): {o.mutant.bug}")
    for o in errors:
        print(f"  error {o.mutant.id} ({o.mutant.file}): {o.detail}")
    return 0 if not survived and not errors else 1


def command_list(args):
    root = pathlib.Path(args.root).resolve()
    mutants = select(parse_list(root / "test" / "mutants" / LIST_NAME), args.only)
    bad = 0
    for m in mutants:
        try:
            m.apply((root / m.file).read_text())
            status = ""
        except (ListError, OSError) as error:
            status = f"   ERROR: {error}"
            bad += 1
        print(f"{m.id:32} {m.file:38} {m.bug}{status}")
    print(f"{len(mutants)} mutants, {len(mutants) - bad} apply")
    return 1 if bad else 0


def main():
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    commands = parser.add_subparsers(dest="command", required=True)
    listing = commands.add_parser("list")
    listing.add_argument("--only", action="append", default=[])
    listing.add_argument("--root", default=str(HERE.parent.parent))
    copy = commands.add_parser("sync")
    copy.add_argument("repo")
    copy.add_argument("scratch")
    run = commands.add_parser("run")
    run.add_argument("build")
    run.add_argument("results")
    run.add_argument("--only", action="append", default=[])
    run.add_argument("--jobs", type=int, default=2)
    run.add_argument("--timeout", type=float, default=30.0)
    run.add_argument("--root", default=str(HERE.parent.parent))
    args = parser.parse_args()
    try:
        if args.command == "list":
            return command_list(args)
        if args.command == "sync":
            sync(pathlib.Path(args.repo).resolve(), pathlib.Path(args.scratch).resolve())
            return 0
        if args.jobs < 1:
            raise ListError("--jobs: at least 1")
        return command_run(args)
    except ListError as error:
        print(f"mutants: {error}")
        return 2


if __name__ == "__main__":
    sys.exit(main())
