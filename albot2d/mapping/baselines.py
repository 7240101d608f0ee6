"""The paper's Albot_x comparison robots that integrate every view into one map.

- ``NaiveIntegration``: every view placed by the raw odometry pose; nothing corrected or
  deleted (the paper's Fig. 16a/b).
- ``GroundTruthIntegration``: every view placed by the true pose: the exact map, an upper
  bound available in simulation only.

Both use the same surface extraction as Albot1 so their maps are comparable, and
implement the mapper protocol (``albot2d.mapping.protocol.PerceivingMapper``: a driver
that already extracted a frame's surfaces passes them to ``observe_perceived``).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from albot2d.errors import InputError
from albot2d.frames import Frame
from albot2d.geometry import Pose, transform_segments
from albot2d.mapping.global_map import GlobalMap
from albot2d.mapping.protocol import MapperCounts, MapSnapshot, StageTimer
from albot2d.perception import ExtractionParams, Surfaces, extract_surfaces

__all__ = ["GroundTruthIntegration", "NaiveIntegration", "ViewIntegrator"]


class ViewIntegrator:
    """Places every view's surfaces at a pose chosen by the subclass (``_source_pose``);
    deletes nothing. The base of the baselines and of ``slam.ScanMatchingSLAM``."""

    name = "integrator"

    def __init__(self, extraction: ExtractionParams | None = None) -> None:
        self.extraction = extraction or ExtractionParams()
        self.map = GlobalMap()
        self.timer = StageTimer()
        self._origin: Pose | None = None
        self._poses: list[NDArray[np.float64]] = []

    def _source_pose(self, frame: Frame) -> Pose:
        raise NotImplementedError

    def perception(self) -> ExtractionParams:
        return self.extraction

    def observe(self, frame: Frame) -> None:
        with self.timer.stage("extraction"):
            view = extract_surfaces(frame.scan, self.extraction)
        self.observe_perceived(frame, view)

    def observe_perceived(self, frame: Frame, view: Surfaces) -> None:
        source = self._source_pose(frame)
        if self._origin is None:
            self._origin = source
        pose = self._origin.between(source)
        self._poses.append(pose.as_array())
        with self.timer.stage("global_map"):
            self.map.insert(transform_segments(pose.as_array(), view.segments), len(self._poses))

    def pose(self) -> Pose:
        return Pose.from_array(self._poses[-1]) if self._poses else Pose()

    def global_map(self, at_update: int | None = None) -> MapSnapshot:
        return self.map.snapshot(at_update)

    def trajectory(self) -> NDArray[np.float64]:
        return np.array(self._poses).reshape(-1, 3)

    def counts(self) -> MapperCounts:
        n = len(self._poses)
        return MapperCounts(n, n, triangulations=0, path_integrations=max(n - 1, 0))

    def timings_ms(self) -> dict[str, float]:
        return self.timer.mean_ms_per(len(self._poses))


class NaiveIntegration(ViewIntegrator):
    """Albot_x without error correction: views placed by raw odometry."""

    name = "naive"

    def _source_pose(self, frame: Frame) -> Pose:
        return frame.odom_pose


class GroundTruthIntegration(ViewIntegrator):
    """Views placed by the true pose (simulation only): the exact map."""

    name = "truth"

    def _source_pose(self, frame: Frame) -> Pose:
        if frame.true_pose is None:
            raise InputError(
                f"the truth mapper needs true poses, but frame {frame.index} has none "
                "(real logs carry no ground truth)"
            )
        return frame.true_pose
