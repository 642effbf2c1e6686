#!/usr/bin/python3
"""The node and propagate_bag, message for message (node_vs_bag.test).

Both decode every message through the message layer and drive the core engine, so the same
messages in the same order on the same clock must give the same states and the same counters.
Each test writes a bag (with record times), runs propagate_bag on it with the parameters the
node runs with (read back from its private namespace), then publishes the bag's messages to
the node one at a time in record order and compares every state (orientation and angular
velocity within 1e-12, every other field exactly: the same libraries make both) and every
counter both report.

The order the node sees is the bag's by construction, not by timing: each message is published
synchronously and the next one waits until the node has acted on it, i.e.
- until the node has published as many states as propagate_bag had written by that message's
  record time (propagate_bag writes a state at the record time of the message that made it due),
- or, when that message makes no state due and the next one comes on another topic, until a
  call of the node's ~set_parameters service (no change: dynamic_reconfigure calls back with the
  values in force) returns. roscpp reads the request on a connection opened after the message
  was already in the node's socket, and puts both callbacks on the node's one callback queue in
  the order read, so the message's callback has run when the call returns. Messages on one
  topic come through one connection, in order, and need no call between them.
The one exception is the node's tf listener, which runs its own thread: the transform that first
gives the mount is followed by a settle time (a mount cached once stops the listener).
"""
import math
import os
import re
import shutil
import subprocess
import tempfile
import threading
import time
import unittest
import warnings

import rosbag
import rosgraph
import rospkg
import rospy
import rostest
import yaml
from attitude_propagator.msg import AttitudeState
from catkin.find_in_workspaces import find_in_workspaces
from diagnostic_msgs.msg import DiagnosticArray
from dynamic_reconfigure.srv import Reconfigure, ReconfigureRequest
from geometry_msgs.msg import Quaternion, TransformStamped, Vector3, Vector3Stamped, WrenchStamped
from rosgraph_msgs.msg import Clock
from tf2_msgs.msg import TFMessage

from ap_test_util import (NS_PER_S, Recorder, as_tuple, axis_angle, call_with_timeout,
                          make_imu, qconj, qmul, time_ns, wait_for)

T0 = 100 * NS_PER_S
MS = 10 ** 6
US = 10 ** 3
# The mount, body <- imu: no symmetric case, so C and its transpose (or a wrong axis) differ.
MOUNT = axis_angle((1.0, 2.0, 3.0), 0.7)
# The gyro bias sample that is used, in the mount's frame (rad/s).
BIAS_IN_MOUNT = (0.01, -0.02, 0.015)
# Agreement asked of the two: the same code on the same doubles, so round-off at most.
TOLERANCE = 1e-12
# Waiting for the node to act on one message (wall s): generous, the machine is shared.
PACE_TIMEOUT = 20.0
# After the transform that first gives the mount: the listener's own thread stores it.
LISTENER_SETTLE = 2.0

# The drops propagate_bag's summary may name (under the node's diagnostics keys, the core's
# counter table): each is 0 when the summary names none.
DROPS = ("rejected_non_finite", "rejected_out_of_range", "rejected_no_rate", "rejected_type",
         "rejected_covariance", "dropped_stale", "dropped_no_tf", "dropped_no_time",
         "rejected_future", "held_ahead", "dropped_on_reset", "pending_overflow")


def rotation_angle_exact(a, b):
    """2 asin |vec(a^-1 b)|: the angle between two orientations (q and -q alike)."""
    d = qmul(qconj(a), b)
    return 2.0 * math.asin(min(1.0, math.sqrt(d[0] ** 2 + d[1] ** 2 + d[2] ** 2)))


def subscriber_count(topic):
    """How many nodes the master lists as subscribers of topic."""
    subscribers = rosgraph.Master(rospy.get_name()).getSystemState()[1]
    return sum(len(nodes) for name, nodes in subscribers if name == topic)


def fields(state):
    """An AttitudeState's fields but the header's sequence number, as plain values."""
    return {"stamp": state.header.stamp.to_nsec(), "frame_id": state.header.frame_id,
            "child_frame_id": state.child_frame_id, "orientation": as_tuple(state.orientation),
            "orientation_covariance": tuple(state.orientation_covariance),
            "angular_velocity": vector(state.angular_velocity),
            "angular_momentum": vector(state.angular_momentum),
            "kinetic_energy": state.kinetic_energy, "norm_error": state.norm_error,
            "model": state.model, "integrator": state.integrator, "steps": state.steps}


