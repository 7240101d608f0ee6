"""The paper's Albot_x comparison robots that integrate every view into one map.

- ``NaiveIntegration``: every view placed by the raw odometry pose; nothing corrected or
  deleted (the paper's Fig. 16a/b).
- ``GroundTruthIntegration``: every view placed by the true pose: the exact map, an upper
  bound available in simulation only.

Both use the same surface extraction as Albot1 so their maps are comparable, and
implement the mapper protocol (``albot2d.mapping.protocol.PerceivingMapper``: a driver
that already extracted a frame's surfaces passes them to ``observe_perceived``).

They keep every view, so their storage is what a long run's memory follows: the map is
one ``(N, 4)`` array of surfaces and one of view ids, grown in fixed blocks
(``IntegratedMap``: 40 bytes a surface, no spatial index, since nothing is ever queried
or deleted), and the poses one flat array (``PoseLog``: 24 bytes a view), not an object
per view.
"""

from __future__ import annotations

from array import array
from collections.abc import Iterator

import numpy as np
from numpy.typing import NDArray

from albot2d.errors import InputError
from albot2d.frames import Frame
from albot2d.geometry import Pose, as_segments, transform_segments
from albot2d.mapping.protocol import MapperCounts, MapSnapshot, StageTimer
from albot2d.perception import ExtractionParams, Surfaces, extract_surfaces

__all__ = [
    "GroundTruthIntegration",
    "IntegratedMap",
    "NaiveIntegration",
    "PoseLog",
    "ViewIntegrator",
]

# Surfaces per storage block of IntegratedMap: growing never copies what is stored, and
# at most one block (1.3 MB) is allocated ahead.
_BLOCK_SURFACES = 1 << 15


class IntegratedMap:
    """A map that only grows: every update's surfaces with its map id, nothing deleted.

    The same answers as ``GlobalMap.insert`` followed by ``GlobalMap.snapshot`` (the
    surfaces in insertion order, ``snapshot(at_update=k)`` those of the first ``k``
    updates), in blocks of plain arrays: no spatial index and no per-update objects."""

    def __init__(self) -> None:
        self._blocks: list[tuple[NDArray[np.float64], NDArray[np.int64]]] = []
        self._n = 0
        self._ends = array("q")  # surfaces stored after each update
        self.last_map_id: int | None = None

    def __len__(self) -> int:
        """Number of surfaces in the map."""
        return self._n

    @property
    def n_updates(self) -> int:
        """Number of updates (``insert`` calls) so far."""
        return len(self._ends)

    def insert(self, segments: NDArray[np.float64], map_id: int) -> None:
        """Add one update's surfaces (``(K, 4)``), all tagged ``map_id``."""
        segs = as_segments(segments)
        if self.last_map_id is not None and map_id <= self.last_map_id:
            raise ValueError(f"map ids must increase: got {map_id} after {self.last_map_id}")
        done = 0
        while done < len(segs):
            at = self._n % _BLOCK_SURFACES
            if at == 0:
                self._blocks.append(
                    (np.empty((_BLOCK_SURFACES, 4)), np.empty(_BLOCK_SURFACES, np.int64))
                )
            take = min(len(segs) - done, _BLOCK_SURFACES - at)
            block_segs, block_ids = self._blocks[-1]
            block_segs[at : at + take] = segs[done : done + take]
            block_ids[at : at + take] = map_id
            done += take
            self._n += take
        self._ends.append(self._n)
        self.last_map_id = map_id

    def blocks(self) -> Iterator[tuple[NDArray[np.float64], NDArray[np.int64]]]:
        """The stored ``(segments, map_ids)`` in insertion order, block by block (views
        into the storage, not copies: for reading a long run's map in bounded memory)."""
        for b, (block_segs, block_ids) in enumerate(self._blocks):
            rows = min(_BLOCK_SURFACES, self._n - b * _BLOCK_SURFACES)
            yield block_segs[:rows], block_ids[:rows]

    def snapshot(self, at_update: int | None = None) -> MapSnapshot:
        """The map now, or right after update number ``at_update`` (1-based)."""
        n = self._n
        if at_update is not None:
            n = 0 if at_update < 1 else self._ends[min(at_update, self.n_updates) - 1]
        segments, ids = np.zeros((n, 4)), np.zeros(n, np.int64)
        lo = 0
        for block_segs, block_ids in self.blocks():
            if lo >= n:
                break
            rows = min(n - lo, len(block_ids))
            segments[lo : lo + rows] = block_segs[:rows]
            ids[lo : lo + rows] = block_ids[:rows]
            lo += rows
        return MapSnapshot(segments, ids)


class PoseLog:
    """Planar poses ``(x, y, theta)`` appended one by one, stored flat (24 bytes each)."""

    def __init__(self) -> None:
        self._values = array("d")

    def __len__(self) -> int:
        return len(self._values) // 3

    def append(self, pose: NDArray[np.float64]) -> None:
        self._values.extend(np.asarray(pose, dtype=np.float64).reshape(3).tolist())

    def last(self) -> NDArray[np.float64]:
        return np.array(self._values[-3:], dtype=np.float64)

    def as_array(self) -> NDArray[np.float64]:
        """All poses, ``(N, 3)`` (a copy)."""
        return np.array(self._values, dtype=np.float64).reshape(-1, 3)


class ViewIntegrator:
    """Places every view's surfaces at a pose chosen by the subclass (``_source_pose``);
    deletes nothing. The base of the baselines and of ``slam.ScanMatchingSLAM``."""

    name = "integrator"

    def __init__(self, extraction: ExtractionParams | None = None) -> None:
        self.extraction = extraction or ExtractionParams()
        self.map = IntegratedMap()
        self.timer = StageTimer()
        self._origin: Pose | None = None
        self._poses = PoseLog()

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
        return Pose.from_array(self._poses.last()) if len(self._poses) else Pose()

    def global_map(self, at_update: int | None = None) -> MapSnapshot:
        return self.map.snapshot(at_update)

    def trajectory(self) -> NDArray[np.float64]:
        return self._poses.as_array()

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
