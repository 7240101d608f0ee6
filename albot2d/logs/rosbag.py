"""ROS bags as albot2d frames: the topic and frame conventions, and the bag reader.

:func:`read_bag` reads a ROS 1 bag (``.bag``) or a ROS 2 bag (a directory with
``metadata.yaml``, one without it holding one storage file, or one ``.mcap`` / ``.db3``
storage file) with the pure-Python ``rosbags`` library (no ROS install) and turns each
``sensor_msgs/msg/LaserScan`` on the scan topic into one :class:`~albot2d.frames.Frame`,
stamped with the message's header stamp (its record time in the bag when the header stamp
is zero, as some drivers leave it):

- Odometry: the ``nav_msgs/msg/Odometry`` of the odometry topic; when the bag has no such
  topic, the ``/tf`` transforms from ``odom`` to the robot's base frame (``base_link`` or
  ``base_footprint``). Poses are interpolated linearly (heading along the shorter turn) to
  each scan's stamp; scans before the first or after the last odometry stamp are dropped
  and counted (:attr:`BagFrames.scans_without_odometry`).
- Mount: the laser's pose in the base frame, from the chain of ``/tf_static`` (or, as in
  older ROS 1 bags, constant ``/tf``) transforms between the scan's ``frame_id`` and the
  base frame; the identity when the bag has none. The chain is composed in 3-D: a laser
  mounted upside down has its beams mirrored, one whose scan plane is tilted more than
  :data:`MAX_MOUNT_TILT_RAD` is refused.
- Beams: angles ``angle_min + k·angle_increment`` (spread evenly to ``angle_max`` when that
  agrees, which undoes the float32 rounding of the increment); a clockwise scan
  (negative increment) is reversed into albot2d's counter-clockwise order. A beam is valid
  when ``range_min <= r <= range_max`` and ``r > 0`` (REP-117); ``±inf`` (REP-117's "no
  return" codes) are invalid and stored as ``range_max``, while NaN and negative ranges are
  kept and counted as anomalies by ``albot2d.logs.anomalies`` like a CARMEN log's.

Limits are the CARMEN reader's (``albot2d.logs.carmen``): at most ``MAX_BEAMS`` ranges per
scan (also the longest sequence the deserialiser will allocate), angles within a turn,
ranges and poses within ``COORDINATE_LIMIT_M``. Anything wrong — a truncated or corrupt
file, a missing topic (the error names the topics the bag has), a topic of another type,
no scans, no odometry — raises :class:`~albot2d.errors.InputError` naming the bag.
"""

from __future__ import annotations

import contextlib
import math
import os
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from albot2d.errors import InputError
from albot2d.frames import Frame, Scan
from albot2d.geometry import Pose
from albot2d.geometry.pose import wrap_angle
from albot2d.logs.carmen import ANGLE_LIMIT_RAD, MAX_BEAMS, TIMESTAMP_LIMIT_S
from albot2d.validation import COORDINATE_LIMIT_M

__all__ = [
    "BAG_SUFFIXES",
    "BASE_FRAME",
    "DEFAULT_ODOM_TOPIC",
    "DEFAULT_SCAN_TOPIC",
    "GROUND_TRUTH_TOPIC",
    "LASER_FRAME",
    "MAP_FRAME",
    "MAX_MOUNT_TILT_RAD",
    "ODOM_FRAME",
    "TF_STATIC_TOPIC",
    "TF_TOPIC",
    "BagFrames",
    "is_bag",
    "read_bag",
    "require_rosbags",
    "typestore_for",
]