def vector(v):
    return (v.x, v.y, v.z)


def stamp_index(states):
    """State by stamp (ns); None where a stamp repeats."""
    at = {}
    for m in states:
        t = m.header.stamp.to_nsec()
        at[t] = None if t in at else m
    return at


class Scene:
    """A bag's messages: (record time ns, topic, message), strictly increasing record times."""

    def __init__(self):
        self.events = []

    def add(self, record_ns, topic, msg):
        self.events.append((int(record_ns), topic, msg))

    def sorted_events(self):
        events = sorted(self.events, key=lambda e: e[0])
        times = [e[0] for e in events]
        assert len(set(times)) == len(times), "two messages at one record time"
        return events

    def write(self, path):
        with rosbag.Bag(path, "w") as bag:
            for record, topic, msg in self.sorted_events():
                bag.write(topic, msg, t=time_ns(record))


def clock(ns):
    return Clock(clock=time_ns(ns))


def rate_in_imu_frame(t):
    """A smooth body rate (rad/s) about all three axes, as the mounted IMU reads it."""
    return (0.4 * math.sin(2.0 * t), 0.3 * math.cos(3.0 * t), 0.5 + 0.1 * math.sin(t))


# A full covariance, cross terms included: rotated into the body as C R C^T.
RATE_COVARIANCE = [1e-4, 1e-5, 0.0, 1e-5, 2e-4, -2e-5, 0.0, -2e-5, 3e-4]


def kinematic_scene():
    """200 Hz IMU in frame imu_kin, its mount on /tf from 12.5 ms on (the first three samples
    have no transform yet), gyro bias samples (one used, one before the mount is known, one in
    a wrong frame), a straggler, NaN, REP-145 and far-future samples, a gap of 0.3 s (max_dt
    0.05 s), and the stamps jumping back by 1.5 s at 2 s and going on; /clock at 10 Hz."""
    s = Scene()
    for k in range(31):
        s.add(T0 + k * 100 * MS, "/clock", clock(T0 + k * 100 * MS))

    def imu(stamp_ns, w, covariance=RATE_COVARIANCE):
        return make_imu(time_ns(stamp_ns), w, "imu_kin", list(covariance))

    for i in range(600):
        t_ms = 5 * i
        if 1200 < t_ms < 1500:
            continue  # a gap longer than max_dt
        stamp = T0 + t_ms * MS - (1500 * MS if t_ms >= 2000 else 0)  # jumped back, going on
        s.add(T0 + t_ms * MS + MS, "/imu/data_raw", imu(stamp, rate_in_imu_frame(t_ms * 1e-3)))
    s.add(T0 + 802500 * US, "/imu/data_raw", imu(T0 + 800 * MS, (0.1, 0.2, 0.3)))  # straggler
    s.add(T0 + 902500 * US, "/imu/data_raw",
          imu(T0 + 902500 * US, (float("nan"), 0.0, 0.0)))
    no_rate = imu(T0 + 952500 * US, (0.1, 0.2, 0.3))
    no_rate.angular_velocity_covariance[0] = -1.0  # REP-145: no rate
    s.add(T0 + 952500 * US, "/imu/data_raw", no_rate)
    # The clock is at 1.0 s: a stamp 1.6 s ahead is beyond max_future (1 s).
    s.add(T0 + 1002500 * US, "/imu/data_raw", imu(T0 + 2600 * MS, (0.1, 0.2, 0.3)))
    for k in range(15):
        t = TransformStamped()
        t.header.stamp = time_ns(T0 + 12500 * US + k * 200 * MS)
        t.header.frame_id = "body_kin"
        t.child_frame_id = "imu_kin"
        t.transform.rotation = Quaternion(*MOUNT)
        s.add(t.header.stamp.to_nsec(), "/tf", TFMessage(transforms=[t]))

    def bias(record_ns, stamp_ns, frame, value):
        msg = Vector3Stamped()
        msg.header.stamp = time_ns(stamp_ns)
        msg.header.frame_id = frame
        msg.vector = Vector3(*value)
        s.add(record_ns, "/gyro_bias", msg)

    bias(T0 + 7500 * US, T0 + 7500 * US, "imu_kin", (0.02, 0.0, 0.0))  # mount not known yet
    bias(T0 + 503500 * US, T0 + 600 * MS, "imu_kin", BIAS_IN_MOUNT)  # from 0.6 s on
    bias(T0 + 700500 * US, T0 + 700500 * US, "elsewhere", (0.03, 0.0, 0.0))  # wrong frame
    return s


