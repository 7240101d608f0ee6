#!/usr/bin/env python3
"""Convert a CARMEN log's FLASER scans to a ROS 1 bag and/or a ROS 2 bag, with ``rosbags``.

An independent converter (it parses the log itself and writes with rosbags' own writers and
typestores, not with albot2d), used to check that ``albot2d replay`` scores a bag as it scores
the CARMEN log it came from, and handy for feeding old CARMEN datasets to ROS tools::

    python scripts/carmen_to_rosbag.py ../shared/data/raw/mit-csail.clf.gz \\
        --ros1 mit-csail.bag --ros2 mit-csail_ros2            # MCAP; --storage sqlite3

Topics: ``/scan`` (sensor_msgs/msg/LaserScan, frame ``laser``), ``/odom``
(nav_msgs/msg/Odometry, ``odom`` → ``base_link``, the FLASER line's odometry pose), ``/tf``
(the same transform) and ``/tf_static`` (``base_link`` → ``laser`` from the log's
``robot_frontlaser_*offset`` PARAMs, else the identity). Every message is stamped with the
line's ``ipc_timestamp`` (the relations' clock), converted exactly from its decimal text.

Beam angles follow the FLASER convention of albot2d and SOURCES.md: the first beam at
``-fov/2`` (``--fov-deg``, default 180, or the log's ``laser_front_laser_fov`` PARAM), a step
of ``fov/(n-1)`` for odd ``n`` and ``fov/n`` for even ``n``. ``range_max`` is ``--range-max``
(default 30 m, the no-return threshold albot2d uses for a FLASER log without a
``robot_front_laser_max`` PARAM; values above it, like the SICK's 81.91 no-return code,
are then invalid beams by REP-117's rule). Ranges are stored as float32, as in ROS.
"""

from __future__ import annotations

import argparse
import contextlib
import gzip
import math
import sys
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Any

import numpy as np
from rosbags.interfaces import (
    Qos,
    QosDurability,
    QosHistory,
    QosLiveliness,
    QosReliability,
    QosTime,
)
from rosbags.rosbag1 import Writer as Writer1
from rosbags.rosbag2 import StoragePlugin
from rosbags.rosbag2 import Writer as Writer2
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

DEFAULT_RANGE_MAX_M = 30.0
DEFAULT_FOV_DEG = 180.0


@dataclass(frozen=True)
class Scan:
    sec: int
    nanosec: int
    ranges: np.ndarray
    odom: tuple[float, float, float]


def _open(path: Path) -> IO[str]:
    with open(path, "rb") as handle:
        gz = handle.read(2) == b"\x1f\x8b"
    return gzip.open(path, "rt") if gz else open(path)


def _stamp(text: str) -> tuple[int, int]:
    """Decimal seconds text → (sec, nanosec), exactly."""
    whole, _, frac = text.partition(".")
    sec = int(whole)
    nanosec = int((frac + "000000000")[:9])
    if text.startswith("-") and nanosec:
        sec, nanosec = sec - 1, 1_000_000_000 - nanosec
    return sec, nanosec


def read_log(path: Path) -> tuple[dict[str, float], list[Scan]]:
    """The log's numeric PARAMs and its FLASER scans."""
    params: dict[str, float] = {}
    scans: list[Scan] = []
    with _open(path) as handle:
        for line in handle:
            tokens = line.split()
            if not tokens:
                continue
            if tokens[0] == "PARAM" and len(tokens) >= 3:
                with contextlib.suppress(ValueError):
                    params[tokens[1]] = float(tokens[2])
            elif tokens[0] == "FLASER":
                n = int(tokens[1])
                ranges = np.array(tokens[2 : 2 + n], dtype=np.float64)
                tail = tokens[2 + n :]
                odom = (float(tail[3]), float(tail[4]), float(tail[5]))
                sec, nanosec = _stamp(tail[6])
                scans.append(Scan(sec, nanosec, ranges, odom))
    return params, scans


