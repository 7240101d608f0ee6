"""Mappers with a bug planted on purpose, loadable as ``module:Class`` plugins
(``tests.plants:OverDeletingAlbot1``), so a test shows a fuzzing invariant catching the
bug through the same path a user's campaign takes."""

from __future__ import annotations

import numpy as np
import shapely
from numpy.typing import NDArray

from albot2d.geometry import Pose
from albot2d.mapping import Albot1
from albot2d.mapping.albot1.global_map import GlobalMap, UpdateReport

__all__ = ["OverDeletingAlbot1", "OverDeletingMap", "UnderDeletingMap"]


class OverDeletingMap(GlobalMap):
    """Algorithm #5 as written, then every surface of maps older than the one being left
    deleted too (the bug of a rule whose "could see" is always true), reported as such."""

    def add_view(self, segments: NDArray[np.float64], map_id: int, robot: Pose) -> UpdateReport:
        report = super().add_view(segments, map_id, robot)
        n = self._n
        alive = np.flatnonzero(self._removed[:n] == np.iinfo(np.int64).max)
        older = alive[self._map_ids[alive] < map_id - 1]
        if len(older):
            gone = self._mark_deleted(older)
            self._index.remove(gone, self._segments.take(gone, axis=0))
            report = report._replace(deleted_older=report.deleted_older + len(gone))
        return report


class UnderDeletingMap(GlobalMap):
    """Algorithm #5 that never deletes anything (only adds)."""

    def add_view(self, segments: NDArray[np.float64], map_id: int, robot: Pose) -> UpdateReport:
        self.insert(segments, map_id)
        return UpdateReport(self.n_updates, map_id, 0, (), (), 0, len(segments), shapely.Polygon())


class OverDeletingAlbot1(Albot1):
    """Albot1 with the over-deleting global map."""

    name = "over_deleting"

    def __init__(self) -> None:
        super().__init__()
        self.map = OverDeletingMap(self.params.global_map)
