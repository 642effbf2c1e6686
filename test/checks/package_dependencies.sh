#!/usr/bin/env bash
# package.xml declares what the code and tests use: every #include <pkg/...> and every Python
# import of src/, nodes/ and test/ is mapped to the rosdep key (Ubuntu + Noetic) that provides
# it, and that key must be declared: for src/ and nodes/ as a build or run dependency
# (depend, build_depend, exec_depend, buildtool_depend), for test/ also as a test_depend. An
# include root or import this check does not know fails too, so a new one gets a line below.
cd "$(dirname "${BASH_SOURCE[0]}")/../.." || exit 1
exec /usr/bin/python3 - <<'PY'
import ast
import pathlib
import re
import sys
import xml.etree.ElementTree as ET

# Include roots and Python modules -> the rosdep keys that provide them (any one suffices).
INCLUDES = {
    "Eigen": ["eigen"], "unsupported": ["eigen"], "boost": ["boost"], "gtest": ["gtest", "rosunit"],
    "ros": ["roscpp", "rostime", "rosconsole", "roscpp_serialization"],
    "rosbag": ["rosbag_storage", "rosbag"], "roslz4": ["roslz4"], "xmlrpcpp": ["xmlrpcpp"],
    "attitude_propagator": ["attitude_propagator"],
}
PYTHON = {
    "yaml": ["python3-yaml"], "matplotlib": ["python3-matplotlib"], "rospkg": ["python3-rospkg"],
    "catkin": ["catkin"], "attitude_propagator": ["attitude_propagator"],
}
# roscpp's headers by the package that installs them (ros/ is shared by several).
ROS_HEADERS = {
    "console.h": ["rosconsole"], "console_backend.h": ["rosconsole"], "assert.h": ["rosconsole"],
    "time.h": ["rostime"], "duration.h": ["rostime"], "rate.h": ["rostime"],
    "serialization.h": ["roscpp_serialization"], "serialized_message.h": ["roscpp_serialization"],
    "message_traits.h": ["roscpp_traits", "roscpp_serialization"],
}
SYSTEM_INCLUDES = {"sys", "linux", "arpa", "netinet"}  # the C library's directories

package = ET.parse("package.xml").getroot()
declared = {"attitude_propagator"}
test_declared = set(declared)
for element in package:
    if element.tag in ("depend", "build_depend", "exec_depend", "buildtool_depend",
                       "build_export_depend"):
        declared.add(element.text.strip())
    if element.tag in ("depend", "build_depend", "exec_depend", "buildtool_depend",
                       "build_export_depend", "test_depend"):
        test_declared.add(element.text.strip())

local_modules = {p.stem for root in ("src", "nodes", "test", "scripts", "bench")
                 for p in pathlib.Path(root).rglob("*.py")}
stdlib = set(sys.stdlib_module_names)
problems = []


def need(path, what, keys):
    have = test_declared if path.parts[0] == "test" else declared
    if not any(k in have for k in keys):
        kind = "test_depend" if path.parts[0] == "test" else "depend"
        problems.append(f"{path}: {what} needs one of {', '.join(keys)} in package.xml ({kind})")


def is_python(path):
    if path.suffix == ".py":
        return True
    if path.suffix:
        return False
    try:
        return path.read_text(errors="replace").startswith("#!/usr/bin/python3") or \
            path.read_text(errors="replace").startswith("#!/usr/bin/env python3")
    except OSError:
        return False


for root in ("src", "nodes", "test"):
    for path in sorted(pathlib.Path(root).rglob("*")):
        if not path.is_file():
            continue
        if path.suffix in (".cpp", ".h", ".hpp", ".cc"):
            for include in re.findall(r'^\s*#\s*include\s*<([^>]+)>', path.read_text(errors="replace"),
                                      re.M):
                if "/" not in include:
                    continue  # the C++ and C standard libraries
                top = include.split("/")[0]
                if top in SYSTEM_INCLUDES:
                    continue
                keys = INCLUDES.get(top, [top])
                if top == "ros":
                    keys = ROS_HEADERS.get(include.split("/", 1)[1], ["roscpp"])
                need(path, f"#include <{include}>", keys)
        elif is_python(path):
            try:
                tree = ast.parse(path.read_text(errors="replace"))
            except SyntaxError as e:
                problems.append(f"{path}: not Python ({e})")
                continue
            for node in ast.walk(tree):
                if isinstance(node, ast.Import):
                    names = [a.name for a in node.names]
                elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                    names = [node.module]
                else:
                    continue
                for name in names:
                    top = name.split(".")[0]
                    if top in stdlib or top in local_modules:
                        continue
                    need(path, f"import {name}", PYTHON.get(top, [top]))

for p in problems:
    print("package dependencies:", p)
sys.exit(1 if problems else 0)
PY
