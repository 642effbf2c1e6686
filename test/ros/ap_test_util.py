"""Helpers shared by the rostest nodes: waiting for conditions, recording the node's outputs,
and quaternion arithmetic for closed-form answers. Public interface only (topics, tf,
services, diagnostics)."""
import math
import threading
import time

import rospy
import tf2_ros
from attitude_propagator.msg import AttitudeState
from attitude_propagator.srv import SetState, SetStateRequest
from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import PoseWithCovarianceStamped, Quaternion, Vector3
from rosgraph_msgs.msg import Clock, Log
from sensor_msgs.msg import Imu
from std_srvs.srv import Empty
from tf2_msgs.msg import TFMessage


def wait_for(condition, timeout=10.0, what="condition"):
    """Polls condition() in wall time (valid under sim time too) until true or timeout."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        value = condition()
        if value:
            return value
        time.sleep(0.01)
    raise AssertionError("timed out after %.1f s waiting for %s" % (timeout, what))


# Quaternions as (x, y, z, w) tuples, Hamilton product, like ROS messages.
def qmul(a, b):
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return (aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
            aw * bw - ax * bx - ay * by - az * bz)


def qconj(q):
    return (-q[0], -q[1], -q[2], q[3])


def axis_angle(axis, angle):
    n = math.sqrt(sum(c * c for c in axis))
    s = math.sin(angle / 2.0) / n
    return (axis[0] * s, axis[1] * s, axis[2] * s, math.cos(angle / 2.0))


def qexp(v):
    """Exp of a rotation vector: the rotation by |v| about v."""
    n = math.sqrt(sum(c * c for c in v))
    return (0.0, 0.0, 0.0, 1.0) if n == 0.0 else axis_angle(v, n)


def rotation_angle(a, b):
    """Angle of the rotation a^c b, so q and -q compare equal."""
    d = qmul(qconj(a), b)
    return 2.0 * math.atan2(math.sqrt(d[0] ** 2 + d[1] ** 2 + d[2] ** 2), abs(d[3]))


def as_tuple(q):
    return (q.x, q.y, q.z, q.w)


def finite_quaternion(q):
    return all(math.isfinite(c) for c in as_tuple(q))


def make_imu(stamp, w, frame_id="base_link", covariance=None):
    msg = Imu()
    msg.header.stamp = stamp
    msg.header.frame_id = frame_id
    msg.angular_velocity = Vector3(*w)
    if covariance is not None:
        msg.angular_velocity_covariance = covariance
    msg.orientation_covariance[0] = -1.0
    return msg


def make_pose_fix(stamp, frame_id, q, rotation_covariance=None):
    """An orientation fix as PoseWithCovarianceStamped: q in frame_id, the 3x3 rotation
    covariance (row-major, about frame_id's axes) in rows and columns 3-5 of the 6x6."""
    msg = PoseWithCovarianceStamped()
    msg.header.stamp = stamp
    msg.header.frame_id = frame_id
    msg.pose.pose.orientation = Quaternion(*q)
    covariance = [0.0] * 36
    for i in range(3):
        covariance[7 * i] = 1.0  # the position's, which a fix ignores
    if rotation_covariance is not None:
        for i in range(3):
            for j in range(3):
                covariance[6 * (i + 3) + (j + 3)] = rotation_covariance[3 * i + j]
    msg.pose.covariance = covariance
    return msg


class Recorder:
    """Keeps every message of a topic by stamp (nanoseconds)."""

    def __init__(self, topic, msg_type):
        self.lock = threading.Lock()
        self.by_stamp = {}
        self.messages = []
        self.sub = rospy.Subscriber(topic, msg_type, self._cb, queue_size=100000)

    def _cb(self, msg):
        with self.lock:
            self.messages.append(msg)
            self.by_stamp.setdefault(msg.header.stamp.to_nsec(), []).append(msg)

    def at(self, stamp):
        with self.lock:
            return list(self.by_stamp.get(stamp.to_nsec(), []))

    def wait_at(self, stamp, timeout=10.0):
        return wait_for(lambda: self.at(stamp), timeout, "a message at %.3f on %s"
                        % (stamp.to_sec(), self.sub.name))[0]

    def count(self):
        with self.lock:
            return len(self.messages)


class RosoutLines:
    """rosout lines (level, text) per node name."""

    def __init__(self):
        self.lock = threading.Lock()
        self.lines = []
        self.sub = rospy.Subscriber("/rosout", Log, self._cb, queue_size=100000)

    def _cb(self, msg):
        with self.lock:
            self.lines.append((msg.name, msg.level, msg.msg))

    def of(self, node, level, text):
        with self.lock:
            return [m for n, lv, m in self.lines if n == node and lv == level and text in m]


class Diagnostics:
    """Latest diagnostic values per status name."""

    def __init__(self):
        self.lock = threading.Lock()
        self.values = {}
        self.sub = rospy.Subscriber("/diagnostics", DiagnosticArray, self._cb, queue_size=100)

    def _cb(self, msg):
        with self.lock:
            for status in msg.status:
                self.values[status.name] = {kv.key: kv.value for kv in status.values}

    def get(self, node, key):
        with self.lock:
            for name, values in self.values.items():
                if name.startswith(node.lstrip("/") + ":") and key in values:
                    return values[key]
        return None

    def counter(self, node, key):
        value = self.get(node, key)
        return None if value is None else int(value)

    def wait_counter(self, node, key, at_least, timeout=10.0):
        return wait_for(lambda: (self.counter(node, key) or 0) >= at_least, timeout,
                        "%s %s >= %d (now %s)" % (node, key, at_least, self.get(node, key)))


class NodeDiagnostics:
    """The latest diagnostic status of one node (level, message, values)."""

    def __init__(self, private_name):
        self.prefix = private_name.lstrip("/") + ":"
        self.lock = threading.Lock()
        self.latest = None
        self.sub = rospy.Subscriber("/diagnostics", DiagnosticArray, self._cb, queue_size=100)

    def _cb(self, msg):
        with self.lock:
            for status in msg.status:
                if status.name.startswith(self.prefix):
                    self.latest = (status.level, status.message,
                                   {kv.key: kv.value for kv in status.values})

    def get(self):
        with self.lock:
            return self.latest


class Node:
    """The public interface of one attitude_propagator instance in namespace ns."""

    def __init__(self, ns, name="attitude_propagator"):
        self.ns = ns
        self.name = "/%s/%s" % (ns, name)
        self.state = Recorder("/%s/attitude_state" % ns, AttitudeState)
        self._reset = rospy.ServiceProxy(self.name + "/reset", Empty)
        self._set_state = rospy.ServiceProxy(self.name + "/set_state", SetState)

    def wait_ready(self, timeout=20.0):
        rospy.wait_for_service(self.name + "/reset", timeout)
        wait_for(lambda: self.state.sub.get_num_connections() > 0, timeout,
                 self.name + " attitude_state connection")

    def reset(self):
        self._reset()

    def set_state(self, stamp, q=(0, 0, 0, 1), w=(0, 0, 0)):
        req = SetStateRequest()
        req.header.stamp = stamp
        req.orientation = Quaternion(*q)
        req.angular_velocity = Vector3(*w)
        return self._set_state(req)


def make_tf_buffer():
    buffer = tf2_ros.Buffer(cache_time=rospy.Duration(100000.0))
    listener = tf2_ros.TransformListener(buffer)
    return buffer, listener


def lookup(buffer, parent, child, stamp, timeout=10.0):
    """The rotation (x, y, z, w) of parent -> child at stamp, waiting in wall time."""
    def get():
        try:
            return buffer.lookup_transform(parent, child, stamp)
        except (tf2_ros.LookupException, tf2_ros.ExtrapolationException,
                tf2_ros.ConnectivityException):
            return None
    t = wait_for(get, timeout, "tf %s -> %s at %.3f" % (parent, child, stamp.to_sec()))
    return as_tuple(t.transform.rotation)


def wait_connected(pub, timeout=20.0):
    wait_for(lambda: pub.get_num_connections() > 0, timeout, "a subscriber on " + pub.name)


# ---- Shared by the robustness, grid and reconfiguration tests --------------------------------

NS_PER_S = 10 ** 9


def time_ns(ns):
    """rospy.Time from integer nanoseconds (exact, unlike a float of seconds)."""
    return rospy.Time(0, int(ns))


def call_with_timeout(fn, timeout=5.0, what="a call"):
    """fn() in a thread; fails instead of hanging when the other side does not answer."""
    result = {}

    def run():
        try:
            result["value"] = fn()
        except Exception as e:  # handed to the caller
            result["error"] = e
    thread = threading.Thread(target=run, daemon=True)
    thread.start()
    thread.join(timeout)
    if thread.is_alive():
        raise AssertionError("%s did not return within %.1f s" % (what, timeout))
    if "error" in result:
        raise result["error"]
    return result.get("value")


def check_finite_state(test, msg, unit_tol=1e-12):
    """An AttitudeState that can be used: finite numbers, a unit quaternion."""
    q = as_tuple(msg.orientation)
    test.assertTrue(all(math.isfinite(c) for c in q), "orientation %s" % (q,))
    test.assertLess(abs(math.sqrt(sum(c * c for c in q)) - 1.0), unit_tol, "|q| of %s" % (q,))
    w = (msg.angular_velocity.x, msg.angular_velocity.y, msg.angular_velocity.z)
    test.assertTrue(all(math.isfinite(c) for c in w), "angular_velocity %s" % (w,))
    test.assertTrue(math.isfinite(msg.kinetic_energy), "kinetic_energy %r" % msg.kinetic_energy)
    test.assertTrue(all(math.isfinite(c) for c in msg.orientation_covariance),
                    "orientation_covariance %s" % (msg.orientation_covariance,))


class TfRecorder:
    """Every transform on /tf whose parent or child is one of `frames`, in arrival order."""

    def __init__(self, frames):
        self.lock = threading.Lock()
        self.frames = set(frames)
        self.transforms = []
        self.sub = rospy.Subscriber("/tf", TFMessage, self._cb, queue_size=100000)

    def _cb(self, msg):
        with self.lock:
            for t in msg.transforms:
                if t.header.frame_id in self.frames or t.child_frame_id in self.frames:
                    self.transforms.append(t)

    def at(self, stamp):
        with self.lock:
            return [t for t in self.transforms if t.header.stamp == stamp]

    def since(self, stamp):
        with self.lock:
            return [t for t in self.transforms if t.header.stamp >= stamp]


class SimClock:
    """Publishes /clock in integer nanoseconds, only forwards."""

    def __init__(self, subscribers, start_ns):
        self.pub = rospy.Publisher("/clock", Clock, queue_size=100000)
        wait_for(lambda: self.pub.get_num_connections() >= subscribers, 30.0,
                 "%d subscribers on /clock" % subscribers)
        self.now_ns = None
        self.set(start_ns)

    def set(self, ns):
        self.now_ns = int(ns)
        self.pub.publish(Clock(clock=time_ns(self.now_ns)))

    def run(self, to_ns, step_ns, pause=0.001):
        """Steps the clock to to_ns (the last step may be shorter); pause: wall seconds
        between ticks, 0 for a burst."""
        while self.now_ns < to_ns:
            self.set(min(self.now_ns + step_ns, to_ns))
            if pause:
                time.sleep(pause)


class Stamps:
    """Increasing stamps (integer ns) for the inputs of one kinematic node, step_s apart."""

    def __init__(self, start_s, step_s=0.1):
        self.ns = start_s * NS_PER_S
        self.step = int(round(step_s * NS_PER_S))

    def next(self, steps=1):
        self.ns += steps * self.step
        return time_ns(self.ns)


def check_each(test, cases, check):
    """check(case) for every case, then one failure listing every case that failed. (Instead
    of unittest's subTest, whose failures the rosunit XML does not attribute to the test.)"""
    failures = []
    for case in cases:
        try:
            check(case)
        except AssertionError as e:
            failures.append("%r: %s" % (case, e))
    test.assertFalse(failures, "\n".join(failures))
