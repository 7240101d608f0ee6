"""Bags for the bag-reader tests, written with rosbags directly (not albot2d's writer), so
the tests can make what albot2d never writes: other topics and types, clockwise or wider
scans, odometry only on /tf, NaN ranges."""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from albot2d.logs.rosbag import typestore_for

__all__ = ["BagScan", "bag_messages", "write_test_bag"]


@dataclass(frozen=True)
class BagScan:
    """One scan of a test bag and the odometry pose at its stamp."""

    t: float
    ranges: list[float]
    pose: tuple[float, float, float] = (0.0, 0.0, 0.0)
    angle_min: float = -math.pi / 2
    angle_increment: float = math.pi / 180
    range_min: float = 0.0
    range_max: float = 30.0
    extra: dict[str, Any] = field(default_factory=dict)


def _float32(value: float) -> float:
    """``value``, or ±inf where float32 (a LaserScan's angles) cannot hold it."""
    return value if abs(value) <= 3.4e38 or math.isnan(value) else math.copysign(math.inf, value)


def _stamp(t: float) -> tuple[int, int]:
    sec = math.floor(t)
    return sec, round((t - sec) * 1e9)


def bag_messages(
    store: Any,
    ros1: bool,
    scans: Iterable[BagScan],
    *,
    scan_topic: str = "/scan",
    odom_topic: str | None = "/odom",
    tf: bool = True,
    mount: tuple[float, float, float] | None = (0.1, 0.0, 0.0),
    mount_rotation: tuple[float, float, float, float] | None = None,
) -> list[tuple[str, str, int, Any]]:
    """``(topic, msgtype, ns, message)`` of a bag holding ``scans``; ``mount_rotation``
    (a quaternion x, y, z, w) replaces the mount's yaw-only rotation."""
    t = store.types

    def header(s: tuple[int, int], frame: str) -> Any:
        time = t["builtin_interfaces/msg/Time"](sec=s[0], nanosec=s[1])
        extra = {"seq": 0} if ros1 else {}
        return t["std_msgs/msg/Header"](stamp=time, frame_id=frame, **extra)

    def quat(theta: float) -> Any:
        if not math.isfinite(theta):  # a bad heading: the quaternion holds it as it is
            return t["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=theta, w=theta)
        return t["geometry_msgs/msg/Quaternion"](
            x=0.0, y=0.0, z=math.sin(theta / 2), w=math.cos(theta / 2)
        )

    def transform(
        s: tuple[int, int], parent: str, child: str, pose: tuple[float, ...], rotation: Any = None
    ) -> Any:
        return t["geometry_msgs/msg/TransformStamped"](
            header=header(s, parent),
            child_frame_id=child,
            transform=t["geometry_msgs/msg/Transform"](
                translation=t["geometry_msgs/msg/Vector3"](x=pose[0], y=pose[1], z=0.0),
                rotation=quat(pose[2]) if rotation is None else rotation,
            ),
        )

    out: list[tuple[str, str, int, Any]] = []
    tf_type = "tf2_msgs/msg/TFMessage"
    for k, scan in enumerate(scans):
        s = _stamp(scan.t)
        ns = s[0] * 1_000_000_000 + s[1]
        if k == 0 and mount is not None:
            rotation = None
            if mount_rotation is not None:
                x, y, z, w = mount_rotation
                rotation = t["geometry_msgs/msg/Quaternion"](x=x, y=y, z=z, w=w)
            static = transform(s, "base_link", "laser", mount, rotation)
            out.append(("/tf_static", tf_type, ns, t[tf_type](transforms=[static])))
        if tf:
            moving = transform(s, "odom", "base_link", scan.pose)
            out.append(("/tf", tf_type, ns, t[tf_type](transforms=[moving])))
        if odom_topic is not None:
            zeros = np.zeros(36)
            v = t["geometry_msgs/msg/Vector3"](x=0.0, y=0.0, z=0.0)
            pose = t["geometry_msgs/msg/Pose"](
                position=t["geometry_msgs/msg/Point"](x=scan.pose[0], y=scan.pose[1], z=0.0),
                orientation=quat(scan.pose[2]),
            )
            out.append((odom_topic, "nav_msgs/msg/Odometry", ns, t["nav_msgs/msg/Odometry"](
                header=header(s, "odom"), child_frame_id="base_link",
                pose=t["geometry_msgs/msg/PoseWithCovariance"](pose=pose, covariance=zeros),
                twist=t["geometry_msgs/msg/TwistWithCovariance"](
                    twist=t["geometry_msgs/msg/Twist"](linear=v, angular=v), covariance=zeros),
            )))  # fmt: skip
        n = len(scan.ranges)
        fields = {
            "angle_min": scan.angle_min,
            "angle_max": _float32(scan.angle_min + (n - 1) * scan.angle_increment),
            "angle_increment": scan.angle_increment,
            "time_increment": 0.0,
            "scan_time": 0.0,
            "range_min": scan.range_min,
            "range_max": scan.range_max,
        } | scan.extra
        out.append((scan_topic, "sensor_msgs/msg/LaserScan", ns, t["sensor_msgs/msg/LaserScan"](
            header=header(s, "laser"), ranges=np.asarray(scan.ranges, dtype=np.float32),
            intensities=np.empty(0, dtype=np.float32), **fields,
        )))  # fmt: skip
    return out


def write_test_bag(
    path: Path, messages: list[tuple[str, str, int, Any]] | None = None, *, ros1: bool, **kw: Any
) -> Path:
    """Write ``messages`` (or ``bag_messages(store, ros1, kw.pop('scans'), **kw)``) as a
    ROS 1 bag (``path`` should end in .bag) or a ROS 2 MCAP / sqlite3 bag."""
    store = typestore_for(1 if ros1 else 2)
    storage = kw.pop("storage", "mcap")
    if messages is None:
        messages = bag_messages(store, ros1, kw.pop("scans"), **kw)
    if ros1:
        from rosbags.rosbag1 import Writer as Writer1

        with Writer1(path) as w1:
            conns: dict[str, Any] = {}
            for topic, msgtype, ns, msg in messages:
                if topic not in conns:
                    conns[topic] = w1.add_connection(topic, msgtype, typestore=store)
                w1.write(conns[topic], ns, store.serialize_ros1(msg, msgtype))
        return path
    from rosbags.rosbag2 import StoragePlugin
    from rosbags.rosbag2 import Writer as Writer2

    plugin = StoragePlugin.SQLITE3 if storage == "sqlite3" else StoragePlugin.MCAP
    with Writer2(path, version=Writer2.VERSION_LATEST, storage_plugin=plugin) as w2:
        conns = {}
        for topic, msgtype, ns, msg in messages:
            if topic not in conns:
                conns[topic] = w2.add_connection(topic, msgtype, typestore=store)
            w2.write(conns[topic], ns, store.serialize_cdr(msg, msgtype))
    return path