DEFAULT_SCAN_TOPIC = "/scan"
DEFAULT_ODOM_TOPIC = "/odom"
GROUND_TRUTH_TOPIC = "/ground_truth"
TF_TOPIC = "/tf"
TF_STATIC_TOPIC = "/tf_static"
MAP_FRAME = "map"
ODOM_FRAME = "odom"
BASE_FRAME = "base_link"
LASER_FRAME = "laser"
#: Largest tilt of a laser's scan plane from the base's (a mount a few degrees off level
#: still sees the walls a planar scan would; beyond, beams hit the floor or the ceiling).
MAX_MOUNT_TILT_RAD = math.radians(10.0)
#: Base frames looked for under ``odom`` in ``/tf`` when a bag has no odometry topic.
TF_BASE_FRAMES = (BASE_FRAME, "base_footprint")
#: Suffixes of bag files: ROS 1, then ROS 2's two storage files.
BAG_SUFFIXES = (".bag", ".mcap", ".db3")
_MAGIC = {b"#ROSBAG V2.0": ".bag", b"\x89MCAP": ".mcap", b"SQLite format 3\x00": ".db3"}

_LASER_SCAN = "sensor_msgs/msg/LaserScan"
_ODOMETRY = "nav_msgs/msg/Odometry"
_TF_MESSAGE = "tf2_msgs/msg/TFMessage"
# ROS 1's TFMessage (tf2_msgs/TFMessage), which rosbags' Noetic store lacks.
_TF_MESSAGE_MSG = "geometry_msgs/TransformStamped[] transforms\n"
# Transforms of the mount chain followed at most (a robot description is a few links deep).
_MAX_CHAIN = 32

FloatArray = NDArray[np.float64]


MISSING_ROSBAGS = "ROS bags need the optional extra: pip install 'albot2d[ros]' (rosbags)"


def require_rosbags() -> None:
    """Raise ``InputError`` (one line, with the install command) if rosbags is missing."""
    try:
        import rosbags.highlevel  # noqa: F401
    except ImportError as exc:
        raise InputError(f"{MISSING_ROSBAGS}: {exc}") from None


def typestore_for(ros_version: int) -> Any:
    """rosbags' typestore of ROS 2 Humble or ROS 1 Noetic (with ``tf2_msgs/TFMessage``)."""
    require_rosbags()
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    if ros_version == 2:
        return get_typestore(Stores.ROS2_HUMBLE)
    store = get_typestore(Stores.ROS1_NOETIC)
    if _TF_MESSAGE not in store.types:
        store.register(get_types_from_msg(_TF_MESSAGE_MSG, _TF_MESSAGE))
    return store


def _sniff(path: Path) -> str | None:
    """The bag suffix the file's first bytes say it has, or None."""
    try:
        with open(path, "rb") as handle:
            head = handle.read(16)
    except OSError:
        return None
    return next((suffix for magic, suffix in _MAGIC.items() if head.startswith(magic)), None)


def is_bag(path: str | os.PathLike[str]) -> bool:
    """Whether ``path`` is (or claims to be) a ROS bag rather than a CARMEN log."""
    p = Path(path)
    if p.is_dir():
        return True
    return p.suffix in BAG_SUFFIXES or _sniff(p) is not None


@dataclass(frozen=True, eq=False)
class BagFrames:
    """A bag read as frames, with what the reader used and dropped."""

    frames: list[Frame]
    ros_version: int
    scan_topic: str
    odometry_source: str
    base_frame: str
    laser_frame: str
    scans_without_odometry: int = 0
    topics: dict[str, str] = field(default_factory=dict)

    def as_dict(self) -> dict[str, Any]:
        return {
            "format": f"rosbag{self.ros_version}",
            "scan_topic": self.scan_topic,
            "odometry": self.odometry_source,
            "base_frame": self.base_frame,
            "laser_frame": self.laser_frame,
            "scans_without_odometry": self.scans_without_odometry,
            "topics": dict(self.topics),
        }


def _topic(name: str) -> str:
    return name if name.startswith("/") else f"/{name}"


def _frame_id(name: str) -> str:
    return name.lstrip("/")


