#!/usr/bin/env python3
"""Writes the seed corpus test/fuzz/corpus/<target>/: short inputs that decode (through
fuzz_support.h's ByteReader) to meaningful scenarios, so fuzzing starts from the configurations
and call sequences the node produces instead of from random bytes.
    python3 test/fuzz/make_seeds.py
The encoders below mirror the decoding in fuzz_*.cpp; keep them in step."""
import pathlib
import re
import struct

HERE = pathlib.Path(__file__).resolve().parent
# The integrators by code (fuzz_support.h's integratorCodes(): the rows of the core's table, in
# its order, a new method appended at the end): the targets pick a name by its index here.
# KINEMATIC and DYNAMIC: the methods that drive each model, each seeded once. All three are read
# from the table's source, a row being the text from its `IntegratorInfo m;` line to its
# `return m;` line;
# test/checks/integrator_lists.sh checks them against the built table, and the corpus against
# seeds().
TABLE = HERE.parents[1] / "src" / "core" / "numerics" / "integrator.cpp"


def table_rows():
    """(name, kinematic, dynamic) per row of the integrator table, in its order."""
    rows = []
    for text in re.split(r"^ *IntegratorInfo m;$", TABLE.read_text(), flags=re.M)[1:]:
        text = re.split(r"^ *return m;$", text, flags=re.M)[0]
        name = re.findall(r'^ *m\.name =\s*"([a-z0-9_]+)";$', text, re.M)
        if len(name) != 1:
            raise ValueError("%s: a row without one m.name line: %r" % (TABLE, text))
        rows.append((name[0], "m.kinematic_step = " in text, "m.dynamic_step = " in text))
    return rows


NAMES = [name for name, _, _ in table_rows()]
KINEMATIC = [name for name, kinematic, _ in table_rows() if kinematic]
DYNAMIC = [name for name, _, dynamic in table_rows() if dynamic]
SPECIAL = {0.0: 0, 1.0: 2, 0.5: 4, 1e-3: 5, 0.1: 7, 10.0: 8, 1e6: 11, 1e12: 12, 1e154: 14,
           1e200: 16, 1e300: 17, 1e-300: 21, 1.7e9: 24, float("nan"): 31, float("inf"): 33,
           2.0: 35, 3.0: 36, 20.0: 38, 4.0: 39}


def value(x):
    """ByteReader::value(): a special value when there is one, else a moderate one (1e-3
    steps, |x| < 32.768), else the raw bits."""
    for key, index in SPECIAL.items():
        if key == x or (key != key and x != x):
            return bytes([0, index])
    if abs(x) < 32.7 and abs(round(x * 1000) - x * 1000) < 1e-9:
        return bytes([1]) + struct.pack(">h", round(x * 1000))
    return bytes([2]) + struct.pack("<d", x)


def vec(*xs):
    return b"".join(value(x) for x in xs)


def quat(w, x, y, z):
    return vec(w, x, y, z)


# ByteReader::stamp() tags
NEXT_MS = bytes([7])            # last + 1e-3
REPEAT = bytes([1])             # last
BACK_HALF = bytes([2])          # last - 0.5
BACK_FAR = bytes([3])           # last - 5
def step(index):                # last + {1e-3, 5e-3, 1e-2, 0.1, 0.5, 1, 1 + 1e-9, 2}[index]
    return bytes([0, index])
def at(x):                      # absolute
    return bytes([5]) + value(x)
TINY = bytes([6, 1])            # last + denorm_min


# ---- kinematic: config, then ops (0-4 addSample, 5 burst, 6 setState, 7 reset)
def kin_config(integrator, epoch=False):
    return bytes([NAMES.index(integrator), 0, 0, 0, int(epoch)])

def kin_sample(stamp, rate=None):
    return bytes([0]) + stamp + (bytes([0]) if rate is None else bytes([1]) + vec(*rate))

def kin_burst(period_index, n):
    return bytes([5, period_index, n - 1])

def kin_set_state(stamp, q, w):
    return bytes([6]) + stamp + quat(*q) + vec(*w)


# ---- dynamic: body, config, then ops (0-2 advanceTo, 3 setTorque, 4 setRate, 5 setState,
# 6 reset, 7 timer)
def dyn_config(body_index, integrator, torque_input=False, max_step_index=None,
               initial_w=None, epoch=False):
    out = bytes([0, body_index, 0, NAMES.index(integrator), int(torque_input)])
    out += bytes([0]) if max_step_index is None else bytes([1, 1, max_step_index])
    out += bytes([0, 0, 0, 0, 0])  # tolerance, torque_timeout, max_dt, backward_jump, q
    out += bytes([0]) if initial_w is None else bytes([1, 1]) + vec(*initial_w)
    return out + bytes([int(epoch)])

def dyn_advance(stamp):
    return bytes([0]) + stamp

def dyn_torque(stamp, tau, fixed=False):
    return bytes([3]) + stamp + vec(*tau) + bytes([int(fixed)])

def dyn_rate(stamp, w):
    return bytes([4]) + stamp + vec(*w)

def dyn_timer(period_index, n):
    return bytes([7, period_index, n - 1])


# ---- parameters: one flag per field in declaration order, then the value
FIELDS = ["model", "integrator", "rate_input", "torque_input", "torque_frame", "torque_timeout",
          "inertia", "initial_orientation", "initial_angular_velocity", "fixed_frame",
          "body_frame", "publish_tf", "reverse_tf", "publish_rate", "max_step", "max_dt",
          "tolerance", "angular_velocity_stddev"]
