"""Write a run's frames as a ROS 1 bag or a ROS 2 bag (MCAP or sqlite3), with ``rosbags``.

What a ROS user gets (REP-103 units and axes, REP-105 frames; stamps are the simulated time
of each frame, the first scan at t = 0, so play it with ``--clock`` and ``use_sim_time``):

=================  ==============================  ============================================
topic              type                            content
=================  ==============================  ============================================
``/scan``          ``sensor_msgs/msg/LaserScan``   each scan, frame ``laser``; beams without a
                                                   return are ``+inf`` (REP-117)
``/odom``          ``nav_msgs/msg/Odometry``       odometry pose ``odom`` → ``base_link`` and
                                                   the body velocities since the last frame
``/tf``            ``tf2_msgs/msg/TFMessage``      ``odom`` → ``base_link`` at each frame
``/tf_static``     ``tf2_msgs/msg/TFMessage``      ``base_link`` → ``laser`` (the mount), once,
                                                   latched (ROS 2: transient-local)
``/ground_truth``  ``nav_msgs/msg/Odometry``       the true pose in ``map`` (simulated runs)
=================  ==============================  ============================================

Covariances are left zero (unknown). Every message is stamped with its frame's time and
recorded at that time. The bag appears atomically: it is written beside its target under a
temporary name and renamed into place when complete.
"""

from __future__ import annotations

import math
import os
import shutil
import tempfile
from collections.abc import Callable, Iterable, Mapping
from pathlib import Path
from typing import Any, Literal

import numpy as np

from albot2d.errors import InputError
from albot2d.frames import Frame
from albot2d.geometry import Pose
from albot2d.logs.rosbag import (
    BASE_FRAME,
    DEFAULT_ODOM_TOPIC,
    DEFAULT_SCAN_TOPIC,
    GROUND_TRUTH_TOPIC,
    LASER_FRAME,
    MAP_FRAME,
    ODOM_FRAME,
    TF_STATIC_TOPIC,
    TF_TOPIC,
    require_rosbags,
    typestore_for,
)

__all__ = ["BAG_STORAGES", "BagStorage", "write_bag"]

BagStorage = Literal["mcap", "sqlite3"]
#: ROS 2 storage plugins, the default first.
BAG_STORAGES: tuple[BagStorage, ...] = ("mcap", "sqlite3")
#: How far (rad) beam angles may stray from a uniform sweep and still be written as one.
_UNIFORM_TOLERANCE_RAD = 1e-9

_LASER_SCAN = "sensor_msgs/msg/LaserScan"
_ODOMETRY = "nav_msgs/msg/Odometry"
_TF_MESSAGE = "tf2_msgs/msg/TFMessage"


def write_bag(
    path: str | os.PathLike[str],
    frames: Iterable[Frame],
    *,
    ros_version: Literal[1, 2] = 2,
    storage: BagStorage = "mcap",
    metadata: Mapping[str, str] | None = None,
) -> int:
    """Write ``frames`` as a bag at ``path`` (ROS 1: a ``.bag`` file; ROS 2: a directory).

    ``storage`` picks the ROS 2 storage plugin; ``metadata`` goes to a ROS 2 bag's
    ``custom_data``. An existing bag at ``path`` is replaced. Returns the frames written.
    """
    if ros_version not in (1, 2):
        raise InputError(f"ros_version must be 1 or 2, got {ros_version!r}")
    if storage not in BAG_STORAGES:
        raise InputError(f"bag storage must be one of {', '.join(BAG_STORAGES)}, got {storage!r}")
    require_rosbags()
    target = Path(path)
    staging = Path(tempfile.mkdtemp(prefix=f".{target.name}.", dir=target.parent))
    try:
        staged = staging / target.name
        if ros_version == 1:
            count = _write_ros1(staged, frames)
        else:
            count = _write_ros2(staged, frames, storage, dict(metadata or {}))
        _replace(staged, target)
    finally:
        shutil.rmtree(staging, ignore_errors=True)
    return count


def _replace(staged: Path, target: Path) -> None:
    """Move ``staged`` onto ``target``; a directory target (an older bag) is replaced whole."""
    if target.is_dir() and not target.is_symlink():
        old = target.with_name(f".{target.name}.old")
        shutil.rmtree(old, ignore_errors=True)
        os.replace(target, old)
        os.replace(staged, target)
        shutil.rmtree(old, ignore_errors=True)
    else:
        os.replace(staged, target)


def _stamp(seconds: float) -> tuple[int, int]:
    """Seconds → (sec, nanosec), exact to the nanosecond (``t - floor(t)`` is exact)."""
    sec = math.floor(seconds)
    nanosec = round((seconds - sec) * 1e9)
    if nanosec >= 1_000_000_000:
        sec, nanosec = sec + 1, nanosec - 1_000_000_000
    return sec, nanosec


