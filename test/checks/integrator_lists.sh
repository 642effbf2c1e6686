#!/usr/bin/env bash
# What names the integrators outside the core agrees with its table
# (src/core/numerics/integrator.cpp), in the table's order. Read from the table's source: the
# reconfigure enum (cfg/AttitudePropagator.cfg generates it; compared as the build generated it)
# and the fuzz seeds (test/fuzz/make_seeds.py's NAMES, KINEMATIC and DYNAMIC, its corpus, and
# fuzz_parameters.cpp's refused names after NAMES). Read through the core: evaluate_bag_core's
# --integrators default in its --help and the fuzz targets' codes (fuzz_support.h). Read from
# that --help: bench/bag_throughput.sh's loop and evaluate_bag's colours. Lists kept by hand:
# the chart styles (bench/plot.py's KINEMATIC_STYLES, DYNAMIC_STYLES, BOTH_MODELS_STYLES: one
# free for every method) and evaluate_bag's KINEMATIC_COLOURS (plot.py's kinematic colours).
# docs/bag_tools.md points at the table. The table comes from the core's API through the
# integrator_table program, so this needs the built workspace (scripts/test.sh builds first).
source "$(dirname "${BASH_SOURCE[0]}")/../../scripts/common.sh"
source_ros
# Under catkin's run_tests (test/checks/junit.py) the workspace's environment is already set.
[ -n "${AP_CATKIN_ENV:-}" ] || source_workspace
cd "$REPO_DIR" || exit 1
program="$(catkin_find --first-only --libexec attitude_propagator integrator_table 2>/dev/null)"
[ -x "$program" ] || program="$WORKSPACE/devel/lib/attitude_propagator/integrator_table"
if [ ! -x "$program" ]; then
  echo "integrator lists: integrator_table is not built (build the package first)"
  exit 1
fi
table="$("$program")" || { echo "integrator lists: $program failed"; exit 1; }
# evaluate_bag_core's help is printed from its option table: read as the user reads it.
core_help="$("$(dirname "$program")/evaluate_bag_core" --help)" ||
  { echo "integrator lists: evaluate_bag_core --help failed"; exit 1; }
TABLE="$table" CORE_HELP="$core_help" /usr/bin/python3 - <<'PY'
import ast
import os
import pathlib
import re
import sys

sys.dont_write_bytecode = True

rows = [line.split() for line in os.environ["TABLE"].splitlines() if line.strip()]
names = [r[0] for r in rows]
kinematic = [r[0] for r in rows if r[0] != "auto" and "kinematic" in r[1:]]
dynamic = [r[0] for r in rows if r[0] != "auto" and "dynamic" in r[1:]]
errors = []


def expect(what, found, wanted, source="the table"):
    if found != wanted:
        errors.append("%s: %s; %s: %s" % (what, found, source, wanted))


def assigned(path, variable):
    """The literal value assigned to a top-level variable of a Python file."""
    for node in ast.parse(pathlib.Path(path).read_text(), path).body:
        if isinstance(node, ast.Assign) and any(
                isinstance(t, ast.Name) and t.id == variable for t in node.targets):
            return ast.literal_eval(node.value)
    errors.append("%s: no %s = ..." % (path, variable))
    return None


def one_match(path, pattern):
    found = re.findall(pattern, pathlib.Path(path).read_text())
    if len(found) != 1:
        errors.append("%s: %d matches of %r, expected 1" % (path, len(found), pattern))
        return None
    return found[0]


if not names or names[0] != "auto" or not kinematic or not dynamic:
    errors.append("integrator_table printed no usable table: %r" % rows)

# The reconfigure enum, as the build generated it from the table's source: every name, auto
# first (the generated module of the built workspace).
from attitude_propagator.cfg import AttitudePropagatorConfig  # noqa: E402

enum = [p for p in AttitudePropagatorConfig.config_description["parameters"]
        if p["name"] == "integrator"]
if len(enum) != 1:
    errors.append("AttitudePropagatorConfig: %d integrator parameters, expected 1" % len(enum))
else:
    expect("the reconfigure enum (cfg/AttitudePropagator.cfg, generated)",
           [c["name"] for c in ast.literal_eval(enum[0]["edit_method"])["enum"]], names)

# evaluate_bag_core: the default reads the table; its help text spells it out.
core = "src/tools/evaluate_bag_core.cpp"
default = one_match(core, r"std::vector<std::string> integrators\b[^;]*;")
if default is not None and "integratorsFor(Model::Kinematic)" not in default:
    errors.append("%s: the --integrators default is not the table's kinematic methods: %s"
                  % (core, default))
