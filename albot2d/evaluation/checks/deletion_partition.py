"""Algorithm #5 checked both ways: every update deleted exactly the surfaces its rule says.

``update_deletes_facing_overlap`` in full: the surfaces alive before an update split into
those kept and those deleted; the set the rule deletes is recomputed here from the rule's
definition (``albot2d.mapping.albot1.deletion``'s module docstring, every reading of
``GlobalMapParams``) and must equal the set the map deleted, so both an update that keeps
a surface it should delete and one that deletes a surface it should keep fail.

The recomputation is plain and independent of the mapper's deletion code (no spatial
index, no quick touching test, no compiled kernels): P built with shapely from its
definition, every live surface asked against it, the
facing and seen-side tests, the visible share decided by shapely sight lines
(``checks.deletion.visible_mask``, itself checked against the definition asked point by
point), Expand's groups from the affected ids, the current map's rule and ``keep_if_all``.
What the map deleted is read through the view-based mapper protocol only: the map right
before the update and right after it (``global_map(at_update=…)``); surfaces are never
modified, so the map after is the map before minus the deleted surfaces plus the view.
"""

from __future__ import annotations

import math

import numpy as np
import shapely
from numpy.typing import NDArray

from albot2d.errors import InvariantError, fail
from albot2d.evaluation.checks.deletion import ahead_square, facing_mask, visible_mask
from albot2d.geometry import Pose
from albot2d.mapping.albot1.deletion import GlobalMapParams
from albot2d.mapping.albot1.global_map import UpdateReport
from albot2d.mapping.albot1.mapper import Albot1
from albot2d.mapping.albot1.route_map import LocalMap
from albot2d.mapping.protocol import MapSnapshot
from albot2d.perception.surfaces import transform_segments_fast

__all__ = [
    "UpdateRecorder",
    "check_update_partition",
    "deleted_by_update",
    "expand_groups",
    "expected_deletions",
    "view_polygon",
]

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]

NAME = "update_deletes_facing_overlap"


def expand_groups(affected: list[int], rule: str, gap_maps: int, existing: set[int]) -> set[int]:
    """Expand (the paper's "25 and 28 → 25…28"), from its definition: ``split`` fills each
    run of affected ids whose consecutive gaps are at most ``gap_maps``; ``contiguous``
    fills first…last; ``none`` keeps the affected ids; only ids in ``existing``."""
    ids = sorted(set(affected))
    if not ids:
        return set()
    if rule == "none":
        return set(ids) & existing
    if rule == "contiguous":
        return set(range(ids[0], ids[-1] + 1)) & existing
    out: set[int] = set()
    start = ids[0]
    for prev, nxt in zip(ids, [*ids[1:], None], strict=True):
        if nxt is None or nxt - prev > gap_maps:
            out |= set(range(start, prev + 1))
            if nxt is not None:
                start = nxt
    return out & existing


def view_polygon(view: FloatArray, robot: Pose, params: GlobalMapParams) -> shapely.Geometry:
    """P from its definition: the viewpoint (with ``include_viewpoint``) and the view's
    endpoints in scan order, those pushed ``enlarge_m`` away from the viewpoint
    (``radial``) or the polygon buffered by ``enlarge_m`` (``forward``: then cut to the
    half-plane in front of the robot's lateral axis); fewer than three points: a disc
    round each (of at least a micrometre)."""
    o = np.array([robot.x, robot.y])
    pts = np.asarray(view, np.float64).reshape(-1, 2)
    if params.enlarge == "radial" and len(pts):
        away = pts - o
        norm = np.hypot(away[:, 0], away[:, 1])[:, None]
        pts = pts + np.where(norm > 1e-9, params.enlarge_m * away / np.maximum(norm, 1e-9), 0.0)
    if params.include_viewpoint:
        pts = np.vstack([o, pts])
    if len(pts) == 0:
        return shapely.Polygon()
    grow = 0.0 if params.enlarge == "radial" else params.enlarge_m
    if len(pts) < 3:
        poly = shapely.MultiPoint(pts).buffer(max(grow, 1e-6))
    else:
        poly = shapely.make_valid(shapely.Polygon(pts))
        if grow > 0:
            poly = poly.buffer(grow)
    if params.enlarge == "forward":
        big = 10.0 * (1.0 + float(np.abs(pts - o).max()) + grow)
        poly = poly.intersection(ahead_square(robot, big))
    return poly


