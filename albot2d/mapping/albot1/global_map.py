"""Albot1's transient global map (algorithm #5): add each remembered view, delete what overlaps.

Every surface is tagged with the id of the local map it came from. Adding a view:

1. P = the polygon joining the view's surface endpoints in scan order (through the
   viewpoint, so P is the area the view saw), enlarged (by default 0.5 m in front of the
   robot only);
2. surfaces touching P make their maps "affected"; those of the current map (the one the
   robot is leaving) that the robot could see are deleted;
3. the affected maps are grouped (the paper's Expand: 25 and 28 → 25…28, split where the
   ids jump) and the group's surfaces the robot could see from where it is are deleted
   (by default: on the facing side, seen from this side, and wholly visible through the
   incoming view, at most 0.5 m beyond its surfaces);
4. the incoming view is added.

Which surfaces "could be seen", how P is enlarged and how far a group reaches are the
paper's gaps; ``albot2d.mapping.albot1.deletion`` holds the rule and its named readings.

Surfaces are never modified, only added and deleted, so each carries the update number at
which it was added and removed: any past state of the map is a cheap filter
(``snapshot(at_update=k)``), which is how the map's evolution is shown (paper Figs. 7, 10–15).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import NamedTuple

import numpy as np
import shapely
from numpy.typing import NDArray

from albot2d.geometry import Pose, as_segments
from albot2d.geometry.spatial_index import grid_index, sorted_unique
from albot2d.mapping.albot1.deletion import (
    GlobalMapParams,
    facing_seen_mask,
    group_maps,
    in_range_mask,
    quick_touch_box,
    quick_touch_ring,
    quick_touching_mask,
    touching_mask,
    view_polygon,
    visible_share,
)
from albot2d.mapping.protocol import MapSnapshot  # the value type every mapper returns

__all__ = ["GlobalMap", "GlobalMapParams", "MapSnapshot", "UpdateReport", "view_polygon"]

_NEVER = np.iinfo(np.int64).max


class UpdateReport(NamedTuple):
    """What one update did (for traces, tests and the fuzzing invariants)."""

    update: int
    map_id: int
    deleted_current: int
    affected_maps: tuple[int, ...]
    group: tuple[int, ...]
    deleted_older: int
    added: int
    #: P, or a function building it on first use (most updates never need P built).
    polygon_or_maker: shapely.Geometry | Callable[[], shapely.Geometry]

    @property
    def polygon(self) -> shapely.Geometry:
        """The enlarged view polygon P of this update."""
        got = self.polygon_or_maker
        return got() if callable(got) else got


class _LazyPolygon:
    """The view polygon P of one update, built on first call (most updates never need it)."""

    __slots__ = ("_args", "_polygon")

    def __init__(self, segs: NDArray[np.float64], robot: Pose, params: GlobalMapParams) -> None:
        self._args = (segs, robot, params)
        self._polygon: shapely.Geometry | None = None

    def __call__(self) -> shapely.Geometry:
        if self._polygon is None:
            segs, robot, p = self._args
            self._polygon = view_polygon(
                segs, robot, p.enlarge_m, p.enlarge, include_viewpoint=p.include_viewpoint
            )
        return self._polygon


class GlobalMap:
    """The global map of algorithm #5, with a grid index and a full add/delete history."""

    def __init__(self, params: GlobalMapParams | None = None) -> None:
        params = params if params is not None else GlobalMapParams()
        self.params = params
        self._segments = np.zeros((64, 4))
        self._map_ids = np.zeros(64, np.int64)
        self._added = np.zeros(64, np.int64)
        self._removed = np.full(64, _NEVER, np.int64)
        self._n = 0
        self._alive = 0
        self._by_map: dict[int, NDArray[np.int64]] = {}
        #: The ids added so far: a range while they are consecutive (Albot1's are), else
        #: ``_by_map`` itself; what group expansion picks from.
        self._ids: range | dict[int, NDArray[np.int64]] = range(0)
        self._index = grid_index(params.index_cell_m)
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

    def _mark_deleted(self, ids: NDArray[np.int64]) -> NDArray[np.int64]:
        """Mark the live ones of ``ids`` removed at this update; returns them (the caller
        forgets them in the index, once for the whole update)."""
        ids = ids.compress(self._removed.take(ids) == _NEVER)
        self._removed[ids] = self.n_updates
        self._alive -= len(ids)
        return ids

    def _alive_ids(self, ids: NDArray[np.int64]) -> NDArray[np.int64]:
        return ids[self._removed[ids] == _NEVER]

    def add_view(self, segments: NDArray[np.float64], map_id: int, robot: Pose) -> UpdateReport:
        """Algorithm #5: add view ``map_id`` (surfaces in the global frame, scan order) seen
        from ``robot`` (global pose), deleting overlapping older information first."""
        segs = as_segments(segments)
        if self.last_map_id is not None and map_id <= self.last_map_id:
            raise ValueError(f"map ids must increase: got {map_id} after {self.last_map_id}")
        self.n_updates += 1
        p = self.params
        make_polygon = _LazyPolygon(segs, robot, p)
        ring = quick_touch_ring(segs, robot, p)  # None: P built now, tested by GEOS
        poly = make_polygon() if ring is None else None
        current = self.last_map_id
        doomed = np.zeros(0, np.int64)
        n_current = 0
        affected: tuple[int, ...] = ()
        group: tuple[int, ...] = ()
        if self._alive and (poly is None or not poly.is_empty):
            if poly is None:
                assert ring is not None
                # The index holds live ids only (deletions leave it at once).
                cand = self._index.query_box(*quick_touch_box(ring, p.enlarge_m))
                touch = quick_touching_mask(
                    ring, make_polygon, self._segments.take(cand, axis=0), robot, p.enlarge_m
                )
            else:
                box = shapely.bounds(poly).tolist()
                if p.forward_ray_m > 0:
                    tip = robot @ Pose(p.forward_ray_m, 0.0, 0.0)
                    box = [min(box[0], tip.x), min(box[1], tip.y),
                           max(box[2], tip.x), max(box[3], tip.y)]  # fmt: skip
                cand = self._index.query_box(*box)
                touch = touching_mask(
                    poly, self._segments.take(cand, axis=0), robot, p.forward_ray_m
                )
            # take/compress, not fancy indexing: the same arrays at a third of the cost on
            # the few dozen rows of an update (~1.5 µs each, a dozen per update).
            hit = cand.compress(touch)
            hit_maps = self._map_ids.take(hit)
            hsegs = self._segments.take(hit, axis=0)
            visible = facing_seen_mask(hsegs, robot, p.facing_test, p.seen_side)
            if p.could_see == "visible" and visible.any():
                share = visible_share(
                    hsegs.compress(visible, axis=0), segs, robot, p.enlarge_m, p.visible_samples
                )
                visible[visible] = (share > 0.0) & (share >= p.min_visible_share)
            is_current = hit_maps == current
            cur_del = is_current if p.current_map == "touch" else is_current & visible
            doomed = hit.compress(cur_del)
            n_current = len(doomed)
            touched = hit_maps if p.current_in_group else hit_maps.compress(~is_current)
            affected = tuple(sorted(set(touched.tolist())))  # np.unique's, without numpy's overhead
            group = group_maps(affected, p.expand, p.group_gap_maps, self._ids)
            # Any map of the group but the current one (a group spans up to every id).
            if len(group) > 1 or (group and group[0] != current):
                if p.could_see in ("in_view", "visible"):
                    # Every hit's map is affected (or the current one) and every affected
                    # map is in its group (each id ever added is in _by_map), so the hits
                    # in the older group are exactly those not of the current map.
                    older = hit.compress(~is_current & visible)
                else:
                    older_group = [m for m in group if m != current]
                    ids = self._alive_ids(np.concatenate([self._by_map[m] for m in older_group]))
                    gsegs = self._segments[ids]
                    keep = facing_seen_mask(gsegs, robot, p.facing_test, p.seen_side)
                    if p.could_see == "in_range":
                        pts = segs.reshape(-1, 2)
                        reach = float(
                            np.max(np.hypot(pts[:, 0] - robot.x, pts[:, 1] - robot.y), initial=0.0)
                        )
                        keep &= in_range_mask(gsegs, robot, reach + p.enlarge_m)
                    older = ids[keep]
                doomed = np.concatenate([doomed, older])
            if p.keep_if_all and len(np.unique(doomed)) >= self._alive:
                doomed = np.zeros(0, np.int64)
                n_current = 0
        deleted_older = deleted_current = 0
        if len(doomed):
            older_ids = self._mark_deleted(sorted_unique(doomed[n_current:]))
            current_ids = self._mark_deleted(doomed[:n_current])
            deleted_older, deleted_current = len(older_ids), len(current_ids)
            gone = np.concatenate([older_ids, current_ids])
            # Speed: queries see live ids only.
            self._index.remove(gone, self._segments.take(gone, axis=0))
        self._append(segs, map_id)
        return UpdateReport(
            self.n_updates, map_id, deleted_current, affected, group, deleted_older, len(segs),
            make_polygon if poly is None else poly,
        )  # fmt: skip

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
        ids = self._ids
        if isinstance(ids, range) and self.last_map_id in (None, map_id - 1):
            # Every id first…map_id so far: a range answers ``in`` and groups in C.
            self._ids = range(ids.start if self.last_map_id is not None else map_id, map_id + 1)
        else:
            self._ids = self._by_map
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
