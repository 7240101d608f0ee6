"""The invariant of algorithm #5 (``update_deletes_facing_overlap``): after every global-map
update no surface of an earlier map remains that the deletion rule says the robot could
see. Everything is recomputed here from the definitions (view polygon, facing side, seen
side, sight lines) with shapely, independently of the mapper's own deletion code;
``UpdateRecorder`` runs the check after each update of an ``Albot1``."""

from __future__ import annotations

import math

import numpy as np
import shapely
from numpy.typing import NDArray

from albot2d.evaluation.invariant_base import InvariantError, fail
from albot2d.geometry import Pose, transform_segments
from albot2d.mapping.albot1 import Albot1
from albot2d.mapping.global_map import UpdateReport
from albot2d.mapping.route_map import LocalMap

__all__ = ["UpdateRecorder", "check_update_deleted_facing_overlap"]

FloatArray = NDArray[np.float64]


# -- algorithm #5 ---------------------------------------------------------------------------
def _facing(segs: FloatArray, robot: Pose, test: str) -> NDArray[np.bool_]:
    c, s = math.cos(robot.theta), math.sin(robot.theta)
    fwd0 = c * (segs[:, 0] - robot.x) + s * (segs[:, 1] - robot.y)
    fwd1 = c * (segs[:, 2] - robot.x) + s * (segs[:, 3] - robot.y)
    if test == "any_endpoint":
        return (fwd0 > 0.0) | (fwd1 > 0.0)
    if test == "both_endpoints":
        return (fwd0 > 0.0) & (fwd1 > 0.0)
    return (fwd0 + fwd1) > 0.0


def _ahead(robot: Pose, big: float) -> shapely.Geometry:
    """The square ``x >= 0`` of the robot's frame, ``big`` a side, in the map's frame: the
    corners moved as ``shapely.affinity.affine_transform`` moves them (the same floats),
    without its per-geometry overhead."""
    x = np.array([0.0, big, big, 0.0, 0.0])
    y = np.array([-big, -big, big, big, -big])
    c, s = math.cos(robot.theta), math.sin(robot.theta)
    return shapely.polygons(np.stack([c * x + -s * y + robot.x, s * x + c * y + robot.y]).T)


def _view_polygon(
    view: FloatArray, robot: Pose, enlarge_m: float, mode: str, through_viewpoint: bool
) -> shapely.Geometry:
    """P from its definition: the view's endpoints joined in scan order (from the
    viewpoint), enlarged by ``enlarge_m`` (a buffer, cut at the robot's lateral axis for
    ``forward``; every vertex moved ``enlarge_m`` away from the viewpoint for ``radial``)."""
    o = np.array([robot.x, robot.y])
    pts = view.reshape(-1, 2)
    if mode == "radial":
        away = pts - o
        norm = np.linalg.norm(away, axis=1, keepdims=True)
        pts = pts + enlarge_m * away / np.where(norm > 0, norm, 1.0)
    if through_viewpoint:
        pts = np.vstack([o, pts])
    if len(pts) < 3:
        return shapely.MultiPoint(pts).buffer(max(enlarge_m, 1e-6))
    poly = shapely.make_valid(shapely.Polygon(pts))
    if mode == "radial":
        return poly
    poly = poly.buffer(enlarge_m)
    if mode == "forward":  # keep x >= 0 in the robot frame
        big = 10.0 * (1.0 + float(np.abs(pts - o).max()) + enlarge_m)
        poly = poly.intersection(_ahead(robot, big))
    return poly


def _seen_samples(
    segs: FloatArray,
    view: FloatArray,
    robot: Pose,
    beyond_m: float,
    samples: int,
    least_share: float = 0.0,
) -> NDArray[np.bool_]:
    """``(N, samples)``: which of the surfaces' sample points are seen from the viewpoint:
    the sight line through the point meets a view surface, the nearest meeting at most
    ``beyond_m`` short of the point (or beyond it). A surface whose sight lines meet the
    view at fewer than ``least_share`` of its points cannot reach that share seen, and is
    left all unseen without the second test.

    Both halves are shapely predicates on the prepared view surfaces (six times cheaper
    than constructing each meeting and measuring its distance): the whole sight line meets
    the view, and its piece from the viewpoint to ``beyond_m`` short of the point does not
    (a meeting there is nearer than the rule allows)."""
    frac = (np.arange(samples) + 0.5) / samples
    pts = segs[:, None, :2] + frac[None, :, None] * (segs[:, None, 2:] - segs[:, None, :2])
    pts = pts.reshape(-1, 2)
    o = np.array([robot.x, robot.y])
    dist = np.linalg.norm(pts - o, axis=1)
    unit = (pts - o) / np.maximum(dist, 1e-12)[:, None]
    origin = np.broadcast_to(o, pts.shape)
    surfaces = shapely.multilinestrings(view.reshape(-1, 2, 2))
    shapely.prepare(surfaces)
    # The sight line goes on past the point (a point in front of the view's surfaces is in
    # the free space the laser crossed): as far as the farthest view point, and more.
    reach = float(np.linalg.norm(view.reshape(-1, 2) - o, axis=1).max()) + 1.0
    far = o + unit * (reach + dist)[:, None]
    meets = shapely.intersects(surfaces, shapely.linestrings(np.stack([origin, far], axis=1)))
    meets = meets.reshape(len(segs), samples)
    meets &= (meets.mean(axis=1) >= least_share)[:, None]
    short = dist - beyond_m
    ahead = np.flatnonzero(meets.ravel() & (short > 0.0))  # a nearer meeting is possible
    blocked = np.zeros(len(pts), dtype=bool)
    if len(ahead):
        stop = o + unit[ahead] * short[ahead, None]
        blocked[ahead] = shapely.intersects(
            surfaces, shapely.linestrings(np.stack([origin[ahead], stop], axis=1))
        )
    return meets & ~blocked.reshape(len(segs), samples)


