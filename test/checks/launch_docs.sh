#!/usr/bin/env bash
# docs/node.md's table of launch arguments names exactly the <arg>s each launch file declares
# (launch/*.launch, launch/examples/*.launch; an <arg> inside an <include> passes a value on and
# declares nothing), and every launch file has its row. Reads the files only.
source "$(dirname "${BASH_SOURCE[0]}")/../../scripts/common.sh"
cd "$REPO_DIR" || exit 1
/usr/bin/python3 - <<'PY'
import glob
import re
import sys
import xml.etree.ElementTree as ET


def declared(path):
    tree = ET.parse(path)
    inside = {id(a) for inc in tree.iter("include") for a in inc.iter("arg")}
    return [a.get("name") for a in tree.iter("arg") if id(a) not in inside]


rows = {}
for line in open("docs/node.md", encoding="utf-8"):
    m = re.match(r"^\| `(launch/[^`]+\.launch)` \| (.*) \|\s*$", line)
    if m:
        rows[m.group(1)] = re.findall(r"`([^`]+)`", m.group(2))
status = 0
files = sorted(glob.glob("launch/*.launch") + glob.glob("launch/examples/*.launch"))
for path in files:
    if path not in rows:
        print("docs/node.md: no row for %s in the table of launch arguments" % path)
        status = 1
        continue
    args, documented = declared(path), rows[path]
    missing = [a for a in args if a not in documented]
    extra = [a for a in documented if a not in args]
    if missing:
        print("docs/node.md: %s declares %s, not in its row" % (path, ", ".join(missing)))
        status = 1
    if extra:
        print("docs/node.md: %s's row names %s, which it does not declare" %
              (path, ", ".join(extra)))
        status = 1
for path in sorted(set(rows) - set(files)):
    print("docs/node.md: a row for %s, which does not exist" % path)
    status = 1
sys.exit(status)
PY