class _Bag:
    """An open bag whose every rosbags failure becomes one ``InputError`` naming the file."""

    def __init__(self, path: Path, reader: Any) -> None:
        self.path = path
        self.reader = reader
        self.ros_version = 2 if reader.is2 else 1
        self.topics = {c.topic: c.msgtype for c in reader.connections}

    def _fail(self, exc: BaseException, what: str) -> InputError:
        text = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        return InputError(f"{self.path}: {what} ({text})")

    def messages(self, topic: str) -> Iterator[tuple[int, Any, int]]:
        """``(index, message, record time ns)`` of each message on ``topic``, in bag order."""
        connections = [c for c in self.reader.connections if c.topic == topic]
        if not connections:  # (no connections would mean every message to rosbags)
            return
        stream = self.reader.messages(connections=connections)
        index = 0
        while True:
            try:
                item = next(stream, None)
            except Exception as exc:  # rosbags on a corrupt file: any exception type
                raise self._fail(exc, f"cannot read {topic} message {index}") from None
            if item is None:
                return
            connection, record_ns, raw = item
            try:
                message = self.reader.deserialize(raw, connection.msgtype)
            except Exception as exc:
                raise self._fail(exc, f"cannot decode {topic} message {index}") from None
            yield index, message, int(record_ns)
            index += 1

    def listing(self) -> str:
        if not self.topics:
            return "the bag has no topics"
        shown = ", ".join(f"{t} ({m})" for t, m in sorted(self.topics.items()))
        return f"the bag has {shown}"

    def require(self, topic: str, msgtype: str, option: str) -> None:
        if topic not in self.topics:
            raise InputError(f"{self.path}: no topic {topic} (give {option}); {self.listing()}")
        if self.topics[topic] != msgtype:
            raise InputError(
                f"{self.path}: topic {topic} holds {self.topics[topic]}, expected {msgtype}"
            )


@contextlib.contextmanager
def _open(path: Path) -> Iterator[_Bag]:
    require_rosbags()
    from rosbags.highlevel import AnyReader

    if not path.exists():
        raise InputError(f"{path}: no such bag")
    if path.is_dir() and not (path / "metadata.yaml").exists():
        storage = sorted(p for p in path.iterdir() if p.suffix in (".mcap", ".db3"))
        if len(storage) == 1:  # a ROS 2 bag without its metadata: read the storage file
            path = storage[0]
    sniffed = None if path.is_dir() else _sniff(path)
    if not path.is_dir() and sniffed is None:
        raise InputError(f"{path}: not a ROS bag (no ROS 1, MCAP or sqlite3 header)")
    if sniffed is not None and path.suffix != sniffed:
        kind = {".bag": "ROS 1 bag", ".mcap": "MCAP file", ".db3": "sqlite3 file"}[sniffed]
        raise InputError(f"{path}: the file is a {kind} by its header; name it *{sniffed}")
    try:
        reader = AnyReader([path], default_typestore=typestore_for(1 if sniffed == ".bag" else 2))
        reader.open()
    except Exception as exc:  # rosbags on a corrupt file or directory: any exception type
        text = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise InputError(f"{path}: not a readable ROS bag ({text})") from None
    try:
        # A corrupt length field must not make the deserialiser allocate more than a scan.
        reader.typestore.max_sequence_length = MAX_BEAMS
        yield _Bag(path, reader)
    finally:
        with contextlib.suppress(Exception):
            reader.close()


def _stamp_s(header: Any, where: str, record_ns: int) -> float:
    """A header stamp in seconds, correctly rounded (``sec.nanosec`` read as decimal text);
    the bag's record time when the stamp is zero (a driver that leaves it unset)."""
    sec, nanosec = int(header.stamp.sec), int(header.stamp.nanosec)
    if sec == 0 and nanosec == 0:
        sec, nanosec = divmod(record_ns, 1_000_000_000)
    if not 0 <= nanosec < 1_000_000_000:
        raise InputError(f"{where}: stamp nanosec {nanosec} is not in [0, 1e9)")
    value = float(f"{sec}.{nanosec:09d}") if sec >= 0 else sec + nanosec * 1e-9
    if abs(value) > TIMESTAMP_LIMIT_S:
        raise InputError(f"{where}: stamp {value!r} s is outside ±{TIMESTAMP_LIMIT_S:g}")
    return value


