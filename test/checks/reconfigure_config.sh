#!/usr/bin/env bash
# cfg/AttitudePropagator.cfg stays in step with the parameters it mirrors: its defaults are
# those of config/default.yaml, each default lies within its bounds, and docs/parameters.md's
# table of the live parameters gives its bounds and defaults (its integrator choices:
# test/checks/integrator_lists.sh). Reads the Python module that the build generates, so it
# needs the built workspace (scripts/test.sh builds first).
source "$(dirname "${BASH_SOURCE[0]}")/../../scripts/common.sh"
source_ros
# Under catkin's run_tests (test/checks/junit.py) the workspace's environment is already set.
[ -n "${AP_CATKIN_ENV:-}" ] || source_workspace
cd "$REPO_DIR" || exit 1
/usr/bin/python3 - <<'PY'
import sys

import yaml
from attitude_propagator.cfg import AttitudePropagatorConfig as cfg

errors = []
defaults = yaml.safe_load(open("config/default.yaml"))
for name, value in cfg.defaults.items():
    if name not in defaults:
        errors.append("%s is not a parameter of config/default.yaml" % name)
    elif value != defaults[name]:
        errors.append("%s: default %r, config/default.yaml %r" % (name, value, defaults[name]))
    elif isinstance(value, float) and not cfg.min[name] <= value <= cfg.max[name]:
        errors.append("%s: default %r outside [%r, %r]" % (name, value, cfg.min[name],
                                                            cfg.max[name]))

# docs/parameters.md's table of the live parameters (what rqt_reconfigure shows): every cfg
# parameter once, with its slider ends and default.
doc = open("docs/parameters.md").read()
begin = doc.index("<!-- live parameters: checked against cfg/AttitudePropagator.cfg -->")
end = doc.index("<!-- end of live parameters -->")
rows = {}
for line in doc[begin:end].splitlines():
    cells = [c.strip() for c in line.strip().strip("|").split("|")]
    if len(cells) == 4 and cells[0].startswith("`"):
        rows[cells[0].strip("`")] = cells[1:]
if set(rows) != set(cfg.defaults):
    errors.append("docs/parameters.md live table lists %s; the cfg has %s"
                  % (sorted(rows), sorted(cfg.defaults)))
for name, (low, high, default) in rows.items():
    if name not in cfg.defaults:
        continue
    value = cfg.defaults[name]
    if isinstance(value, float):
        expected = [repr(cfg.min[name]), repr(cfg.max[name]), repr(value)]
        if [repr(float(x)) for x in (low, high, default)] != expected:
            errors.append("docs/parameters.md live table: %s %s, cfg %s"
                          % (name, [low, high, default], expected))
    elif default != str(value):
        errors.append("docs/parameters.md live table: %s default %s, cfg %s"
                      % (name, default, value))

for line in errors:
    print("reconfigure config:", line)
sys.exit(1 if errors else 0)
PY