def _touching(poly: shapely.Geometry, segs: FloatArray) -> NDArray[np.bool_]:
    """Which surfaces touch ``poly``: only those whose bounding box meets the polygon's are
    asked (a map holds hundreds of surfaces, a view polygon is a few metres across)."""
    x0, y0, x1, y1 = poly.bounds
    out = np.zeros(len(segs), dtype=bool)
    near = np.flatnonzero(
        (np.minimum(segs[:, 0], segs[:, 2]) <= x1) & (np.maximum(segs[:, 0], segs[:, 2]) >= x0)
        & (np.minimum(segs[:, 1], segs[:, 3]) <= y1) & (np.maximum(segs[:, 1], segs[:, 3]) >= y0)
    )  # fmt: skip
    if len(near):
        shapely.prepare(poly)
        out[near] = shapely.intersects(poly, shapely.linestrings(segs[near].reshape(-1, 2, 2)))
    return out


def check_update_deleted_facing_overlap(
    m: Albot1, report: UpdateReport, robot: Pose, view: FloatArray
) -> None:
    """Right after an update that added ``view`` (its surfaces in the map's frame, scan
    order) seen from ``robot``: no surface of an earlier map remains that the rule says the
    robot could see, all recomputed here from the definitions: it touches the enlarged view
    polygon P, lies on the facing side (the rule's facing test), and, as the rule asks,
    the robot is on the side it was seen from and enough of it is visible through the view
    (``could_see="visible"``). With ``current_map="touch"`` no surface of the map being
    left touches P at all. (A rule with ``keep_if_all`` may skip an update that would
    empty the map.)"""
    name = "update_deletes_facing_overlap"
    params = m.map.params
    snap = m.map.snapshot()
    older = snap.map_ids < report.map_id
    view = np.asarray(view, np.float64).reshape(-1, 4)
    if not older.any() or len(view) == 0:
        return
    if params.keep_if_all and report.deleted_current + report.deleted_older == 0:
        return
    segs = snap.segments[older]
    ids = snap.map_ids[older]
    poly = _view_polygon(view, robot, params.enlarge_m, params.enlarge, params.include_viewpoint)
    hits = _touching(poly, segs)
    seeable = hits & _facing(segs, robot, params.facing_test)
    if params.seen_side == "front":  # the robot on the left of the directed surface
        d = segs[:, 2:] - segs[:, :2]
        r = np.array([robot.x, robot.y]) - segs[:, :2]
        seeable &= d[:, 0] * r[:, 1] - d[:, 1] * r[:, 0] > 0
    if params.could_see == "visible" and seeable.any():
        share = np.zeros(len(segs))
        share[seeable] = _seen_samples(
            segs[seeable], view, robot, params.enlarge_m, params.visible_samples,
            least_share=params.min_visible_share,
        ).mean(axis=1)  # fmt: skip
        seeable &= (share > 0) & (share >= params.min_visible_share)
    current = report.map_id - 1
    left = (hits if params.current_map == "touch" else seeable) & (ids == current)
    if left.any():
        fail(
            name,
            f"update {report.update} (map {report.map_id}): {int(left.sum())} surface(s) "
            f"of the map being left remain inside the view polygon",
        )
    stale = seeable & (ids < current)
    if stale.any():
        fail(
            name,
            f"update {report.update} (map {report.map_id}): {int(stale.sum())} older "
            f"surface(s) of map(s) {sorted(set(ids[stale].tolist()))} remain in view "
            "on the facing side",
        )


class UpdateRecorder:
    """An Albot1 ``on_update`` hook checking algorithm #5's postcondition after every update.

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
        try:
            view = transform_segments(lm.pose.as_array(), lm.view.segments)
            check_update_deleted_facing_overlap(self.mapper, report, lm.pose, view)
        except InvariantError as exc:
            if self.raise_at_once:
                raise
            self.violations.append(exc.message)