class _Messages:
    """Message builders of one typestore (ROS 1 headers carry a ``seq``, ROS 2 ones do not)."""

    def __init__(self, typestore: Any, ros_version: int) -> None:
        self.types = typestore.types
        self.ros1 = ros_version == 1
        self._seq: dict[str, int] = {}

    def header(self, stamp: tuple[int, int], frame_id: str) -> Any:
        time = self.types["builtin_interfaces/msg/Time"](sec=stamp[0], nanosec=stamp[1])
        header = self.types["std_msgs/msg/Header"]
        if self.ros1:
            seq = self._seq.get(frame_id, 0)
            self._seq[frame_id] = seq + 1
            return header(seq=seq, stamp=time, frame_id=frame_id)
        return header(stamp=time, frame_id=frame_id)

    def _pose(self, pose: Pose) -> Any:
        t = self.types
        return t["geometry_msgs/msg/Pose"](
            position=t["geometry_msgs/msg/Point"](x=pose.x, y=pose.y, z=0.0),
            orientation=self._quaternion(pose.theta),
        )

    def _quaternion(self, theta: float) -> Any:
        half = 0.5 * theta
        return self.types["geometry_msgs/msg/Quaternion"](
            x=0.0, y=0.0, z=math.sin(half), w=math.cos(half)
        )

    def transform(self, stamp: tuple[int, int], parent: str, child: str, pose: Pose) -> Any:
        t = self.types
        return t["geometry_msgs/msg/TransformStamped"](
            header=self.header(stamp, parent),
            child_frame_id=child,
            transform=t["geometry_msgs/msg/Transform"](
                translation=t["geometry_msgs/msg/Vector3"](x=pose.x, y=pose.y, z=0.0),
                rotation=self._quaternion(pose.theta),
            ),
        )

    def tf(self, transforms: list[Any]) -> Any:
        return self.types[_TF_MESSAGE](transforms=transforms)

    def odometry(
        self, stamp: tuple[int, int], parent: str, pose: Pose, velocity: tuple[float, float, float]
    ) -> Any:
        t = self.types
        vector = t["geometry_msgs/msg/Vector3"]
        zeros = np.zeros(36, dtype=np.float64)
        return t[_ODOMETRY](
            header=self.header(stamp, parent),
            child_frame_id=BASE_FRAME,
            pose=t["geometry_msgs/msg/PoseWithCovariance"](pose=self._pose(pose), covariance=zeros),
            twist=t["geometry_msgs/msg/TwistWithCovariance"](
                twist=t["geometry_msgs/msg/Twist"](
                    linear=vector(x=velocity[0], y=velocity[1], z=0.0),
                    angular=vector(x=0.0, y=0.0, z=velocity[2]),
                ),
                covariance=zeros,
            ),
        )

    def scan(self, stamp: tuple[int, int], frame: Frame, geometry: _Sweep) -> Any:
        s = frame.scan
        ranges = np.where(s.valid, s.ranges, np.inf).astype(np.float32)
        return self.types[_LASER_SCAN](
            header=self.header(stamp, LASER_FRAME),
            angle_min=geometry.angle_min,
            angle_max=geometry.angle_max,
            angle_increment=geometry.increment,
            time_increment=0.0,
            scan_time=0.0,
            range_min=0.0,
            range_max=float(s.max_range_m),
            ranges=ranges,
            intensities=np.empty(0, dtype=np.float32),
        )


class _Sweep:
    """The LaserScan angle fields of a uniform counter-clockwise sweep."""

    def __init__(self, frame: Frame) -> None:
        a = frame.scan.angles
        n = len(a)
        if n < 2:
            raise InputError(f"frame {frame.index}: a LaserScan needs >= 2 beams, got {n}")
        step = float(a[-1] - a[0]) / (n - 1)
        uniform = np.max(np.abs(a - (a[0] + step * np.arange(n)))) <= _UNIFORM_TOLERANCE_RAD
        if not (uniform and step > 0):
            raise InputError(
                f"frame {frame.index}: scan angles are not a uniform counter-clockwise sweep "
                f"(all a LaserScan can record): first {a[0]!r}, last {a[-1]!r}, n {n}"
            )
        self.angles = a
        self.angle_min, self.angle_max, self.increment = float(a[0]), float(a[-1]), step

    def check(self, frame: Frame) -> None:
        a = frame.scan.angles
        if a is not self.angles and not (
            len(a) == len(self.angles)
            and np.allclose(a, self.angles, rtol=0.0, atol=_UNIFORM_TOLERANCE_RAD)
        ):
            raise InputError(
                f"frame {frame.index}: beam angles differ from frame 0 (one laser per bag)"
            )


