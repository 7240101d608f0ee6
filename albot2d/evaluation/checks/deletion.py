"""The invariant of algorithm #5 (``update_deletes_facing_overlap``): after every global-map
update no surface of an earlier map remains that the deletion rule says the robot could
see. Everything is recomputed here from the definitions (view polygon, facing side, seen
side, sight lines) with shapely, independently of the mapper's own deletion code;
``deletion_partition`` asks the same both ways after each update of an ``Albot1``
(``deletion_partition.UpdateRecorder``).

A surface's verdict is a conjunction of per-surface tests, asked cheapest first. Before
shapely is asked whether a sample point is seen, plain geometry proves most points unseen
with a micrometre / micro-radian margin (beyond the view's reach, outside every view
surface's fan, or crossing a view surface more than ``enlarge_m`` short of the point);
those tests are compiled when numba imports (``deletion_numba``), with the numpy path
kept. P is built only for a surface still in question. The
verdicts equal the definition asked in full (``tests/test_deletion_invariant.py``)."""

from __future__ import annotations

import functools
import math
from types import ModuleType

import numpy as np
import shapely
from numpy.typing import NDArray

from albot2d.compiled import compiled_module
from albot2d.errors import fail
from albot2d.geometry import Pose
from albot2d.mapping.albot1.deletion import GlobalMapParams
from albot2d.mapping.albot1.global_map import UpdateReport
from albot2d.mapping.albot1.mapper import Albot1

__all__ = ["ahead_square", "check_update_deleted_facing_overlap", "facing_mask", "visible_mask"]

FloatArray = NDArray[np.float64]


# -- algorithm #5 ---------------------------------------------------------------------------
def facing_mask(segs: FloatArray, robot: Pose, test: str) -> NDArray[np.bool_]:
    """The surfaces on the robot's facing side by the rule's facing ``test``
    (``any_endpoint``, ``both_endpoints`` or, otherwise, the midpoint) ahead of its pose."""
    c, s = math.cos(robot.theta), math.sin(robot.theta)
    fwd0 = c * (segs[:, 0] - robot.x) + s * (segs[:, 1] - robot.y)
    fwd1 = c * (segs[:, 2] - robot.x) + s * (segs[:, 3] - robot.y)
    if test == "any_endpoint":
        return (fwd0 > 0.0) | (fwd1 > 0.0)
    if test == "both_endpoints":
        return (fwd0 > 0.0) & (fwd1 > 0.0)
    return (fwd0 + fwd1) > 0.0


_FACING_TESTS = ("any_endpoint", "both_endpoints", "midpoint")


def _facing_front(segs: FloatArray, robot: Pose, test: str, front: bool) -> NDArray[np.bool_]:
    """The surfaces on the facing side (the rule's facing test) and, with ``front``, with
    the robot on the side they were seen from (on the left of the directed surface)."""
    kernels = _kernels()
    if kernels is not None and test in _FACING_TESTS:
        return kernels.facing_front(
            np.ascontiguousarray(segs), float(robot.x), float(robot.y),
            math.cos(robot.theta), math.sin(robot.theta), _FACING_TESTS.index(test), front,
        )  # fmt: skip
    out = facing_mask(segs, robot, test)
    if front:
        d = segs[:, 2:] - segs[:, :2]
        r = np.array([robot.x, robot.y]) - segs[:, :2]
        out &= d[:, 0] * r[:, 1] - d[:, 1] * r[:, 0] > 0
    return out


