#!/usr/bin/env bash
# cfg/AttitudePropagator.cfg stays in step with the parameters it mirrors: its defaults are
# those of config/default.yaml and each default lies within its bounds (its integrator choices:
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

for line in errors:
    print("reconfigure config:", line)
sys.exit(1 if errors else 0)
PY