def expected_deletions(
    segments: FloatArray,
    map_ids: NDArray[np.int64],
    view: FloatArray,
    robot: Pose,
    current: int | None,
    params: GlobalMapParams,
    existing: set[int],
) -> BoolArray:
    """``(N,)``: which of the live surfaces ``segments`` (with ``map_ids``) the rule deletes
    when ``view`` (map frame, scan order) is added from ``robot``; ``current`` is the map
    being left (``None`` at the first update), ``existing`` every map id added so far."""
    p = params
    segs = np.asarray(segments, np.float64).reshape(-1, 4)
    ids = np.asarray(map_ids, np.int64)
    view = np.asarray(view, np.float64).reshape(-1, 4)
    n = len(segs)
    none = np.zeros(n, dtype=bool)
    if n == 0:
        return none
    poly = view_polygon(view, robot, p)
    if poly.is_empty:
        return none
    lines = shapely.linestrings(segs.reshape(-1, 2, 2))
    touch = np.asarray(shapely.intersects(poly, lines), bool)
    if p.forward_ray_m > 0:
        tip = (
            robot.x + p.forward_ray_m * math.cos(robot.theta),
            robot.y + p.forward_ray_m * math.sin(robot.theta),
        )
        ray = shapely.LineString([(robot.x, robot.y), tip])
        touch |= np.asarray(shapely.intersects(ray, lines), bool)
    seeable = facing_mask(segs, robot, p.facing_test)
    if p.seen_side == "front":
        d = segs[:, 2:] - segs[:, :2]
        r = np.array([robot.x, robot.y]) - segs[:, :2]
        seeable &= d[:, 0] * r[:, 1] - d[:, 1] * r[:, 0] > 0
    is_current = ids == current if current is not None else none
    # "Could see" among the touching surfaces (the current map's and the in-view readings).
    could_see = touch & seeable
    if p.could_see == "visible" and could_see.any() and len(view):
        idx = np.flatnonzero(could_see)
        could_see[idx] = visible_mask(
            segs[idx], view, robot, p.enlarge_m, p.visible_samples, p.min_visible_share,
            backend="numpy",
        )  # fmt: skip
    elif p.could_see == "visible":
        could_see[:] = False
    deleted = (touch if p.current_map == "touch" else could_see) & is_current
    touched = touch if p.current_in_group else touch & ~is_current
    group = expand_groups(ids[touched].tolist(), p.expand, p.group_gap_maps, existing)
    group.discard(current if current is not None else -1)
    in_group = np.isin(ids, sorted(group)) & ~is_current
    if p.could_see in ("in_view", "visible"):
        older = in_group & could_see
    else:
        older = in_group & seeable
        if p.could_see == "in_range":
            pts = view.reshape(-1, 2)
            reach = float(np.max(np.hypot(pts[:, 0] - robot.x, pts[:, 1] - robot.y), initial=0.0))
            reach += p.enlarge_m
            d0 = np.hypot(segs[:, 0] - robot.x, segs[:, 1] - robot.y)
            d1 = np.hypot(segs[:, 2] - robot.x, segs[:, 3] - robot.y)
            older &= (d0 <= reach) & (d1 <= reach)
    deleted |= older
    if p.keep_if_all and deleted.sum() >= n:
        return none
    return deleted