def mount_first_scene():
    """0.5 s of a 200 Hz IMU in frame imu_early whose mount is on /tf at 10 Hz from the start,
    before the first rate (as in any recording of a running robot); /clock at 20 Hz."""
    s = Scene()
    for k in range(11):
        s.add(T0 + k * 50 * MS, "/clock", clock(T0 + k * 50 * MS))
    for i in range(100):
        s.add(T0 + 5 * i * MS + MS, "/imu/data_raw",
              make_imu(time_ns(T0 + 5 * i * MS), rate_in_imu_frame(5e-3 * i), "imu_early"))
    for k in range(5):
        t = TransformStamped()
        t.header.stamp = time_ns(T0 + k * 100 * MS + 500 * US)
        t.header.frame_id = "body_early"
        t.child_frame_id = "imu_early"
        t.transform.rotation = Quaternion(*MOUNT)
        s.add(t.header.stamp.to_nsec(), "/tf", TFMessage(transforms=[t]))
    return s


def dynamic_scene():
    """/clock at 100 Hz (3 ms past the 100 Hz grid) with a jump of 0.3 s at 1.5 s (max_dt
    0.1 s); WrenchStamped torques in the body at 20 Hz stamped 19 ms after their record time
    (they wait for the clock), one stamped before the clock (late), and from 2.2 s on stamps
    1.5 s back, going on (late input on ROS time, the two that confirm the jump too); at 3 s
    the clock jumps back by 2 s (a reset) and goes on for 0.3 s with torques."""
    s = Scene()
    for k in range(300):
        tick = T0 + 3 * MS + k * 10 * MS
        if T0 + 1503 * MS < tick < T0 + 1803 * MS:
            continue  # the clock jumps ahead: a gap
        s.add(tick, "/clock", clock(tick))
    for j in range(60):
        record = T0 + j * 50 * MS + MS
        if T0 + 1503 * MS < record < T0 + 1803 * MS:
            continue
        stamp = record + 19 * MS
        if j == 20:
            stamp = T0 + 980 * MS  # the clock is at 0.993 s: late
        if record >= T0 + 2200 * MS:
            stamp -= 1500 * MS
        msg = WrenchStamped()
        msg.header.stamp = time_ns(stamp)
        msg.header.frame_id = "body_dyn"
        msg.wrench.torque = Vector3(0.2 * math.sin(j / 5.0), 0.1 * math.cos(j / 7.0), -0.15)
        s.add(record, "/torque", msg)
    # Then the clock jumps back by 2 s (a looped bag) and goes on for 0.3 s, torques with it.
    for k in range(31):
        s.add(T0 + 3003 * MS + k * 10 * MS, "/clock", clock(T0 + 1003 * MS + k * 10 * MS))
    for j in range(6):
        msg = WrenchStamped()
        msg.header.stamp = time_ns(T0 + 1020 * MS + j * 50 * MS)
        msg.header.frame_id = "body_dyn"
        msg.wrench.torque = Vector3(0.0, 0.05 * j, 0.1)
        s.add(T0 + 3006 * MS + j * 50 * MS, "/torque", msg)
    return s


def named_counts(text):
    """{name: n} of a summary's "name n, name n" list ("none": empty)."""
    if text == "none":
        return {}
    return {name: int(n) for name, n in (part.rsplit(" ", 1) for part in text.split(", "))}


def tool_summary(text):
    """propagate_bag's counters: its summary names them as the node's diagnostics do."""
    c = {key: 0 for key in DROPS}
    m = re.search(r"(\d+) accepted, dropped: ([^;]*); ([^;]*); (\d+) states", text)
    assert m, text
    c["accepted"] = int(m.group(1))
    c.update(named_counts(m.group(2)))
    c.update(named_counts(m.group(3)))  # resets, jumps_back, gaps, late
    m = re.search(r"inputs: (\d+) = \d+ accepted \+ \d+ dropped \+ (\d+) pending", text)
    assert m, text
    c["received"], c["pending"] = int(m.group(1)), int(m.group(2))
    m = re.search(r"dynamic: (failed_steps \d+), pending \d+ \(.*?\), (deferred_ticks \d+)", text)
    if m:
        c.update(named_counts(m.group(1) + ", " + m.group(2)))
    m = re.search(r"gyro bias: ([^(]*) \(", text)
    if m:
        c.update(named_counts(m.group(1)))  # bias_applied, rejected_bias, bias_queue_full
    return c