def _messages(
    typestore: Any, ros1: bool, params: dict[str, float], scans: list[Scan], args: Any
) -> Iterator[tuple[str, str, int, Any]]:
    """``(topic, msgtype, ns, message)`` in time order."""
    t = typestore.types
    seq = {"n": 0}

    def header(sec: int, nanosec: int, frame_id: str) -> Any:
        stamp = t["builtin_interfaces/msg/Time"](sec=sec, nanosec=nanosec)
        if ros1:
            seq["n"] += 1
            return t["std_msgs/msg/Header"](seq=seq["n"], stamp=stamp, frame_id=frame_id)
        return t["std_msgs/msg/Header"](stamp=stamp, frame_id=frame_id)

    def quaternion(theta: float) -> Any:
        return t["geometry_msgs/msg/Quaternion"](
            x=0.0, y=0.0, z=math.sin(theta / 2), w=math.cos(theta / 2)
        )

    def transform(
        sec: int, nanosec: int, parent: str, child: str, x: float, y: float, theta: float
    ) -> Any:
        return t["geometry_msgs/msg/TransformStamped"](
            header=header(sec, nanosec, parent),
            child_frame_id=child,
            transform=t["geometry_msgs/msg/Transform"](
                translation=t["geometry_msgs/msg/Vector3"](x=x, y=y, z=0.0),
                rotation=quaternion(theta),
            ),
        )

    fov = math.radians(params.get("laser_front_laser_fov", args.fov_deg))
    mount = (
        params.get("robot_frontlaser_offset", 0.0),
        params.get("robot_frontlaser_sideoffset", 0.0),
        params.get("robot_frontlaser_angular_offset", 0.0),
    )
    zeros = np.zeros(36)
    for k, scan in enumerate(scans):
        ns = scan.sec * 1_000_000_000 + scan.nanosec
        if k == 0:
            static = transform(scan.sec, scan.nanosec, "base_link", "laser", *mount)
            yield (
                "/tf_static",
                "tf2_msgs/msg/TFMessage",
                ns,
                t["tf2_msgs/msg/TFMessage"](transforms=[static]),
            )
        x, y, theta = scan.odom
        yield (
            "/tf",
            "tf2_msgs/msg/TFMessage",
            ns,
            t["tf2_msgs/msg/TFMessage"](
                transforms=[transform(scan.sec, scan.nanosec, "odom", "base_link", x, y, theta)]
            ),
        )
        pose = t["geometry_msgs/msg/Pose"](
            position=t["geometry_msgs/msg/Point"](x=x, y=y, z=0.0), orientation=quaternion(theta)
        )
        vector = t["geometry_msgs/msg/Vector3"](x=0.0, y=0.0, z=0.0)
        yield (
            "/odom",
            "nav_msgs/msg/Odometry",
            ns,
            t["nav_msgs/msg/Odometry"](
                header=header(scan.sec, scan.nanosec, "odom"),
                child_frame_id="base_link",
                pose=t["geometry_msgs/msg/PoseWithCovariance"](pose=pose, covariance=zeros),
                twist=t["geometry_msgs/msg/TwistWithCovariance"](
                    twist=t["geometry_msgs/msg/Twist"](linear=vector, angular=vector),
                    covariance=zeros,
                ),
            ),
        )
        n = len(scan.ranges)
        step = fov / (n - 1) if n % 2 else fov / n
        yield (
            "/scan",
            "sensor_msgs/msg/LaserScan",
            ns,
            t["sensor_msgs/msg/LaserScan"](
                header=header(scan.sec, scan.nanosec, "laser"),
                angle_min=-fov / 2,
                angle_max=-fov / 2 + (n - 1) * step,
                angle_increment=step,
                time_increment=0.0,
                scan_time=0.0,
                range_min=0.0,
                range_max=args.range_max,
                ranges=scan.ranges.astype(np.float32),
                intensities=np.empty(0, dtype=np.float32),
            ),
        )


def _ros1_typestore() -> Any:
    store = get_typestore(Stores.ROS1_NOETIC)
    store.register(
        get_types_from_msg(
            "geometry_msgs/TransformStamped[] transforms\n", "tf2_msgs/msg/TFMessage"
        )
    )
    return store


def write_ros1(path: Path, params: dict[str, float], scans: list[Scan], args: Any) -> None:
    store = _ros1_typestore()
    with Writer1(path) as writer:
        connections = {}
        for topic, msgtype, ns, msg in _messages(store, True, params, scans, args):
            if topic not in connections:
                latching = 1 if topic == "/tf_static" else None
                connections[topic] = writer.add_connection(
                    topic, msgtype, typestore=store, latching=latching
                )
            writer.write(connections[topic], ns, store.serialize_ros1(msg, msgtype))


def write_ros2(path: Path, params: dict[str, float], scans: list[Scan], args: Any) -> None:
    store = get_typestore(Stores.ROS2_HUMBLE)
    plugin = StoragePlugin.MCAP if args.storage == "mcap" else StoragePlugin.SQLITE3
    never = QosTime(0, 0)
    latched = Qos(
        QosHistory.KEEP_LAST, 1, QosReliability.RELIABLE, QosDurability.TRANSIENT_LOCAL,
        never, never, QosLiveliness.AUTOMATIC, never, False,
    )  # fmt: skip
    with Writer2(path, version=Writer2.VERSION_LATEST, storage_plugin=plugin) as writer:
        connections = {}
        for topic, msgtype, ns, msg in _messages(store, False, params, scans, args):
            if topic not in connections:
                qos = [latched] if topic == "/tf_static" else []
                connections[topic] = writer.add_connection(
                    topic, msgtype, typestore=store, offered_qos_profiles=qos
                )
            writer.write(connections[topic], ns, store.serialize_cdr(msg, msgtype))


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("log", type=Path, help="a CARMEN log with FLASER lines (plain or gzip)")
    p.add_argument("--ros1", type=Path, metavar="OUT.bag", help="write a ROS 1 bag")
    p.add_argument("--ros2", type=Path, metavar="DIR", help="write a ROS 2 bag directory")
    p.add_argument("--storage", choices=("mcap", "sqlite3"), default="mcap")
    p.add_argument("--range-max", type=float, default=DEFAULT_RANGE_MAX_M, metavar="M")
    p.add_argument("--fov-deg", type=float, default=DEFAULT_FOV_DEG, metavar="DEG")
    args = p.parse_args(argv)
    if args.ros1 is None and args.ros2 is None:
        p.error("give --ros1 OUT.bag and/or --ros2 DIR")
    params, scans = read_log(args.log)
    if not scans:
        p.error(f"{args.log}: no FLASER lines")
    if args.ros1 is not None:
        write_ros1(args.ros1, params, scans, args)
    if args.ros2 is not None:
        write_ros2(args.ros2, params, scans, args)
    written = ", ".join(str(path) for path in (args.ros1, args.ros2) if path is not None)
    print(f"{args.log}: {len(scans)} scans -> {written}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