def ahead_square(robot: Pose, big: float) -> shapely.Geometry:
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
        poly = poly.intersection(ahead_square(robot, big))
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
    left all unseen without the second test. (Every point is asked; ``visible_mask`` asks only
    the points that can still change a surface's verdict.)"""
    sight = _SightLines(segs, view, robot, beyond_m, samples)
    every = np.arange(len(sight.dist))
    meets = sight.meets(every).reshape(len(segs), samples)
    meets &= (meets.mean(axis=1) >= least_share)[:, None]
    seen = np.zeros(len(every), dtype=bool)
    asked = np.flatnonzero(meets.ravel())
    seen[asked] = ~sight.blocked(asked)
    return seen.reshape(len(segs), samples)


class _SightLines:
    """The sight lines from the viewpoint through ``samples`` points of each surface, and
    the two shapely predicates that decide whether a point is seen (on the prepared view
    surfaces, six times cheaper than constructing each meeting and measuring its distance):
    the whole sight line meets the view, and its piece from the viewpoint to ``beyond_m``
    short of the point does not (a meeting there is nearer than the rule allows). The
    points' coordinates are computed once for all; a subset is asked by index, so a point
    gets the same floats and the same answer whichever other points are asked with it."""

    def __init__(
        self, segs: FloatArray, view: FloatArray, robot: Pose, beyond_m: float, samples: int
    ) -> None:
        frac = (np.arange(samples) + 0.5) / samples
        pts = segs[:, None, :2] + frac[None, :, None] * (segs[:, None, 2:] - segs[:, None, :2])
        pts = pts.reshape(-1, 2)
        self.o = o = np.array([robot.x, robot.y])
        self.dist = np.linalg.norm(pts - o, axis=1)
        self.unit = (pts - o) / np.maximum(self.dist, 1e-12)[:, None]
        self.surfaces = shapely.multilinestrings(view.reshape(-1, 2, 2))
        shapely.prepare(self.surfaces)
        ends = view.reshape(-1, 2) - o
        # The farthest any point of the view lies from the viewpoint (a segment's farthest
        # point is an endpoint). The sight line goes on past the point (a point in front of
        # the view's surfaces is in the free space the laser crossed): that far, and more.
        self.view_reach = float(np.linalg.norm(ends, axis=1).max())
        self.reach = self.view_reach + 1.0
        self.short = self.dist - beyond_m
        self.ends = ends
        self.shape = (len(segs), samples)

    def meets(self, idx: NDArray[np.intp]) -> NDArray[np.bool_]:
        """Whether the sight lines of points ``idx`` meet the view."""
        o = self.o
        far = o + self.unit[idx] * (self.reach + self.dist[idx])[:, None]
        origin = np.broadcast_to(o, far.shape)
        return shapely.intersects(
            self.surfaces, shapely.linestrings(np.stack([origin, far], axis=1))
        )

    def blocked(self, idx: NDArray[np.intp]) -> NDArray[np.bool_]:
        """Whether points ``idx`` (whose sight lines meet the view) have a meeting more than
        ``beyond_m`` short of them."""
        out = np.zeros(len(idx), dtype=bool)
        ahead = np.flatnonzero(self.short[idx] > 0.0)  # a nearer meeting is possible
        if len(ahead):
            k = idx[ahead]
            stop = self.o + self.unit[k] * self.short[k, None]
            origin = np.broadcast_to(self.o, stop.shape)
            out[ahead] = shapely.intersects(
                self.surfaces, shapely.linestrings(np.stack([origin, stop], axis=1))
            )
        return out

    def seen(self, idx: NDArray[np.intp]) -> NDArray[np.bool_]:
        """Whether points ``idx`` are seen: their sight line meets the view, and not more
        than ``beyond_m`` short of them."""
        out = self.meets(idx)
        hit = np.flatnonzero(out)
        out[hit] = ~self.blocked(idx[hit])
        return out

    def out_of_reach(self) -> NDArray[np.bool_]:
        """Points provably unseen without asking shapely: farther than ``beyond_m`` (and a
        micrometre) past the view's farthest point. Any meeting of their sight line lies
        within the view's reach, so nearer than the rule allows (blocked), or there is
        none."""
        return self.short > self.view_reach + _MARGIN_M

    def surely_unseen(self, idx: NDArray[np.intp]) -> NDArray[np.bool_]:
        """Which of points ``idx`` are provably unseen without asking shapely, by the view
        surfaces' angular spans from the viewpoint (their fans):

        - the point's bearing lies outside every fan widened by a micro-radian: its sight
          line meets no view surface;
        - or its bearing lies inside some surface's fan narrowed by a micro-radian, so its
          sight line crosses that surface no farther than the surface's farther end, and
          the point lies more than ``beyond_m`` (and a micrometre) past that: blocked.

        A surface passing within a micrometre of the viewpoint, or spanning nearly half a
        turn, turns this test off (the reach test still holds); so does a point within a
        micrometre of the viewpoint."""
        a, b = self.ends[0::2], self.ends[1::2]
        start = np.arctan2(a[:, 1], a[:, 0])
        span = np.arctan2(a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0], (a * b).sum(axis=1))
        start = np.where(span < 0.0, start + span, start)  # counter-clockwise from start
        span = np.abs(span)
        ra, rb = np.linalg.norm(a, axis=1), np.linalg.norm(b, axis=1)
        if ((ra < _MARGIN_M) | (rb < _MARGIN_M) | (span > math.pi - _MARGIN_RAD)).any():
            return np.zeros(len(idx), dtype=bool)
        unit = self.unit[idx]
        bearing = np.arctan2(unit[:, 1], unit[:, 0])
        # The bearing's angle past each fan's start, counted from a micro-radian before it.
        off = np.mod(bearing[:, None] - start[None, :] + _MARGIN_RAD, 2.0 * math.pi)
        outside = ~(off <= span[None, :] + 2.0 * _MARGIN_RAD).any(axis=1)
        inside = (off >= 2.0 * _MARGIN_RAD) & (off <= span[None, :])
        crossing = np.where(inside, np.maximum(ra, rb)[None, :], np.inf).min(axis=1)
        blocked = self.short[idx] > crossing + _MARGIN_M
        return (outside | blocked) & (self.dist[idx] > _MARGIN_M)