def _yaw(q: Any, where: str) -> float:
    x, y, z, w = float(q.x), float(q.y), float(q.z), float(q.w)
    norm = math.sqrt(x * x + y * y + z * z + w * w)
    if not (math.isfinite(norm) and norm > 1e-9):
        raise InputError(f"{where}: orientation ({x!r}, {y!r}, {z!r}, {w!r}) is not a rotation")
    # Yaw of a (not necessarily unit) quaternion; both arguments scale with its norm squared.
    return wrap_angle(math.atan2(2.0 * (w * z + x * y), w * w + x * x - y * y - z * z))


def _pose(position: Any, orientation: Any, where: str) -> Pose:
    x, y = float(position.x), float(position.y)
    for name, value in (("x", x), ("y", y)):
        if not (abs(value) <= COORDINATE_LIMIT_M):
            raise InputError(
                f"{where}: position {name} {value!r} is not a number within "
                f"±{COORDINATE_LIMIT_M:g} m"
            )
    return Pose(x, y, _yaw(orientation, where))


def _odometry_from_topic(bag: _Bag, topic: str) -> tuple[FloatArray, FloatArray, str]:
    stamps: list[float] = []
    poses: list[tuple[float, float, float]] = []
    base = ""
    for k, msg, record_ns in bag.messages(topic):
        where = f"{bag.path}: {topic} message {k}"
        stamps.append(_stamp_s(msg.header, where, record_ns))
        p = _pose(msg.pose.pose.position, msg.pose.pose.orientation, where)
        poses.append((p.x, p.y, p.theta))
        base = base or _frame_id(msg.child_frame_id)
    return np.array(stamps), np.array(poses).reshape(-1, 3), base or BASE_FRAME


def _transforms(bag: _Bag, topic: str) -> Iterator[tuple[str, str, float, Pose, Any]]:
    """``(parent, child, stamp, planar pose, transform message)`` of each transform on a
    ``/tf`` topic."""
    if topic not in bag.topics:
        return
    bag.require(topic, _TF_MESSAGE, topic)
    for k, msg, record_ns in bag.messages(topic):
        for j, t in enumerate(msg.transforms):
            where = f"{bag.path}: {topic} message {k} transform {j}"
            pose = _pose(t.transform.translation, t.transform.rotation, where)
            stamp = _stamp_s(t.header, where, record_ns)
            yield _frame_id(t.header.frame_id), _frame_id(t.child_frame_id), stamp, pose, t


def _odometry_from_tf(bag: _Bag, odom_topic: str) -> tuple[FloatArray, FloatArray, str]:
    by_child: dict[str, list[tuple[float, float, float, float]]] = {}
    for parent, child, stamp, pose, _ in _transforms(bag, TF_TOPIC):
        if parent == ODOM_FRAME:
            by_child.setdefault(child, []).append((stamp, pose.x, pose.y, pose.theta))
    base = next((f for f in TF_BASE_FRAMES if f in by_child), None)
    if base is None:
        found = ", ".join(sorted(by_child)) or "none"
        raise InputError(
            f"{bag.path}: no odometry: no topic {odom_topic} (give --odom-topic) and no /tf "
            f"transform from {ODOM_FRAME} to {' or '.join(TF_BASE_FRAMES)} "
            f"(children of {ODOM_FRAME}: {found}); {bag.listing()}"
        )
    rows = np.array(by_child[base], dtype=np.float64).reshape(-1, 4)
    return rows[:, 0].copy(), rows[:, 1:].copy(), base


def _rotation(q: Any) -> FloatArray:
    """The rotation matrix of a quaternion already checked by :func:`_yaw`."""
    x, y, z, w = (float(v) for v in (q.x, q.y, q.z, q.w))
    n = math.sqrt(x * x + y * y + z * z + w * w)
    x, y, z, w = x / n, y / n, z / n, w / n
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])  # fmt: skip