def deleted_by_update(before: MapSnapshot, after: MapSnapshot, map_id: int) -> BoolArray:
    """``(N,)`` over ``before``'s surfaces: which are gone from ``after``. ``after`` must be
    ``before`` with some surfaces removed (order kept) and map ``map_id``'s added; anything
    else (a surface moved or changed) fails the invariant."""
    keep_after = after.map_ids != map_id
    a_segs, a_ids = after.segments[keep_after], after.map_ids[keep_after]
    gone = np.ones(len(before.map_ids), dtype=bool)
    j = 0
    for i in range(len(before.map_ids)):
        if (
            j < len(a_ids)
            and a_ids[j] == before.map_ids[i]
            and np.array_equal(a_segs[j], before.segments[i])
        ):
            gone[i] = False
            j += 1
    if j != len(a_ids):
        fail(
            NAME,
            f"update adding map {map_id}: the map after it holds {len(a_ids) - j} surface(s) "
            "of earlier maps that were not in the map before it (moved or changed)",
        )
    return gone


def check_update_partition(
    before: MapSnapshot,
    after: MapSnapshot,
    update: int,
    map_id: int,
    robot: Pose,
    view: FloatArray,
    params: GlobalMapParams,
    existing: set[int],
) -> None:
    """The surfaces update ``update`` (adding map ``map_id``'s ``view`` from ``robot``)
    deleted are exactly those the rule deletes: none kept that it deletes, none deleted
    that it keeps."""
    gone = deleted_by_update(before, after, map_id)
    current = max((m for m in existing if m < map_id), default=None)
    want = expected_deletions(
        before.segments, before.map_ids, view, robot, current, params, existing
    )
    kept_wrongly = want & ~gone
    deleted_wrongly = gone & ~want
    if kept_wrongly.any() or deleted_wrongly.any():
        parts = []
        if kept_wrongly.any():
            maps = sorted(set(before.map_ids[kept_wrongly].tolist()))
            parts.append(
                f"{int(kept_wrongly.sum())} surface(s) of map(s) {maps[:8]} kept that the "
                "rule deletes (they remain in view on the facing side)"
            )
        if deleted_wrongly.any():
            maps = sorted(set(before.map_ids[deleted_wrongly].tolist()))
            parts.append(
                f"{int(deleted_wrongly.sum())} surface(s) of map(s) {maps[:8]} deleted that "
                "the rule keeps"
            )
        fail(
            NAME,
            f"update {update} (map {map_id}): " + "; ".join(parts)
            + f" ({int(gone.sum())} deleted, {int(want.sum())} by the rule)",
        )  # fmt: skip


class UpdateRecorder:
    """An Albot1 ``on_update`` hook checking algorithm #5 after every update, both ways
    (``check_update_partition``: the surfaces deleted are exactly those the rule deletes,
    recomputed from its definition).

    With ``raise_at_once`` (tests) a violation propagates out of ``observe``; otherwise
    (the campaign) the run goes on and the messages collect in ``violations``.
    """

    def __init__(self, mapper: Albot1 | None = None, *, raise_at_once: bool = True) -> None:
        self.mapper = mapper
        self.raise_at_once = raise_at_once
        self.updates = 0
        self.violations: list[str] = []

    def attach(self, mapper: Albot1) -> UpdateRecorder:
        """Hook into ``mapper`` (its ``on_update``); returns self."""
        self.mapper = mapper
        mapper.on_update = self
        return self

    def __call__(self, report: UpdateReport, lm: LocalMap) -> None:
        if self.mapper is None:
            raise RuntimeError("UpdateRecorder: attach it to a mapper first")
        self.updates += 1
        m = self.mapper
        try:
            view = transform_segments_fast(lm.pose, lm.view.segments)
            check_update_partition(
                m.global_map(report.update - 1), m.global_map(report.update), report.update,
                report.map_id, lm.pose, view, m.map.params,
                {x.map_id for x in m.route if x.map_id <= report.map_id},
            )  # fmt: skip
        except InvariantError as exc:
            if self.raise_at_once:
                raise
            self.violations.append(exc.message)
