#!/usr/bin/env bash
# The package builds as an ordinary catkin package, without what only the project's scripts
# use. It is configured in a scratch folder as a catkin workspace configures it (no option of
# scripts/build.sh, the compiler g++), twice: with CATKIN_ENABLE_TESTING off (a build without
# the test packages, the README's Debian path) and on (catkin's default). Either way
#   - no benchmark or fuzz target is defined (no target or object named *bench*/*fuzz*, no
#     -fsanitize=fuzzer flag), and
#   - no file is used of the Debian packages only the scripts need (DEBIAN_SCRIPT_PACKAGES in
#     scripts/common.sh: Google Benchmark, clang and libFuzzer, ccache), nor with testing off of
#     the test packages (DEBIAN_TEST_PACKAGES: gtest, rostest, catkin_lint). "Used": a file CMake
#     ran (its --trace-expand) or a path named in the cache or the generated build files,
#     against the files those packages installed (dpkg -L; a package not installed is skipped).
# And the README's "In your catkin workspace" names exactly DEBIAN_BUILD_PACKAGES and
# DEBIAN_TEST_PACKAGES in its two apt-get lines. Configure only, no build: about 15 s.
source "$(dirname "${BASH_SOURCE[0]}")/../../scripts/common.sh"
source_ros
cd "$REPO_DIR" || exit 1
command -v dpkg-query >/dev/null || { echo "ordinary build: dpkg-query not found (Debian or Ubuntu)"; exit 1; }
scratch="$(mktemp -d)"
trap 'rm -rf "$scratch"' EXIT

# files_of PACKAGE...: the regular files the installed ones among PACKAGE installed, as
# "package<TAB>path" lines.
files_of() {
  local pkg
  for pkg in "$@"; do
    dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null | grep -q "install ok installed" || continue
    dpkg-query -L "$pkg" 2>/dev/null | while read -r path; do
      [ -f "$path" ] && printf '%s\t%s\n' "$pkg" "$path"
    done
  done
}
files_of "${DEBIAN_SCRIPT_PACKAGES[@]}" >"$scratch/script_files.txt"
files_of "${DEBIAN_TEST_PACKAGES[@]}" >"$scratch/test_files.txt"

status=0
for testing in OFF ON; do
  build="$scratch/testing_$testing"
  forbidden=("$scratch/script_files.txt")
  [ "$testing" = ON ] || forbidden+=("$scratch/test_files.txt")
  if ! cmake -S "$REPO_DIR" -B "$build" -G "Unix Makefiles" \
    -DCMAKE_C_COMPILER=gcc -DCMAKE_CXX_COMPILER=g++ -DCATKIN_ENABLE_TESTING="$testing" \
    -DPYTHON_EXECUTABLE=/usr/bin/python3 -DPython3_EXECUTABLE=/usr/bin/python3 \
    --trace-expand --trace-redirect="$build.trace" >"$build.log" 2>&1; then
    echo "ordinary build: the configure with CATKIN_ENABLE_TESTING=$testing failed:"
    tail -n 30 "$build.log"
    status=1
    continue
  fi
  targets="$(cmake --build "$build" --target help 2>/dev/null | grep -Ei '^\.\.\. \S*(bench|fuzz)')"
  if [ -n "$targets" ]; then
    echo "ordinary build (CATKIN_ENABLE_TESTING=$testing): benchmark or fuzz targets defined:"
    echo "$targets" | head -n 20
    status=1
  fi
  if grep -rlq -- "-fsanitize=fuzzer" "$build"; then
    echo "ordinary build (CATKIN_ENABLE_TESTING=$testing): a target is compiled for libFuzzer"
    status=1
  fi
  /usr/bin/python3 - "$build" "CATKIN_ENABLE_TESTING=$testing" "${forbidden[@]}" <<'PY' || status=1
import os
import pathlib
import re
import sys

build, what, lists = pathlib.Path(sys.argv[1]), sys.argv[2], sys.argv[3:]
owner = {}
for name in lists:
    for line in open(name, encoding="utf-8"):
        package, path = line.rstrip("\n").split("\t", 1)
        owner[path] = package
        owner.setdefault(os.path.realpath(path), package)
texts = [pathlib.Path(str(build) + ".trace"), build / "CMakeCache.txt"]
texts += sorted(build.rglob("flags.make")) + sorted(build.rglob("link.txt"))
texts += sorted(build.rglob("*.cmake"))
used = {}
for text in texts:
    for path in set(re.findall(r"/[^\s;\"'()<>$]+", text.read_text(errors="replace"))):
        for candidate in (path, os.path.realpath(path)):
            if candidate in owner:
                used.setdefault(candidate, owner[candidate])
for path, package in sorted(used.items())[:20]:
    print(f"ordinary build ({what}): the configure uses {path} (Debian package {package})")
sys.exit(1 if used else 0)
PY
done

# The README's two apt-get lists against common.sh's.
/usr/bin/python3 - "${#DEBIAN_BUILD_PACKAGES[@]}" "${DEBIAN_BUILD_PACKAGES[@]}" \
  "${DEBIAN_TEST_PACKAGES[@]}" <<'PY' || status=1
import re
import sys

count = int(sys.argv[1])
lists = {"build": sys.argv[2:2 + count], "test": sys.argv[2 + count:]}
text = open("README.md", encoding="utf-8").read()
section = re.search(r"^## In your catkin workspace\n(.*?)(?=^## )", text, re.S | re.M)
if not section:
    print("ordinary build: README.md has no section '## In your catkin workspace'")
    sys.exit(1)
commands = re.findall(r"apt-get install((?:[^\n]*\\\n)*[^\n]*)", section.group(1))
named = [[w for w in re.sub(r"\\\n", " ", c).split() if not w.startswith("-") and w != "\\"]
         for c in commands]
status = 0
if len(named) != 2:
    print(f"ordinary build: README.md's section names {len(named)} apt-get install lists, not 2 "
          "(the build's, then the tests')")
    sys.exit(1)
for (kind, expected), got in zip(lists.items(), named):
    if sorted(got) != sorted(expected):
        print(f"ordinary build: README.md's {kind} packages differ from scripts/common.sh's "
              f"DEBIAN_{kind.upper()}_PACKAGES: missing {sorted(set(expected) - set(got))}, "
              f"extra {sorted(set(got) - set(expected))}")
        status = 1
sys.exit(status)
PY
exit $status