def _frame_messages(frames: Iterable[Frame], messages: _Messages) -> Iterable[tuple[str, int, Any]]:
    """``(topic, stamp ns, message)`` in recording order, frame by frame."""
    sweep: _Sweep | None = None
    prev: Frame | None = None
    for frame in frames:
        stamp = _stamp(frame.timestamp)
        ns = stamp[0] * 1_000_000_000 + stamp[1]
        if ns < 0:
            raise InputError(
                f"frame {frame.index}: timestamp {frame.timestamp!r} is before 1970 (ROS time)"
            )
        if sweep is None:
            sweep = _Sweep(frame)
            mount = messages.transform(stamp, BASE_FRAME, LASER_FRAME, frame.scan.laser_pose)
            yield TF_STATIC_TOPIC, ns, messages.tf([mount])
        else:
            sweep.check(frame)
        velocity = (0.0, 0.0, 0.0)
        if prev is not None and frame.timestamp > prev.timestamp:
            dt = frame.timestamp - prev.timestamp
            inc = prev.odom_pose.between(frame.odom_pose)
            velocity = (inc.x / dt, inc.y / dt, inc.theta / dt)
        odom = frame.odom_pose
        yield TF_TOPIC, ns, messages.tf([messages.transform(stamp, ODOM_FRAME, BASE_FRAME, odom)])
        yield DEFAULT_ODOM_TOPIC, ns, messages.odometry(stamp, ODOM_FRAME, odom, velocity)
        if frame.true_pose is not None:
            yield (
                GROUND_TRUTH_TOPIC,
                ns,
                messages.odometry(stamp, MAP_FRAME, frame.true_pose, (0.0, 0.0, 0.0)),
            )
        yield DEFAULT_SCAN_TOPIC, ns, messages.scan(stamp, frame, sweep)
        prev = frame


_TOPIC_TYPES = {
    TF_STATIC_TOPIC: _TF_MESSAGE,
    TF_TOPIC: _TF_MESSAGE,
    DEFAULT_ODOM_TOPIC: _ODOMETRY,
    GROUND_TRUTH_TOPIC: _ODOMETRY,
    DEFAULT_SCAN_TOPIC: _LASER_SCAN,
}


def _write_all(
    frames: Iterable[Frame],
    typestore: Any,
    ros_version: int,
    connect: Callable[[str, str], Any],
    write: Callable[[Any, int, bytes], None],
    serialize: Callable[[Any, str], bytes],
) -> int:
    connections: dict[str, Any] = {}
    count = 0
    for topic, ns, message in _frame_messages(frames, _Messages(typestore, ros_version)):
        if topic not in connections:
            connections[topic] = connect(topic, _TOPIC_TYPES[topic])
        write(connections[topic], ns, serialize(message, _TOPIC_TYPES[topic]))
        count += topic == DEFAULT_SCAN_TOPIC
    return count


def _write_ros1(path: Path, frames: Iterable[Frame]) -> int:
    from rosbags.rosbag1 import Writer

    typestore = typestore_for(1)
    with Writer(path) as writer:

        def connect(topic: str, msgtype: str) -> Any:
            latching = 1 if topic == TF_STATIC_TOPIC else None
            return writer.add_connection(topic, msgtype, typestore=typestore, latching=latching)

        return _write_all(frames, typestore, 1, connect, writer.write, typestore.serialize_ros1)


def _write_ros2(
    path: Path, frames: Iterable[Frame], storage: BagStorage, custom: dict[str, str]
) -> int:
    from rosbags.interfaces import (
        Qos,
        QosDurability,
        QosHistory,
        QosLiveliness,
        QosReliability,
        QosTime,
    )
    from rosbags.rosbag2 import StoragePlugin, Writer

    typestore = typestore_for(2)
    plugin = StoragePlugin.MCAP if storage == "mcap" else StoragePlugin.SQLITE3
    never = QosTime(0, 0)
    latched = Qos(
        QosHistory.KEEP_LAST, 1, QosReliability.RELIABLE, QosDurability.TRANSIENT_LOCAL,
        never, never, QosLiveliness.AUTOMATIC, never, False,
    )  # fmt: skip
    with Writer(path, version=Writer.VERSION_LATEST, storage_plugin=plugin) as writer:
        for key, value in custom.items():
            writer.set_custom_data(key, value)

        def connect(topic: str, msgtype: str) -> Any:
            qos = [latched] if topic == TF_STATIC_TOPIC else []
            return writer.add_connection(
                topic, msgtype, typestore=typestore, offered_qos_profiles=qos
            )

        return _write_all(frames, typestore, 2, connect, writer.write, typestore.serialize_cdr)