# Margins of the provably conservative prefilters (far above float rounding, far below
# anything a map or a view resolves).
_MARGIN_M = 1e-6
_MARGIN_RAD = 1e-6


def visible_mask(
    segs: FloatArray,
    view: FloatArray,
    robot: Pose,
    beyond_m: float,
    samples: int,
    min_share: float,
    backend: str = "auto",
) -> NDArray[np.bool_]:
    """``(N,)``: which surfaces reach the visible share the rule asks (more than none and at
    least ``min_share`` of their ``samples`` points seen, as ``_seen_samples`` decides each
    point). Points the cheap tests prove unseen are not asked; then one point of every
    surface still undecided, then the rest of those still undecided: a surface is decided
    once enough points are seen, or too many not, so with ``min_share`` 1 (the default) one
    unseen point settles it. ``backend``: how the unseen points are proven ("numpy",
    "numba" or "auto": numba when it imports; the same verdicts)."""
    n = len(segs)
    # A surface with k of its points seen has the share k / samples (a mean of booleans).
    ks = np.arange(1, samples + 1)
    enough = ks[ks / samples >= min_share]
    if n == 0 or len(enough) == 0:
        return np.zeros(n, dtype=bool)
    need = int(enough[0])
    kernels = _kernels() if backend != "numpy" else None
    if kernels is None and backend == "numba":
        raise ValueError("backend='numba' needs numba (off under ALBOT2D_KERNELS=numpy)")
    sight = None
    if kernels is not None:
        possible = kernels.possible_points(
            np.ascontiguousarray(segs), np.ascontiguousarray(view), float(robot.x),
            float(robot.y), float(beyond_m), int(samples), need, _MARGIN_M, _MARGIN_RAD,
        )  # fmt: skip
    else:
        sight = _SightLines(segs, view, robot, beyond_m, samples)
        possible = _possible_points(sight, need)
    # Only surfaces with enough points left can still reach the share: their sight lines
    # (each point's floats are its own, whichever surfaces are taken with it).
    rows = np.flatnonzero(possible.sum(axis=1) >= need)
    out = np.zeros(n, dtype=bool)
    if len(rows) == 0:
        return out
    if sight is None or len(rows) < n:
        sight = _SightLines(segs[rows], view, robot, beyond_m, samples)
    possible = possible[rows]
    seen = np.zeros(len(rows), dtype=int)
    unseen = samples - possible.sum(axis=1)
    todo = possible.copy()
    # A few points are asked at once; many, one per surface first (mostly settling it).
    steps = ("rest",) if possible.sum() <= _ASK_AT_ONCE else ("one", "rest")
    first = np.argmax(possible, axis=1)  # one askable point per surface
    for step in steps:
        open_ = (seen < need) & (unseen <= samples - need)
        if step == "one":
            ask = np.zeros_like(todo)
            at = np.flatnonzero(open_)
            ask[at, first[at]] = True
        else:
            ask = todo & open_[:, None]
        at, cols = np.nonzero(ask)
        if len(at) == 0:
            continue
        got = sight.seen(at * samples + cols)
        todo[at, cols] = False
        np.add.at(seen, at, got)
        np.add.at(unseen, at, ~got)
    out[rows] = seen >= need
    return out