CHOICES = {
    "model": ["auto", "kinematic", "dynamic", "", "Dynamic"],
    "integrator": NAMES + ["", "rk5"],
    "rate_input": ["imu", "twist", "none", "IMU"],
    "torque_frame": ["body", "fixed", "world"],
}

def params(epoch=False, **given):
    out = b""
    for field in FIELDS:
        if field not in given:
            out += bytes([0])
            continue
        x = given[field]
        out += bytes([1])
        if field in CHOICES:
            out += bytes([CHOICES[field].index(x)])
        elif isinstance(x, bool):
            out += bytes([int(x)])
        elif isinstance(x, list):
            if field == "inertia":
                out += bytes([0])  # not the {1, 2, 3} shortcut
            if field in ("initial_orientation", "initial_angular_velocity"):
                out += bytes([0]) + vec(*x)  # the expected size
            else:
                out += bytes([len(x)]) + b"".join(bytes([0]) + value(v) for v in x)
        else:
            out += bytes([0]) + value(x)  # a number given in full
    return out + bytes([int(epoch)])


def seeds():
    kinematic = {}
    for name in KINEMATIC + ["auto"]:
        kinematic[f"steady_{name}"] = (kin_config(name) + kin_sample(at(0.0)) +
                                       kin_burst(0, 32) + kin_burst(1, 16))
    kinematic["refused_dynamic_integrator"] = kin_config("dopri5")
    kinematic["time_policy"] = (kin_config("cf4", epoch=True) + kin_burst(0, 8) +
                                kin_sample(REPEAT) + kin_sample(BACK_HALF) +
                                kin_sample(step(6)) + kin_sample(step(5)) + kin_sample(BACK_FAR) +
                                kin_sample(TINY) + kin_burst(0, 4))
    kinematic["bad_values"] = (kin_config("cf4") + kin_burst(0, 4) +
                               kin_sample(NEXT_MS, (float("nan"), 0.0, 0.0)) +
                               kin_sample(NEXT_MS, (1e200, 0.0, 0.0)) +
                               kin_sample(NEXT_MS, (1e154, 1e154, 0.0)) +
                               kin_sample(at(float("inf"))) +
                               kin_set_state(NEXT_MS, (1e-300, 0, 0, 0), (0, 0, 0)) +
                               kin_set_state(NEXT_MS, (1.0, 0, 0, 1.0), (0.1, 0, 0)) +
                               kin_burst(0, 4) + bytes([7]) + kin_burst(2, 4))

    dynamic = {}
    for index, name in enumerate(DYNAMIC + ["auto"]):
        torque = name != "exact"
        ops = dyn_advance(at(0.0)) + dyn_timer(1, 16)
        if torque:
            ops += dyn_torque(NEXT_MS, (0.0, 0.5, 0.0), fixed=index % 2 == 1)
        ops += dyn_rate(step(2), (0.05, 4.0, 0.0)) + dyn_timer(1, 16)
        dynamic[f"t_handle_{name}"] = dyn_config(1, name, torque_input=torque,
                                                 initial_w=(0.05, 4.0, 0.0)) + ops
    dynamic["tensor_dopri5"] = (dyn_config(3, "dopri5", torque_input=True, max_step_index=1,
                                           initial_w=(1.0, 2.0, 3.0), epoch=True) +
                                dyn_advance(step(0)) + dyn_timer(0, 16) +
                                dyn_torque(BACK_HALF, (1.0, 0.0, 0.0)) + dyn_timer(2, 8))
    dynamic["time_policy"] = (dyn_config(2, "splitting4", torque_input=True) +
                              dyn_advance(at(1.7e9)) + dyn_timer(1, 4) + dyn_advance(REPEAT) +
                              dyn_advance(step(7)) + dyn_advance(BACK_FAR) +
                              dyn_torque(BACK_HALF, (0.0, 0.0, 1.0)) + bytes([6]) +
                              dyn_timer(2, 4))

    parameters = {
        "defaults": b"",
        "coning": params(model="kinematic", integrator="cf4"),
        "t_handle": params(model="dynamic", rate_input="none", inertia=[1.0, 2.0, 3.0],
                           initial_angular_velocity=[0.05, 4.0, 0.0], publish_rate=50.0),
        "spinning_top": params(model="dynamic", rate_input="none", torque_input=True,
                               torque_timeout=0.5, inertia=[1.0, 1.0, 0.5],
                               initial_orientation=[0.14943813247359922, 0.0, 0.0,
                                                    0.9887710779360422],
                               initial_angular_velocity=[0.0, 0.0, 20.0], max_step=0.005),
        "dopri5_rates": params(model="dynamic", integrator="dopri5", inertia=[2.0, 3.0, 4.0],
                               epoch=True),
    }
    return {"kinematic": kinematic, "dynamic": dynamic, "parameters": parameters}


def main():
    for target, files in seeds().items():
        folder = HERE / "corpus" / target
        folder.mkdir(parents=True, exist_ok=True)
        for old in folder.iterdir():
            old.unlink()
        for name, data in files.items():
            (folder / name).write_bytes(data)
        print(f"{folder}: {len(files)} seeds")


if __name__ == "__main__":
    main()