@dataclass(frozen=True)
class _Mount:
    """The laser in the base frame: planar pose, and whether it is upside down (its scan
    plane mirrored: a beam at laser angle ``a`` points at ``-a``)."""

    pose: Pose = field(default_factory=Pose)
    mirrored: bool = False


def _mount(bag: _Bag, base: str, laser: str) -> _Mount:
    """The laser's mount through the first-seen transform of each child frame (3-D, so a
    laser mounted upside down is recognised; a tilted scan plane is refused)."""
    if laser == base:
        return _Mount()
    parents: dict[str, tuple[str, Any]] = {}
    for topic in (TF_STATIC_TOPIC, TF_TOPIC):
        for parent, child, _, _, transform in _transforms(bag, topic):
            if parent != ODOM_FRAME and child not in parents:
                parents[child] = (parent, transform.transform)
    rotation, translation, frame = np.eye(3), np.zeros(3), laser
    for _ in range(_MAX_CHAIN):
        if frame == base:
            break
        if frame not in parents:
            return _Mount()  # no chain to the base: the laser is taken to sit at the base
        parent, step = parents[frame]
        r = _rotation(step.rotation)
        v = step.translation
        translation = r @ translation + np.array([float(v.x), float(v.y), float(v.z)])
        rotation, frame = r @ rotation, parent
    else:
        return _Mount()
    up = float(rotation[2, 2])  # the laser's z axis along the base's
    if abs(up) < math.cos(MAX_MOUNT_TILT_RAD):
        tilt = math.degrees(math.acos(max(-1.0, min(1.0, abs(up)))))
        raise InputError(
            f"{bag.path}: the laser's scan plane ({laser}) is tilted {tilt:.1f} deg from the "
            f"{base} plane by its tf chain; albot2d reads planar scans (at most "
            f"{math.degrees(MAX_MOUNT_TILT_RAD):.1f} deg, or upside down)"
        )
    yaw = math.atan2(float(rotation[1, 0]), float(rotation[0, 0]))
    return _Mount(Pose(float(translation[0]), float(translation[1]), yaw), mirrored=up < 0)


class _Odometry:
    """Odometry poses at any stamp within their span (linear; heading the short way)."""

    def __init__(self, stamps: FloatArray, poses: FloatArray) -> None:
        order = np.argsort(stamps, kind="stable")
        self.t = stamps[order]
        self.poses = poses[order]

    def at(self, stamp: float) -> Pose | None:
        t = self.t
        if len(t) == 0 or not (t[0] <= stamp <= t[-1]):
            return None
        k = int(np.searchsorted(t, stamp, side="left"))
        if t[k] == stamp:
            return Pose(*(float(v) for v in self.poses[k]))
        a, b = self.poses[k - 1], self.poses[k]
        w = (stamp - t[k - 1]) / (t[k] - t[k - 1])
        turn = wrap_angle(float(b[2] - a[2]))
        return Pose(
            float(a[0] + w * (b[0] - a[0])),
            float(a[1] + w * (b[1] - a[1])),
            wrap_angle(float(a[2] + w * turn)),
        )


def _number(value: Any, name: str, where: str, low: float, high: float) -> float:
    v = float(value)
    if not (low <= v <= high):
        raise InputError(f"{where}: {name} {v!r} is not a number in [{low:g}, {high:g}]")
    return v