# Up to this many points left to ask go to shapely in one round.
_ASK_AT_ONCE = 32


def _possible_points(sight: _SightLines, need: int) -> NDArray[np.bool_]:
    """``(N, samples)``: the points the numpy tests do not prove unseen (a surface's points
    are all left false when too few are left for it to reach ``need`` seen)."""
    n, samples = sight.shape
    possible = ~sight.out_of_reach().reshape(n, samples)
    rows = np.flatnonzero(possible.sum(axis=1) >= need)  # the others are decided already
    flat = possible.ravel()  # a view: marking a point here marks it in ``possible``
    idx = (rows[:, None] * samples + np.arange(samples)).ravel()
    idx = idx[flat[idx]]
    flat[idx] = ~sight.surely_unseen(idx)
    return possible


@functools.cache
def _kernels() -> ModuleType | None:
    """The compiled prefilter (``deletion_invariant_numba``), imported on first use; None
    without numba."""
    return compiled_module("albot2d.evaluation.checks.deletion_numba")


def _touching(
    view: FloatArray, robot: Pose, params: GlobalMapParams, segs: FloatArray, ask: NDArray[np.bool_]
) -> NDArray[np.bool_]:
    """Which surfaces of ``ask`` touch P (the others are left false). P is built only when
    some asked surface meets its bounding box, taken first from the view's points widened by
    the enlargement (a box P never leaves: a buffer or a radial push moves no point farther
    than ``enlarge_m``), then from P itself; only those surfaces are asked of shapely."""
    out = np.zeros(len(segs), dtype=bool)
    near = np.flatnonzero(ask)
    if len(near) == 0:
        return out
    pts = view.reshape(-1, 2)
    if params.include_viewpoint:
        pts = np.vstack([[robot.x, robot.y], pts])
    grow = max(params.enlarge_m, 1e-6) + _MARGIN_M
    lo, hi = pts.min(axis=0) - grow, pts.max(axis=0) + grow
    near = near[_in_box(segs[near], (lo[0], lo[1], hi[0], hi[1]))]
    if len(near) == 0:
        return out
    poly = _view_polygon(view, robot, params.enlarge_m, params.enlarge, params.include_viewpoint)
    near = near[_in_box(segs[near], poly.bounds)]
    if len(near):
        shapely.prepare(poly)
        out[near] = shapely.intersects(poly, shapely.linestrings(segs[near].reshape(-1, 2, 2)))
    return out


def _in_box(segs: FloatArray, box: tuple[float, float, float, float]) -> NDArray[np.bool_]:
    """Which segments' bounding boxes meet ``box`` (x0, y0, x1, y1)."""
    x0, y0, x1, y1 = box
    return (
        (np.minimum(segs[:, 0], segs[:, 2]) <= x1) & (np.maximum(segs[:, 0], segs[:, 2]) >= x0)
        & (np.minimum(segs[:, 1], segs[:, 3]) <= y1) & (np.maximum(segs[:, 1], segs[:, 3]) >= y0)
    )  # fmt: skip


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
    empty the map.)

    A surface's verdict is the conjunction of tests that each look at that surface alone,
    so they run cheapest first, each on the surfaces the earlier ones left: the facing and
    seen-side tests (arithmetic), the visible share (sight lines, mostly settled by one
    point), and last P (built only when a surface is still in question, which after a
    correct update is almost never)."""
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
    current = report.map_id - 1
    seeable = _facing_front(segs, robot, params.facing_test, params.seen_side == "front")
    if params.could_see == "visible" and seeable.any():
        idx = np.flatnonzero(seeable)
        seeable[idx] = visible_mask(
            segs[idx], view, robot, params.enlarge_m, params.visible_samples,
            params.min_visible_share,
        )  # fmt: skip
    touch_current = params.current_map == "touch"
    hits = _touching(view, robot, params, segs, seeable | (touch_current & (ids == current)))
    seeable &= hits
    left = (hits if touch_current else seeable) & (ids == current)
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