class Barrier:
    """Returns once the node has run every callback for what was published before the call
    (see the module's text): a ~set_parameters call that changes nothing, on a new connection."""

    def __init__(self, node_name):
        self.service = node_name + "/set_parameters"
        rospy.wait_for_service(self.service, 30.0)
        self.calls = 0

    def __call__(self):
        self.calls += 1
        proxy = rospy.ServiceProxy(self.service, Reconfigure)  # not persistent: a new connection
        call_with_timeout(lambda: proxy(ReconfigureRequest()), 30.0, self.service)


class LatestDiagnostics:
    """The latest diagnostic values of one node, and how many statuses came."""

    def __init__(self, node_name):
        self.prefix = node_name.lstrip("/") + ":"
        self.lock = threading.Lock()
        self.values, self.count = None, 0
        self.sub = rospy.Subscriber("/diagnostics", DiagnosticArray, self._cb, queue_size=100)

    def _cb(self, msg):
        with self.lock:
            for status in msg.status:
                if status.name.startswith(self.prefix):
                    self.values = {kv.key: kv.value for kv in status.values}
                    self.count += 1

    def after_now(self):
        """Values computed after everything published so far was handled: the second status
        from now (one may be on its way)."""
        with self.lock:
            start = self.count
        wait_for(lambda: self.count >= start + 2, 20.0, self.prefix + " diagnostics")
        with self.lock:
            return dict(self.values)