help_lists = re.findall(r"--integrators LIST +comma-separated \(default ([a-z0-9_,]+)\)",
                        os.environ["CORE_HELP"])
if len(help_lists) != 1:
    errors.append("evaluate_bag_core --help: %d --integrators lines, expected 1" % len(help_lists))
else:
    expect("evaluate_bag_core --help --integrators", help_lists[0].split(","), kinematic)

# The benchmark charts give each method the next style of its kind (bench/plot.py:
# KINEMATIC_STYLES for the kinematic methods, DYNAMIC_STYLES for the dynamic ones not kinematic,
# BOTH_MODELS_STYLES for the dynamic use of each method of both models, rk4) in the order it first
# appears in the sweep, the table's; evaluate_bag colours the kinematic methods, in the table's
# order, with the same colours (KINEMATIC_COLOURS). Every method needs a style of its own.
styles = {kind: assigned("bench/plot.py", kind)
          for kind in ("KINEMATIC_STYLES", "DYNAMIC_STYLES", "BOTH_MODELS_STYLES")}
if None not in styles.values():
    wanted = {"KINEMATIC_STYLES": kinematic,
              "DYNAMIC_STYLES": [m for m in dynamic if m not in kinematic],
              "BOTH_MODELS_STYLES": ["dynamic " + m for m in dynamic if m in kinematic]}
    for kind, methods in wanted.items():
        if len(styles[kind]) < len(methods):
            errors.append("bench/plot.py %s: %d styles for the %d methods %s (add one)"
                          % (kind, len(styles[kind]), len(methods), methods))
    every = [c for kind in styles for c, _ in styles[kind]]
    if len(set(every)) != len(every):
        errors.append("bench/plot.py: a colour appears twice in the styles: %s" % every)
    evaluate_colours = assigned("nodes/evaluate_bag", "KINEMATIC_COLOURS")
    if evaluate_colours is not None:
        expect("nodes/evaluate_bag KINEMATIC_COLOURS", evaluate_colours,
               [c for c, _ in styles["KINEMATIC_STYLES"]], "bench/plot.py's KINEMATIC_STYLES")

# The fuzz seeds: the names the targets index, the methods seeded, and the corpus they write.
sys.path.insert(0, "test/fuzz")
import make_seeds  # noqa: E402

# The fuzz targets name a method by its code, its row in the table (fuzz_support.h's
# integratorCodes() is the core's integratorNames()); make_seeds.py reads the same rows from the
# table's source.
one_match("test/fuzz/fuzz_support.h",
          r"static const std::vector<std::string> codes = attitude_propagator::integratorNames\(\);")
expect("test/fuzz/make_seeds.py NAMES", make_seeds.NAMES, names)
refused = one_match("test/fuzz/fuzz_parameters.cpp",
                    r"for \(const char\* refused : \{([^}]*)\}\)")
if refused is not None:
    expect("test/fuzz/make_seeds.py CHOICES['integrator']", make_seeds.CHOICES["integrator"],
           make_seeds.NAMES + ast.literal_eval("[" + refused + "]"),
           "NAMES and fuzz_parameters.cpp's refused names")
try:
    seeds = make_seeds.seeds()
except Exception as e:  # a seed naming a method NAMES lacks
    errors.append("test/fuzz/make_seeds.py: seeds() fails: %r" % e)
    seeds = {}
for target, files in seeds.items():
    folder = pathlib.Path("test/fuzz/corpus") / target
    held = {p.name: p.read_bytes() for p in folder.iterdir()} if folder.is_dir() else {}
    differ = sorted(n for n in set(held) | set(files) if held.get(n) != files.get(n))
    if differ:
        errors.append("%s differs from make_seeds.py's seeds (run python3 "
                      "test/fuzz/make_seeds.py): %s" % (folder, " ".join(differ)))

# Benchmark and documentation of the bag tools: every kinematic method, read from the table
# (bag_throughput.sh loops over evaluate_bag_core's --integrators default; bag_tools.md points
# at the table rather than naming the methods).
one_match("bench/bag_throughput.sh", r'for integrator in "\$\{INTEGRATORS\[@\]\}"; do')
one_match("bench/bag_throughput.sh", r"evaluate_bag_core\" --help \|")
one_match("docs/bag_tools.md", r"\*\*`evaluate_bag`\*\* runs every kinematic integrator of the table")

for line in errors:
    print("integrator lists:", line)
if not errors:
    print("integrator lists: %d names (%d kinematic, %d dynamic) agree with the table"
          % (len(names), len(kinematic), len(dynamic)))
sys.exit(1 if errors else 0)
PY
