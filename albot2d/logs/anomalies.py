"""Oddities of real logs, counted, and the rule that puts a log's frames in time order.

A recorded log may hold beams a laser could not have measured (NaN, infinite or negative
ranges; they are already invalid beams, never points) and frames out of time order
(shuffled or reversed files, clock jumps) or with the timestamp of an earlier frame.
:func:`ordered_frames` counts all of these in :class:`LogAnomalies` and applies one
documented rule, the one of playing a log back by its timestamps:

- the frames are sorted by timestamp (a stable sort: frames in order keep their order);
- a frame whose timestamp equals that of an earlier frame is dropped (the first one read
  is kept), since two scans cannot be mapped at one instant;
- indices and odometry increments are recomputed for the frames kept.

A log without anomalies comes back unchanged. ``albot2d replay`` reports the counts in one
warning line and in ``report.json`` (``log.anomalies``); ``--strict`` refuses the log.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import asdict, dataclass

import numpy as np

from albot2d.frames import Frame
from albot2d.geometry import Pose

__all__ = ["LogAnomalies", "ordered_frames"]


@dataclass(frozen=True)
class LogAnomalies:
    """What was odd about a log: beams (ranges) and frames (timestamps), counted.

    - ``non_finite_ranges`` / ``negative_ranges``: beams holding NaN/±inf or a value < 0.
    - ``out_of_order_timestamps``: frames earlier than the frame read just before them.
    - ``duplicate_timestamps``: frames with the timestamp of an earlier frame (dropped).
    - ``frames_read`` / ``frames_kept``: laser frames in the file and after the rule.
    """

    non_finite_ranges: int = 0
    negative_ranges: int = 0
    out_of_order_timestamps: int = 0
    duplicate_timestamps: int = 0
    frames_read: int = 0
    frames_kept: int = 0

    @property
    def total(self) -> int:
        """How many anomalies there are in all (0 for a clean log)."""
        return (
            self.non_finite_ranges
            + self.negative_ranges
            + self.out_of_order_timestamps
            + self.duplicate_timestamps
        )

    def as_dict(self) -> dict[str, int]:
        return asdict(self)

    def summary(self) -> str:
        """One line: ``2 non-finite ranges, 1 duplicate timestamp (1 frame dropped)``."""
        parts = []
        for count, what in (
            (self.non_finite_ranges, "non-finite range"),
            (self.negative_ranges, "negative range"),
            (self.out_of_order_timestamps, "out-of-order timestamp"),
            (self.duplicate_timestamps, "duplicate timestamp"),
        ):
            if count:
                parts.append(f"{count} {what}{'' if count == 1 else 's'}")
        text = ", ".join(parts) if parts else "no anomalies"
        if self.out_of_order_timestamps:
            text += "; frames sorted by timestamp"
        dropped = self.frames_read - self.frames_kept
        if dropped:
            text += (
                f"; {dropped} frame{'' if dropped == 1 else 's'} with a repeated timestamp dropped"
            )
        return text


def ordered_frames(frames: Iterable[Frame]) -> tuple[list[Frame], LogAnomalies]:
    """The frames in time order by the rule of the module docstring, and the counts."""
    read = list(frames)
    non_finite = negative = out_of_order = 0
    previous = -np.inf
    for frame in read:
        r = frame.scan.ranges
        finite = np.isfinite(r)
        non_finite += int(r.size - np.count_nonzero(finite))
        negative += int(np.count_nonzero(r[finite] < 0.0))
        if frame.timestamp < previous:
            out_of_order += 1
        previous = frame.timestamp
    stamps = np.array([f.timestamp for f in read], dtype=np.float64)
    order = np.argsort(stamps, kind="stable")
    sorted_stamps = stamps[order]
    keep = np.ones(len(read), dtype=bool)
    keep[1:] = sorted_stamps[1:] != sorted_stamps[:-1]
    duplicates = int(len(read) - np.count_nonzero(keep))
    if out_of_order or duplicates:
        read = _renumbered([read[i] for i in order[keep]])
    anomalies = LogAnomalies(
        non_finite_ranges=non_finite,
        negative_ranges=negative,
        out_of_order_timestamps=out_of_order,
        duplicate_timestamps=duplicates,
        frames_read=len(stamps),
        frames_kept=len(read),
    )
    return read, anomalies


def _renumbered(frames: list[Frame]) -> list[Frame]:
    """Frames with consecutive indices and odometry increments between the frames kept."""
    out: list[Frame] = []
    prev: Pose | None = None
    for index, frame in enumerate(frames):
        increment = Pose() if prev is None else prev.between(frame.odom_pose)
        out.append(
            Frame(index, frame.timestamp, frame.scan, frame.odom_pose, increment,
                  frame.true_pose, frame.collided)
        )  # fmt: skip
        prev = frame.odom_pose
    return out