class NodeVsBagTest(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        rospy.init_node("test_node_vs_bag")
        cls.dir = tempfile.mkdtemp(prefix="node_vs_bag_")
        cls.default_keys = list(yaml.safe_load(open(os.path.join(
            rospkg.RosPack().get_path("attitude_propagator"), "config", "default.yaml"))))

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.dir, ignore_errors=True)

    # ---- the two runs ------------------------------------------------------------------------

    def run_tool(self, name, scene, node_name):
        """Writes the bag, runs propagate_bag with the node's parameters; its states (record
        time ns, AttitudeState) and counters."""
        bag = os.path.join(self.dir, name + ".bag")
        out = os.path.join(self.dir, name + ".out.bag")
        config = os.path.join(self.dir, name + ".yaml")
        scene.write(bag)
        params = rospy.get_param(node_name)
        with open(config, "w") as f:
            yaml.safe_dump({k: params[k] for k in self.default_keys if k in params}, f)
        found = find_in_workspaces(search_dirs=["libexec"], project="attitude_propagator",
                                   path="propagate_bag", first_match_only=True)
        self.assertTrue(found, "propagate_bag not built")
        started = time.monotonic()
        run = subprocess.run([found[0], bag, "-o", out, "--config", config, "--no-progress"],
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                             universal_newlines=True, timeout=120)
        print("%s: propagate_bag in %.2f s:\n%s%s" % (name, time.monotonic() - started,
                                                       run.stdout, run.stderr))
        self.assertEqual(run.returncode, 0, run.stdout + run.stderr)
        with rosbag.Bag(out) as b:
            states = [(t.to_nsec(), m) for _, m, t in b.read_messages(topics=["/attitude_state"])]
        return states, tool_summary(run.stdout)

    def run_node(self, scene, ns, tool_states, listener_topic=None, pace_on_states=True):
        """Publishes the scene to the node in record order, each message once the node has acted
        on the one before; the node's states and counters. pace_on_states False: every message
        waits for the barrier (where the node is known to publish fewer states)."""
        node_name = "/%s/attitude_propagator" % ns
        barrier = Barrier(node_name)  # advertised after the node subscribed to its inputs
        states = Recorder("/%s/attitude_state" % ns, AttitudeState)
        diagnostics = LatestDiagnostics(node_name)
        wait_for(lambda: states.sub.get_num_connections() > 0, 30.0, "attitude_state")
        events = scene.sorted_events()
        # Published synchronously (no queue_size): the message is in the node's socket when
        # publish() returns, before the barrier's connection is opened.
        pubs = {}
        for topic in sorted({e[1] for e in events}):
            target = topic if topic == "/tf" else "/%s%s" % (ns, topic)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")  # rospy's advice to give a queue_size
                pubs[topic] = rospy.Publisher(
                    target, type(next(e[2] for e in events if e[1] == topic)), queue_size=None)
        for pub in pubs.values():
            # Every node subscribed (the other nodes' tf watches hear /tf too), connected.
            wait_for(lambda: pub.get_num_connections() >= max(1, subscriber_count(pub.name)),
                     30.0, "every subscriber on " + pub.name)
        # States propagate_bag had written by each record time: the node's pace.
        due, n = [], 0
        for record, _, _ in events:
            while n < len(tool_states) and tool_states[n][0] <= record:
                n += 1
            due.append(n)
        paced_on_states, stalled, rates_sent = 0, None, False
        started = time.monotonic()
        for i, (record, topic, msg) in enumerate(events):
            # The node's tf listener, created by the first rate in the mount's frame, shares the
            # connection of the node's tf watch (one subscription per topic in a process), so it
            # hears what follows that rate; until the node has a state, what it hears may be
            # the mount, which its own thread stores (the settle time below).
            first_mount = topic == listener_topic and states.count() == 0 and rates_sent
            rates_sent = rates_sent or topic not in (listener_topic, "/clock", "/gyro_bias")
            pubs[topic].publish(msg)
            if pace_on_states and stalled is None and due[i] > (due[i - 1] if i else 0):
                try:
                    wait_for(lambda: states.count() >= due[i], PACE_TIMEOUT,
                             "%d states after message %d (%s at %.4f s)"
                             % (due[i], i, topic, (record - T0) * 1e-9))
                    paced_on_states += 1
                    continue
                except AssertionError as e:
                    stalled = str(e)  # the comparison below shows how; pace on the barrier now
            if first_mount or i + 1 == len(events) or events[i + 1][1] != topic:
                barrier()  # the next message comes on another connection: wait for this one
            if first_mount:
                time.sleep(LISTENER_SETTLE)
        barrier()
        try:  # the node has published all; wait for them to arrive
            wait_for(lambda: states.count() >= len(tool_states),
                     10.0 if pace_on_states and stalled is None else 2.0,
                     "%d states" % len(tool_states))
        except AssertionError:
            pass  # fewer states: the comparison says which
        time.sleep(0.5)  # anything the node would publish beyond the tool's states
        counters = diagnostics.after_now()
        print("%s: %d messages fed in %.1f s (%d paced on states, %d barriers)%s"
              % (ns, len(events), time.monotonic() - started, paced_on_states, barrier.calls,
                 "; pacing stalled: " + stalled if stalled else ""))
        with states.lock:
            return list(states.messages), counters, stalled

    # ---- the comparisons ---------------------------------------------------------------------

    def state_differences(self, name, node_states, tool_states):
        """Every state compared: by position when both published as many, otherwise at the
        stamps each published once (a reset may repeat stamps)."""
        tool = [m for _, m in tool_states]
        problems = []
        if len(node_states) == len(tool):
            pairs = list(zip(node_states, tool))
        else:
            problems.append("%d states from the node, %d from propagate_bag"
                            % (len(node_states), len(tool)))
            node_at, tool_at = stamp_index(node_states), stamp_index(tool)
            for who, mine, other in (("node", node_at, tool_at),
                                     ("propagate_bag", tool_at, node_at)):
                only = sorted(set(mine) - set(other))
                if only:
                    problems.append("%d stamps from the %s only, %.4f s to %.4f s after T0"
                                    % (len(only), who, (only[0] - T0) * 1e-9,
                                       (only[-1] - T0) * 1e-9))
            pairs = [(node_at[t], tool_at[t]) for t in sorted(set(node_at) & set(tool_at))
                     if node_at[t] is not None and tool_at[t] is not None]
        worst_angle = worst_rate = 0.0
        identical = 0  # orientation and angular velocity equal to the last bit
        same_fields = 0  # every field of the state
        for i, (a, b) in enumerate(pairs):
            if a.header.stamp != b.header.stamp:
                problems.append("state %d: stamp %d (node) != %d (propagate_bag)"
                                % (i, a.header.stamp.to_nsec(), b.header.stamp.to_nsec()))
                continue
            angle = rotation_angle_exact(as_tuple(a.orientation), as_tuple(b.orientation))
            rate = max(abs(x - y) for x, y in zip(vector(a.angular_velocity),
                                                  vector(b.angular_velocity)))
            worst_angle, worst_rate = max(worst_angle, angle), max(worst_rate, rate)
            identical += (as_tuple(a.orientation) == as_tuple(b.orientation) and
                          vector(a.angular_velocity) == vector(b.angular_velocity))
            if not angle <= TOLERANCE or not rate <= TOLERANCE:
                problems.append("state %d at %.4f s after T0: orientation %.3g rad, angular "
                                "velocity %.3g rad/s apart" % (i, (a.header.stamp.to_nsec() - T0)
                                                               * 1e-9, angle, rate))
            fa, fb = fields(a), fields(b)
            same_fields += fa == fb
            # The rest comes from the same libraries through the same encoder: equal exactly.
            for field in sorted(set(fa) - {"orientation", "angular_velocity"}):
                if fa[field] != fb[field]:
                    problems.append("state %d: %s %s (node) != %s (propagate_bag)"
                                    % (i, field, fa[field], fb[field]))
        print("%s: %d states compared, %d identical to the bit (%d in every field); largest "
              "difference %.3g rad, %.3g rad/s" % (name, len(pairs), identical, same_fields,
                                                   worst_angle, worst_rate))
        return problems

    def counter_differences(self, name, node, tool):
        print("%s: propagate_bag's counters %s" % (name, sorted(tool.items())))
        return ["%s: node %s, propagate_bag %d" % (key, node.get(key), value)
                for key, value in sorted(tool.items()) if node.get(key) != str(value)]

    def assertAgree(self, name, node_states, node_counters, tool_states, tool_counters):
        problems = (self.counter_differences(name, node_counters, tool_counters) +
                    self.state_differences(name, node_states, tool_states))
        if problems:
            self.fail("%s: the node and propagate_bag differ (%d):\n%s"
                      % (name, len(problems), "\n".join(problems[:12])))

    def assertHappened(self, counters, expected):
        """The scene did what it was written to do (design.md §6-§7), in propagate_bag's count."""
        wrong = ["%s %d, expected %d" % (k, counters.get(k, -1), v)
                 for k, v in expected.items() if counters.get(k) != v]
        self.assertFalse(wrong, "the scene's events: " + "; ".join(wrong))

    # ---- the set-ups -------------------------------------------------------------------------

    def test_kinematic_node_and_propagate_bag_agree(self):
        scene = kinematic_scene()
        tool_states, tool = self.run_tool("kinematic", scene, "/kin/attitude_propagator")
        self.assertHappened(tool, {"dropped_no_tf": 3, "rejected_bias": 2, "bias_applied": 1,
                                   "dropped_stale": 1, "rejected_non_finite": 1,
                                   "rejected_no_rate": 1, "rejected_future": 1, "gaps": 1,
                                   "jumps_back": 1, "resets": 1})
        node_states, node, _ = self.run_node(scene, "kin", tool_states, listener_topic="/tf")
        self.assertAgree("kinematic", node_states, node, tool_states, tool)
        # The bias the node uses is the mount-frame sample turned into the body, C b
        # (diagnostics print 6 digits).
        b = qmul(qmul(MOUNT, BIAS_IN_MOUNT + (0.0,)), qconj(MOUNT))[:3]
        used = [float(x) for x in node["gyro_bias"].strip("[]").split(",")]
        self.assertLess(max(abs(x - y) for x, y in zip(used, b)), 1e-7, (used, b))

    def test_mount_on_tf_before_the_first_rate_agrees(self):
        """A mount on /tf recorded before the first rate: propagate_bag has heard it when the
        first rate comes and accepts every rate; so does the node, which listens to tf from its
        start (a listener started at the first rate would drop the rates until the mount's next
        message on /tf: here 20 at 200 Hz, /tf at 10 Hz)."""
        scene = mount_first_scene()
        tool_states, tool = self.run_tool("mount_first", scene, "/early/attitude_propagator")
        self.assertHappened(tool, {"accepted": 100, "dropped_no_tf": 0})
        node_states, node, _ = self.run_node(scene, "early", tool_states, listener_topic="/tf",
                                             pace_on_states=False)
        self.assertAgree("mount_first", node_states, node, tool_states, tool)

    def test_dynamic_node_and_propagate_bag_agree(self):
        scene = dynamic_scene()
        tool_states, tool = self.run_tool("dynamic", scene, "/dyn/attitude_propagator")
        self.assertHappened(tool, {"dropped_stale": 0, "jumps_back": 1, "resets": 1})
        self.assertGreaterEqual(tool["late"], 1)
        self.assertGreaterEqual(tool["gaps"], 1)
        node_states, node, _ = self.run_node(scene, "dyn", tool_states)
        self.assertAgree("dynamic", node_states, node, tool_states, tool)


if __name__ == "__main__":
    rostest.rosrun("attitude_propagator", "node_vs_bag", NodeVsBagTest)