def _scan(msg: Any, where: str, mount: _Mount, stamp: float) -> Scan:
    ranges = np.asarray(msg.ranges, dtype=np.float64)
    n = len(ranges)
    if n == 0:
        raise InputError(f"{where}: LaserScan has no ranges")
    if n > MAX_BEAMS:
        raise InputError(f"{where}: LaserScan has {n} ranges, more than the limit of {MAX_BEAMS}")
    lo, hi = -ANGLE_LIMIT_RAD, ANGLE_LIMIT_RAD
    a_min = _number(msg.angle_min, "angle_min", where, lo, hi)
    a_max = _number(msg.angle_max, "angle_max", where, lo, hi)
    inc = _number(msg.angle_increment, "angle_increment", where, lo, hi)
    r_min = _number(msg.range_min, "range_min", where, 0.0, COORDINATE_LIMIT_M)
    r_max = _number(msg.range_max, "range_max", where, 0.0, COORDINATE_LIMIT_M)
    if r_max <= 0 or r_min > r_max:
        raise InputError(f"{where}: range_min {r_min!r} and range_max {r_max!r} make no interval")
    if n > 1 and inc == 0:
        raise InputError(f"{where}: angle_increment is 0 for {n} beams")
    if n > 1 and abs(a_min + (n - 1) * inc - a_max) <= 0.5 * abs(inc):
        angles = np.linspace(a_min, a_max, n)  # exact ends: undoes the increment's rounding
    else:
        angles = a_min + inc * np.arange(n, dtype=np.float64)
    if abs(angles[-1] - angles[0]) > ANGLE_LIMIT_RAD:
        raise InputError(f"{where}: the {n} beams span more than a turn")
    if mount.mirrored:  # upside down: the beam at a points at -a in the base's plane
        angles, inc = -angles, -inc
    if inc < 0:  # a clockwise scan: albot2d's beams go counter-clockwise
        angles, ranges = angles[::-1].copy(), ranges[::-1].copy()
    with np.errstate(invalid="ignore"):
        valid = np.isfinite(ranges) & (ranges > 0) & (ranges >= r_min) & (ranges <= r_max)
    # REP-117: +inf "no return" and -inf "too close" are codes, not anomalies: stored as
    # range_max (invalid beams); NaN stays NaN and is counted like a CARMEN log's.
    ranges = np.where(np.isinf(ranges), r_max, ranges)
    return Scan(ranges, angles, valid, r_max, stamp, mount.pose)


def read_bag(
    path: str | os.PathLike[str],
    *,
    scan_topic: str = DEFAULT_SCAN_TOPIC,
    odom_topic: str = DEFAULT_ODOM_TOPIC,
) -> BagFrames:
    """The laser frames of a ROS 1 or ROS 2 bag (rules in the module docstring)."""
    bag_path = Path(path)
    scan_topic, odom_topic = _topic(scan_topic), _topic(odom_topic)
    with _open(bag_path) as bag:
        bag.require(scan_topic, _LASER_SCAN, "--scan-topic")
        if odom_topic in bag.topics:
            bag.require(odom_topic, _ODOMETRY, "--odom-topic")
            stamps, poses, base = _odometry_from_topic(bag, odom_topic)
            source = odom_topic
        else:
            stamps, poses, base = _odometry_from_tf(bag, odom_topic)
            source = f"{TF_TOPIC} {ODOM_FRAME}->{base}"
        odometry = _Odometry(stamps, poses)
        mounts: dict[str, _Mount] = {}
        frames: list[Frame] = []
        dropped = 0
        laser = ""
        prev: Pose | None = None
        for k, msg, record_ns in bag.messages(scan_topic):
            where = f"{bag_path}: {scan_topic} message {k}"
            stamp = _stamp_s(msg.header, where, record_ns)
            odom = odometry.at(stamp)
            if odom is None:
                dropped += 1
                continue
            frame_id = _frame_id(msg.header.frame_id)
            laser = laser or frame_id
            if frame_id not in mounts:
                mounts[frame_id] = _mount(bag, base, frame_id)
            scan = _scan(msg, where, mounts[frame_id], stamp)
            increment = Pose() if prev is None else prev.between(odom)
            frames.append(Frame(len(frames), stamp, scan, odom, increment))
            prev = odom
        if not frames:
            why = (
                f"none of its {dropped} scans lies within the odometry's time span"
                if dropped
                else "it has no scans"
            )
            raise InputError(f"{bag_path}: no frames to replay on {scan_topic}: {why}")
        return BagFrames(
            frames=frames,
            ros_version=bag.ros_version,
            scan_topic=scan_topic,
            odometry_source=source,
            base_frame=base,
            laser_frame=laser,
            scans_without_odometry=dropped,
            topics=dict(bag.topics),
        )
