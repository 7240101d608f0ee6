"""A template for writing your own albot2d mapper: copy this file and change ``observe``.

Run it beside the built-in mappers from the folder that holds the file:

    albot2d run --mapper albot1 mapper_template:LastViewOnly --out out/
    albot2d fuzz --episodes 20 --mapper mapper_template:LastViewOnly --out fuzz/

The mapper protocol (``albot2d.mapping.Mapper``) asks for six methods and a ``name``
(the name the report, the tables and the exported files use). Frames: everything a
mapper returns is in *its own* frame, whose origin is the robot's pose at the first
frame it observed (x forward, y left). The evaluation anchors it at the true start pose
(``albot2d.evaluation.metrics.alignment.in_world_frame``) to compare it with the world.

This example places every view by odometry, like ``naive``, but keeps only the surfaces
of the last ``keep_views`` views as its map: a mapper with a very short memory.
"""

from __future__ import annotations

from collections import deque

import numpy as np
from numpy.typing import NDArray

from albot2d.frames import Frame
from albot2d.geometry import Pose, transform_segments
from albot2d.mapping import MapperCounts, MapSnapshot, StageTimer
from albot2d.perception import ExtractionParams, extract_surfaces

__all__ = ["LastViewOnly"]


class LastViewOnly:
    """Views placed by odometry; the map is the surfaces of the last few views."""

    name = "last_views"  # how the report, the tables and the files call this mapper

    def __init__(self, keep_views: int = 3) -> None:
        # The CLI builds a mapper with no arguments: give every parameter a default.
        self.keep_views = keep_views
        self.extraction = ExtractionParams()
        self.timer = StageTimer()  # per-stage timings for report.json (optional)
        self._first_odom: Pose | None = None
        self._poses: list[NDArray[np.float64]] = []
        self._views: deque[tuple[int, NDArray[np.float64]]] = deque(maxlen=keep_views)

    def observe(self, frame: Frame) -> None:
        """Consume the next frame: its laser scan and the odometry (never the truth,
        ``frame.true_pose``, unless the mapper is a simulation-only reference)."""
        with self.timer.stage("extraction"):
            surfaces = extract_surfaces(frame.scan, self.extraction)  # robot frame
        if self._first_odom is None:
            self._first_odom = frame.odom_pose
        pose = self._first_odom.between(frame.odom_pose)  # in this mapper's frame
        self._poses.append(pose.as_array())
        with self.timer.stage("global_map"):
            view_id = len(self._poses) - 1  # the frame index of the view, used as its id
            self._views.append((view_id, transform_segments(pose.as_array(), surfaces.segments)))

    def pose(self) -> Pose:
        """The current pose estimate (identity before the first frame)."""
        return Pose.from_array(self._poses[-1]) if self._poses else Pose()

    def global_map(self) -> MapSnapshot:
        """The map now: ``MapSnapshot(segments, map_ids)`` with ``segments`` an ``(M, 4)``
        float array of surfaces ``x1, y1, x2, y2`` in this mapper's frame and ``map_ids``
        an ``(M,)`` int64 array saying which view (local map) each surface came from
        (the figures colour surfaces old → new by it). An empty map is ``(0, 4)`` and ``(0,)``.
        """
        if not self._views:
            return MapSnapshot(np.empty((0, 4)), np.empty(0, dtype=np.int64))
        segments = np.concatenate([segs for _, segs in self._views]).reshape(-1, 4)
        ids = np.concatenate([np.full(len(segs), k, dtype=np.int64) for k, segs in self._views])
        return MapSnapshot(segments, ids)

    def trajectory(self) -> NDArray[np.float64]:
        """``(F, 3)`` poses ``x, y, theta`` of every frame observed so far, as the mapper
        now believes them (a mapper that corrects its past may change earlier rows)."""
        return np.array(self._poses, dtype=np.float64).reshape(-1, 3)

    def counts(self) -> MapperCounts:
        """Views seen, local maps remembered, and how they were localised."""
        n = len(self._poses)
        return MapperCounts(views=n, local_maps=n, triangulations=0,
                            path_integrations=max(n - 1, 0))  # fmt: skip

    def timings_ms(self) -> dict[str, float]:
        """Mean milliseconds per view for each stage."""
        return self.timer.mean_ms_per(len(self._poses))
