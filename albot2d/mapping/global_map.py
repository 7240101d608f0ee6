"""Albot1's transient global map (algorithm #5): add each remembered view, delete what overlaps.

Every surface is tagged with the id of the local map it came from. Adding a view:

1. P = the polygon joining the view's surface endpoints in scan order (and, by default,
   the viewpoint, so P is the area the view saw), enlarged by 0.5 m;
2. surfaces of the current map (the one the robot is leaving) inside or crossing P are
   deleted; older maps with surfaces there are "affected";
3. the affected maps are expanded to the contiguous group of ids (25 and 28 → 25…28) and
   those maps' surfaces on the robot's facing side (in front of its viewpoint) are deleted;
4. the incoming view is added.

Surfaces are never modified, only added and deleted, so each carries the update number at
which it was added and removed: any past state of the map is a cheap filter
(``snapshot(at_update=k)``), which is how the map's evolution is shown (paper Figs. 7, 10–15).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal, NamedTuple

import numpy as np
import shapely
from numpy.typing import NDArray

from albot2d.errors import InputError
from albot2d.geometry import Pose, as_segments
from albot2d.mapping.spatial_index import SegmentGridIndex
from albot2d.validation import check_non_negative, check_positive

__all__ = ["GlobalMap", "GlobalMapParams", "MapSnapshot", "UpdateReport", "view_polygon"]

_NEVER = np.iinfo(np.int64).max
FacingTest = Literal["midpoint", "any_endpoint", "both_endpoints"]


@dataclass(frozen=True, slots=True)
class GlobalMapParams:
    """Parameters of algorithm #5 (paper defaults).

    - ``enlarge_m``: how much the view polygon is enlarged (paper: 50 cm).
    - ``include_viewpoint``: close the polygon through the viewpoint (the view's visible
      area) rather than only through the surface endpoints.
    - ``expand_group``: delete from the contiguous group min…max of affected map ids
      (the paper's Expand) rather than only the affected maps.
    - ``facing_test``: which points of a surface must be in front of the robot for it to
      lie "on the facing side".
    - ``index_cell_m``: cell size of the spatial index (performance only).
    """

    enlarge_m: float = 0.50
    include_viewpoint: bool = True
    expand_group: bool = True
    facing_test: FacingTest = "midpoint"
    index_cell_m: float = 2.0

    def __post_init__(self) -> None:
        check_non_negative(self, "enlarge_m")
        check_positive(self, "index_cell_m")
        if self.facing_test not in ("midpoint", "any_endpoint", "both_endpoints"):
            raise InputError(
                f"GlobalMapParams.facing_test must be midpoint, any_endpoint or "
                f"both_endpoints, got {self.facing_test!r}"
            )


class MapSnapshot(NamedTuple):
    """Surfaces of the map at one moment: ``segments (M, 4)`` and ``map_ids (M,)``."""

    segments: NDArray[np.float64]
    map_ids: NDArray[np.int64]


class UpdateReport(NamedTuple):
    """What one update did (for traces, tests and the fuzzing invariants)."""

    update: int
    map_id: int
    deleted_current: int
    affected_maps: tuple[int, ...]
    group: tuple[int, ...]
    deleted_older: int
    added: int
    polygon: shapely.Geometry


def view_polygon(
    segments: NDArray[np.float64], viewpoint: Pose | None, enlarge_m: float
) -> shapely.Geometry:
    """The enlarged polygon of a view whose surfaces (global frame) are given in scan order."""
    segs = as_segments(segments)
    pts = segs.reshape(-1, 2)
    if viewpoint is not None:
        pts = np.vstack([[viewpoint.x, viewpoint.y], pts])
    if len(pts) == 0:
        return shapely.Polygon()
    if len(pts) < 3:
        return shapely.MultiPoint(pts).buffer(enlarge_m)
    poly = shapely.make_valid(shapely.Polygon(pts))
    return poly.buffer(enlarge_m) if enlarge_m > 0 else poly


class GlobalMap:
    """The global map of algorithm #5, with a grid index and a full add/delete history."""

    def __init__(self, params: GlobalMapParams = GlobalMapParams()) -> None:
        self.params = params
        self._segments = np.zeros((64, 4))
        self._map_ids = np.zeros(64, np.int64)
        self._added = np.zeros(64, np.int64)
        self._removed = np.full(64, _NEVER, np.int64)
        self._n = 0
        self._alive = 0
        self._by_map: dict[int, NDArray[np.int64]] = {}
        self._index = SegmentGridIndex(params.index_cell_m)
        self.n_updates = 0
        self.last_map_id: int | None = None

    def __len__(self) -> int:
        """Number of surfaces in the map now."""
        return self._alive

    def _grow(self, extra: int) -> None:
        need = self._n + extra
        if need <= len(self._segments):
            return
        cap = max(need, 2 * len(self._segments))
        self._segments = np.resize(self._segments, (cap, 4))
        self._map_ids = np.resize(self._map_ids, cap)
        self._added = np.resize(self._added, cap)
        removed = np.full(cap, _NEVER, np.int64)
        removed[: self._n] = self._removed[: self._n]
        self._removed = removed

    def _delete(self, ids: NDArray[np.int64]) -> int:
        ids = ids[self._removed[ids] == _NEVER]
        self._removed[ids] = self.n_updates
        self._alive -= len(ids)
        return len(ids)

    def _facing(self, ids: NDArray[np.int64], robot: Pose) -> NDArray[np.bool_]:
        segs = self._segments[ids]
        c, s = np.cos(robot.theta), np.sin(robot.theta)
        fwd0 = c * (segs[:, 0] - robot.x) + s * (segs[:, 1] - robot.y)
        fwd1 = c * (segs[:, 2] - robot.x) + s * (segs[:, 3] - robot.y)
        test = self.params.facing_test
        if test == "midpoint":
            return (fwd0 + fwd1) > 0.0
        if test == "any_endpoint":
            return (fwd0 > 0.0) | (fwd1 > 0.0)
        return (fwd0 > 0.0) & (fwd1 > 0.0)

    def add_view(self, segments: NDArray[np.float64], map_id: int, robot: Pose) -> UpdateReport:
        """Algorithm #5: add view ``map_id`` (surfaces in the global frame, scan order) seen
        from ``robot`` (global pose), deleting overlapping older information first."""
        segs = as_segments(segments)
        self.n_updates += 1
        if self.last_map_id is not None and map_id <= self.last_map_id:
            raise ValueError(f"map ids must increase: got {map_id} after {self.last_map_id}")
        viewpoint = robot if self.params.include_viewpoint else None
        poly = view_polygon(segs, viewpoint, self.params.enlarge_m)
        current = self.last_map_id
        deleted_current = deleted_older = 0
        affected: tuple[int, ...] = ()
        group: tuple[int, ...] = ()
        if self._alive and not poly.is_empty:
            cand = self._index.query_box(*poly.bounds)
            cand = cand[self._removed[cand] == _NEVER]
            if len(cand):
                shapely.prepare(poly)
                lines = shapely.linestrings(self._segments[cand].reshape(-1, 2, 2))
                hit = cand[shapely.intersects(poly, lines)]
                hit_maps = self._map_ids[hit]
                deleted_current = self._delete(hit[hit_maps == current])
                older = np.unique(hit_maps[hit_maps != current])
                affected = tuple(int(m) for m in older)
                if affected:
                    if self.params.expand_group:
                        group = tuple(
                            m for m in range(affected[0], affected[-1] + 1) if m in self._by_map
                        )
                    else:
                        group = affected
                    ids = np.concatenate([self._by_map[m] for m in group])
                    ids = ids[self._removed[ids] == _NEVER]
                    deleted_older = self._delete(ids[self._facing(ids, robot)])
        self._append(segs, map_id)
        return UpdateReport(
            self.n_updates, map_id, deleted_current, affected, group, deleted_older, len(segs), poly
        )

    def insert(self, segments: NDArray[np.float64], map_id: int) -> None:
        """Add surfaces as one update without deleting anything (naive integration, tests)."""
        segs = as_segments(segments)
        if self.last_map_id is not None and map_id <= self.last_map_id:
            raise ValueError(f"map ids must increase: got {map_id} after {self.last_map_id}")
        self.n_updates += 1
        self._append(segs, map_id)

    def _append(self, segs: NDArray[np.float64], map_id: int) -> None:
        self._grow(len(segs))
        new_ids = np.arange(self._n, self._n + len(segs), dtype=np.int64)
        self._segments[new_ids] = segs
        self._map_ids[new_ids] = map_id
        self._added[new_ids] = self.n_updates
        self._removed[new_ids] = _NEVER
        self._n += len(segs)
        self._alive += len(segs)
        self._by_map[map_id] = new_ids
        self._index.insert(new_ids, segs)
        self.last_map_id = map_id

    def snapshot(self, at_update: int | None = None) -> MapSnapshot:
        """The map now, or as it was right after update number ``at_update`` (1-based)."""
        n = self._n
        if at_update is None:
            keep = self._removed[:n] == _NEVER
        else:
            keep = (self._added[:n] <= at_update) & (self._removed[:n] > at_update)
        return MapSnapshot(self._segments[:n][keep].copy(), self._map_ids[:n][keep].copy())
