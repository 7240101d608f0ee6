"""Algorithm #5's deletion rule: which surfaces of the global map an incoming view deletes.

The paper (Appendix 3 and section "Computing simultaneously a route map and a global map")
says: compute the polygon P joining the incoming view's surfaces, "slightly enlarged" (by
50 cm) "to remove a bit more of the surfaces in front"; surfaces of the current map inside
or crossing P are removed; older maps with surfaces there are "affected", grouped by
Expand ("25 and 28 → 25…28"), and of those maps only the surfaces "on the facing side" that
the robot "could 'see' from its current position" are removed, which "leaves more
information in the global map, thus creating a residual effect".

It leaves open how P is enlarged, what "facing side" and "could see" mean, and how far a
group reaches. Every reading is a field of ``GlobalMapParams``; four consistent sets are
presets (``GlobalMapParams.preset(name)``):

- ``"visible"`` (default): "could see" read as visibility from the current position. P,
  the facing side and Expand as in ``"paper"``; a surface touching P on the facing side is
  deleted only if the robot is on the side it was seen from (a wall's face cannot be seen
  from behind it) and all of it is visible through the incoming view: every sample point
  lies in the fan of one of the view's surfaces (the sight line meets it) and at most the
  0.5 m enlargement beyond the nearest one, so nothing hidden behind the view's surfaces,
  in the gaps between them (doorways, unextracted clutter) or beside the view is deleted.
  ``min_visible_share`` < 1 deletes surfaces partly in view (0: any sample).
- ``"paper"``: P enlarged by 0.5 m *in front of* the robot only (the buffer is
  clipped at its lateral axis: "surfaces in front"); a surface is deleted only if the robot
  could see it: it touches P and both its endpoints are in front of the robot — for the
  current map too; affected maps (the current one included) are grouped as Expand, split
  where consecutive map ids differ by more than ``group_gap_maps`` (20, the value of the
  authors' code), so a revisit does not wipe the whole history in between.
- ``"v1"``: albot2d's first reading: P buffered 0.5 m all round (behind the robot too), any
  current-map surface touching P deleted whole, one contiguous group from the oldest to the
  newest affected map, "facing side" the half-plane in front of the robot by the surface's
  midpoint. Measured to delete 87–95 % of everything added (the map ends nearly empty).
- ``"original"``: the authors' C++ code (``../shared/spec/albot1-original-code.md`` §5):
  polygon vertices pushed radially out by 0.3 m; a surface of any map is deleted when both
  its endpoints are in front and it touches the view (or crosses the forward ray up to
  3 m); groups split at gaps > 20; group members with both endpoints in front deleted even
  out of view; nothing deleted if that would delete everything.

The functions here are pure and vectorised over ``(N, 4)`` segment arrays; ``GlobalMap``
(``albot2d.mapping.albot1.global_map``) applies them to its store.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from collections.abc import Callable
from dataclasses import dataclass
from types import ModuleType
from typing import Any, Literal

import numpy as np
import shapely
from numpy.typing import NDArray

from albot2d.compiled import compiled_module
from albot2d.errors import InputError
from albot2d.geometry import Pose, as_segments
from albot2d.validation import check_non_negative, check_positive, check_positive_int

__all__ = [
    "DELETION_PRESETS",
    "CouldSee",
    "CurrentMapRule",
    "EnlargeMode",
    "FacingTest",
    "GlobalMapParams",
    "GroupRule",
    "SeenSide",
    "facing_mask",
    "group_maps",
    "in_range_mask",
    "quick_touch_box",
    "quick_touch_ring",
    "quick_touching_mask",
    "seen_side_mask",
    "touching_mask",
    "view_polygon",
    "visible_share",
]

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]

EnlargeMode = Literal["forward", "all_round", "radial"]
CurrentMapRule = Literal["could_see", "touch"]
FacingTest = Literal["both_endpoints", "midpoint", "any_endpoint"]
CouldSee = Literal["in_view", "visible", "in_range", "half_plane"]
SeenSide = Literal["any", "front"]
GroupRule = Literal["split", "contiguous", "none"]

_CHOICES: dict[str, tuple[str, ...]] = {
    "enlarge": ("forward", "all_round", "radial"),
    "current_map": ("could_see", "touch"),
    "facing_test": ("both_endpoints", "midpoint", "any_endpoint"),
    "could_see": ("in_view", "visible", "in_range", "half_plane"),
    "seen_side": ("any", "front"),
    "expand": ("split", "contiguous", "none"),
}


@dataclass(frozen=True, slots=True)
class GlobalMapParams:
    """Parameters of algorithm #5 (defaults: the ``"visible"`` reading; see the module doc).

    - ``enlarge_m``: how much the view polygon is enlarged (paper: 50 cm).
    - ``enlarge``: ``"forward"`` buffer clipped at the robot's lateral axis, ``"all_round"``
      buffer (behind the robot too), or ``"radial"`` vertices pushed out from the viewpoint.
    - ``include_viewpoint``: close the polygon through the viewpoint (the area the view saw)
      rather than only through the surface endpoints.
    - ``current_map``: a current-map surface touching P is deleted only if the robot
      ``"could_see"`` it (the same test as older maps), or whenever it ``"touch"``es P.
    - ``facing_test``: which points of a surface must be in front of the robot for it to
      lie "on the facing side".
    - ``could_see``: which surfaces of the affected group are deleted besides facing:
      ``"in_view"`` those touching P, ``"visible"`` those touching P of which at least
      ``min_visible_share`` (and at least one) of ``visible_samples`` points spread along
      the surface is visible from the viewpoint (:func:`visible_share`: inside the fan of
      one of the view's surfaces, at most ``enlarge_m`` beyond the nearest one; not across
      the gaps between them), ``"in_range"`` those within the view's reach (the farthest
      view point + ``enlarge_m``), ``"half_plane"`` all facing ones. With
      ``current_map="could_see"`` the current map's surfaces take the same test.
    - ``seen_side``: ``"front"`` deletes a surface only when the robot is on the side it
      was seen from (a wall's face cannot be seen from behind it; surfaces keep scan
      order, which puts their seen side on their left); ``"any"`` either side.
    - ``expand``: Expand as ``"split"`` groups (break where consecutive affected map ids
      differ by more than ``group_gap_maps``), one ``"contiguous"`` group min…max, or
      ``"none"`` (only the affected maps).
    - ``current_in_group``: the current map's touched surfaces make it an affected map
      (so a group can reach from it back to older maps).
    - ``forward_ray_m``: a surface crossing the robot's forward ray up to this length also
      touches the view (0: off).
    - ``keep_if_all``: delete nothing when the rule would delete every surface.
    - ``index_cell_m``: cell size of the spatial index (performance only).
    """

    enlarge_m: float = 0.50
    enlarge: EnlargeMode = "forward"
    include_viewpoint: bool = True
    current_map: CurrentMapRule = "could_see"
    facing_test: FacingTest = "both_endpoints"
    could_see: CouldSee = "visible"
    min_visible_share: float = 1.0
    visible_samples: int = 8
    seen_side: SeenSide = "front"
    expand: GroupRule = "split"
    group_gap_maps: int = 20
    current_in_group: bool = True
    forward_ray_m: float = 0.0
    keep_if_all: bool = False
    index_cell_m: float = 2.0

    def __post_init__(self) -> None:
        check_non_negative(self, "enlarge_m", "forward_ray_m")
        check_positive(self, "index_cell_m")
        check_positive_int(self, "group_gap_maps", "visible_samples")
        if not 0.0 <= self.min_visible_share <= 1.0:
            raise InputError(
                f"GlobalMapParams.min_visible_share must be in [0, 1], got "
                f"{self.min_visible_share!r}"
            )
        for name, valid in _CHOICES.items():
            value = getattr(self, name)
            if value not in valid:
                raise InputError(
                    f"GlobalMapParams.{name} must be one of {', '.join(valid)}, got {value!r}"
                )
        for name in ("include_viewpoint", "current_in_group", "keep_if_all"):
            if not isinstance(getattr(self, name), bool):
                raise InputError(
                    f"GlobalMapParams.{name} must be true or false, got {getattr(self, name)!r}"
                )

    @classmethod
    def preset(cls, name: str, **overrides: Any) -> GlobalMapParams:
        """The named consistent set (``visible``, ``paper``, ``v1``, ``original``), with
        overrides."""
        if name not in DELETION_PRESETS:
            raise InputError(
                f"unknown global-map deletion rule {name!r}; valid: {', '.join(DELETION_PRESETS)}"
            )
        return dataclasses.replace(DELETION_PRESETS[name], **overrides)


DELETION_PRESETS: dict[str, GlobalMapParams] = {
    "visible": GlobalMapParams(),
    "paper": GlobalMapParams(could_see="in_view", min_visible_share=0.0, seen_side="any"),
    "v1": GlobalMapParams(
        enlarge="all_round",
        current_map="touch",
        facing_test="midpoint",
        could_see="half_plane",
        min_visible_share=0.0,
        seen_side="any",
        expand="contiguous",
        current_in_group=False,
    ),
    "original": GlobalMapParams(
        enlarge_m=0.30,
        enlarge="radial",
        could_see="half_plane",
        min_visible_share=0.0,
        seen_side="any",
        forward_ray_m=3.0,
        keep_if_all=True,
    ),
}


def _forward_of_ends(segs: FloatArray, robot: Pose) -> FloatArray:
    """``(N, 2)``: each endpoint's coordinate along the robot's heading."""
    c, s = math.cos(robot.theta), math.sin(robot.theta)
    return c * (segs[:, 0::2] - robot.x) + s * (segs[:, 1::2] - robot.y)


def view_polygon(
    segments: FloatArray,
    robot: Pose,
    enlarge_m: float = 0.5,
    enlarge: EnlargeMode = "forward",
    *,
    include_viewpoint: bool = True,
) -> shapely.Geometry:
    """The enlarged polygon P of a view seen from ``robot`` (surfaces in the same frame,
    scan order): the surfaces' endpoints joined in order (through the viewpoint when
    ``include_viewpoint``), enlarged as ``enlarge`` says."""
    segs = as_segments(segments)
    # Speed (one call per update): shapely's vectorised constructors, not its geometry
    # classes, whose Python constructors cost more than GEOS's buffer; same geometry.
    n = 2 * len(segs) + (1 if include_viewpoint else 0)
    pts = np.empty((n, 2))
    if include_viewpoint:
        pts[0, 0] = robot.x
        pts[0, 1] = robot.y
    view_pts = pts[1:] if include_viewpoint else pts
    view_pts[:] = segs.reshape(-1, 2)
    if enlarge == "radial" and len(view_pts):
        off = view_pts - np.array([[robot.x, robot.y]])
        norm = np.hypot(off[:, 0], off[:, 1])
        scale = np.where(norm > 1e-9, enlarge_m / np.maximum(norm, 1e-9), 0.0)
        view_pts += off * scale[:, None]
    if n == 0:
        return shapely.Polygon()
    buffer_m = 0.0 if enlarge == "radial" else enlarge_m
    if n < 3:
        poly = shapely.buffer(shapely.multipoints(pts), max(buffer_m, 1e-6), quad_segs=_QUAD_SEGS)
    else:
        poly = shapely.make_valid(shapely.polygons(pts))
        if buffer_m > 0:
            poly = shapely.buffer(poly, buffer_m, quad_segs=_QUAD_SEGS)
    if enlarge == "forward":
        poly = shapely.intersection(poly, _front_half_plane(pts, robot, buffer_m))
    return poly


_QUAD_SEGS = 16  # shapely's default for ``Geometry.buffer`` (the module function's is 8)


def _front_half_plane(points: FloatArray, robot: Pose, margin_m: float) -> shapely.Geometry:
    """A rectangle covering everything of ``points`` (+ margin) in front of the robot."""
    reach = float(np.max(np.hypot(points[:, 0] - robot.x, points[:, 1] - robot.y)))
    r = reach + margin_m + 1.0
    c, s = math.cos(robot.theta), math.sin(robot.theta)
    x, y = robot.x, robot.y
    # The corners (0, -r), (r, -r), (r, r), (0, r) in the robot frame, in plain floats
    # (the same operations, in the same order, as a rotation of the corner array).
    corners = [(x + c * lx - s * ly, y + s * lx + c * ly)
               for lx, ly in ((0.0, -r), (r, -r), (r, r), (0.0, r))]  # fmt: skip
    return shapely.polygons(corners)


def facing_mask(segments: FloatArray, robot: Pose, test: FacingTest) -> BoolArray:
    """``(N,)``: the surface lies on the robot's facing side (in front of its lateral axis)."""
    segs = as_segments(segments)
    fwd = _forward_of_ends(segs, robot)
    fwd0, fwd1 = fwd[:, 0], fwd[:, 1]
    if test == "midpoint":
        return (fwd0 + fwd1) > 0.0
    if test == "any_endpoint":
        return (fwd0 > 0.0) | (fwd1 > 0.0)
    return (fwd0 > 0.0) & (fwd1 > 0.0)


_FACING_CODES = {"both_endpoints": 0, "midpoint": 1, "any_endpoint": 2}


def facing_seen_mask(
    segments: FloatArray, robot: Pose, test: FacingTest, seen_side: SeenSide
) -> BoolArray:
    """``facing_mask(segments, robot, test)``, and with ``seen_side="front"`` also
    ``seen_side_mask``: one compiled pass when numba imports (the same float operations)."""
    segs = as_segments(segments)
    kernels = _kernels()
    if kernels is None or test not in _FACING_CODES:
        mask = facing_mask(segs, robot, test)
        if seen_side == "front":
            mask &= seen_side_mask(segs, robot)
        return mask
    return kernels.facing_seen_kernel(
        np.ascontiguousarray(segs), float(robot.x), float(robot.y), math.cos(robot.theta),
        math.sin(robot.theta), _FACING_CODES[test], seen_side == "front",
    )  # fmt: skip


def touching_mask(
    polygon: shapely.Geometry, segments: FloatArray, robot: Pose, forward_ray_m: float = 0.0
) -> BoolArray:
    """``(N,)``: the surface is inside or crosses P (or the forward ray, when > 0)."""
    segs = as_segments(segments)
    if len(segs) == 0 or (polygon.is_empty and forward_ray_m <= 0):
        return np.zeros(len(segs), bool)
    lines = shapely.linestrings(segs.reshape(-1, 2, 2))
    if polygon.is_empty:  # nothing inside an empty P; the forward ray still counts
        hit = np.zeros(len(segs), bool)
    else:
        shapely.prepare(polygon)
        hit = shapely.intersects(polygon, lines)
    if forward_ray_m > 0:
        tip = (
            robot.x + forward_ray_m * math.cos(robot.theta),
            robot.y + forward_ray_m * math.sin(robot.theta),
        )
        ray = shapely.LineString([(robot.x, robot.y), tip])
        hit |= shapely.intersects(ray, lines)
    return np.asarray(hit, bool)


# -- the touching test without building P, where it is sure (speed only) ---------------
# Building P with GEOS (polygon, make_valid, buffer, clip) and testing lines against it is
# most of an update. P is the view's polygon Q (simple in nearly every view) buffered by
# r = enlarge_m and cut at the robot's lateral axis. GEOS's buffer lies between Q's true
# r-neighbourhood shrunk by its arc chords and grown by its input simplification (by at
# most r/100); a chord spans at most 1.5 angle quanta (pi/32 at 16 segments a quadrant,
# GEOS rounds the count per arc), so it stays cos(3 pi/128) r = 0.99729 r from Q
# (measured on the default run: 0.99731 r to 1.0092 r). The cut is the axis to rounding.
# So a surface farther than 1.011 r from Q, or wholly behind the axis, misses P, and one
# with a part in front of the axis within 0.997 r of Q meets it (each with a micrometre to
# spare). The compiled kernel (``deletion_numba.classify_touching``) sorts the candidates
# so; only those it is unsure of take GEOS's test, on P built then (most updates never
# build P). Same answers: ``tests/test_deletion_numba.py`` checks the kernel's sure
# answers against GEOS's and whole runs against the GEOS path.
_QUICK_SLACK_M = 1e-6
_QUICK_OUT = 1.011  # x r: beyond this from Q, outside P
_QUICK_IN = 0.997  # x r: within this of Q (in front of the axis), inside P


@functools.cache
def _kernels() -> ModuleType | None:
    """The compiled kernels (``deletion_numba``), imported on first use; None without numba."""
    return compiled_module("albot2d.mapping.albot1.deletion_numba")


def quick_touch_ring(
    segments: FloatArray, robot: Pose, params: GlobalMapParams
) -> FloatArray | None:
    """Q's vertices (the viewpoint, then the view's endpoints) when the quick touching test
    applies: numba present, P enlarged ``"forward"`` through the viewpoint by > 0, no
    forward ray, and Q clearly simple; ``None``: build P and test with GEOS."""
    kernels = _kernels()
    if (kernels is None or params.enlarge != "forward" or not params.include_viewpoint
            or params.forward_ray_m > 0 or not params.enlarge_m > 0):  # fmt: skip
        return None
    ring = kernels.quick_ring(np.ascontiguousarray(as_segments(segments)), float(robot.x),
                      float(robot.y), 1e-6)  # fmt: skip
    return ring if len(ring) else None


def quick_touch_box(ring: FloatArray, enlarge_m: float) -> list[float]:
    """A box holding P (Q's box grown by the farthest P can reach beyond Q)."""
    grow = _QUICK_OUT * enlarge_m + _QUICK_SLACK_M
    lo, hi = ring.min(axis=0), ring.max(axis=0)
    return [lo[0] - grow, lo[1] - grow, hi[0] + grow, hi[1] + grow]


def quick_touching_mask(
    ring: FloatArray,
    polygon: Callable[[], shapely.Geometry],
    segments: FloatArray,
    robot: Pose,
    enlarge_m: float,
) -> BoolArray:
    """``touching_mask(polygon(), segments, robot)``, calling ``polygon`` only for the
    surfaces the ring test is unsure of."""
    kernels = _kernels()
    assert kernels is not None  # quick_touch_ring gave the ring
    segs = np.ascontiguousarray(as_segments(segments))
    status = kernels.classify_touching(
        segs, ring, float(robot.x), float(robot.y), math.cos(robot.theta),
        math.sin(robot.theta), _QUICK_OUT * enlarge_m + _QUICK_SLACK_M,
        _QUICK_IN * enlarge_m - _QUICK_SLACK_M, _QUICK_SLACK_M,
    )  # fmt: skip
    touch = status == 1
    unsure = np.flatnonzero(status == 2)
    if len(unsure):
        touch[unsure] = touching_mask(polygon(), segs[unsure], robot)
    return touch


def in_range_mask(segments: FloatArray, robot: Pose, reach_m: float) -> BoolArray:
    """``(N,)``: both endpoints within ``reach_m`` of the robot."""
    segs = as_segments(segments)
    d0 = np.hypot(segs[:, 0] - robot.x, segs[:, 1] - robot.y)
    d1 = np.hypot(segs[:, 2] - robot.x, segs[:, 3] - robot.y)
    return (d0 <= reach_m) & (d1 <= reach_m)


def group_maps(
    affected: tuple[int, ...],
    rule: GroupRule,
    gap_maps: int,
    existing: set[int] | dict[int, Any] | range,
) -> tuple[int, ...]:
    """Expand: the map ids whose surfaces are candidates for deletion as a group.

    ``affected`` is sorted. ``"split"``: runs of affected ids whose consecutive differences
    are at most ``gap_maps``, each filled in (25, 28 → 25…28); ``"contiguous"``: one run
    from the first to the last; ``"none"``: the affected ids. Only ids in ``existing``
    (a ``range`` when they are consecutive: then each run is a slice of it).
    """
    if not affected:
        return ()
    if rule == "none":
        return tuple(m for m in affected if m in existing)
    if rule == "contiguous":
        runs = [(affected[0], affected[-1])]
    else:
        runs = []
        start = prev = affected[0]
        for m in affected[1:]:
            if m - prev > gap_maps:
                runs.append((start, prev))
                start = m
            prev = m
        runs.append((start, prev))
    if isinstance(existing, range) and existing.step == 1:
        first, last = existing.start, existing.stop - 1
        return tuple([m for lo, hi in runs for m in range(max(lo, first), min(hi, last) + 1)])
    has = existing.__contains__  # filter() runs the test in C: groups span many ids
    return tuple([m for lo, hi in runs for m in filter(has, range(lo, hi + 1))])


def seen_side_mask(segments: FloatArray, robot: Pose) -> BoolArray:
    """``(N,)``: the robot is strictly on the left of each directed surface, the side a
    surface in scan order was seen from."""
    segs = as_segments(segments)
    ex, ey = segs[:, 2] - segs[:, 0], segs[:, 3] - segs[:, 1]
    return ex * (robot.y - segs[:, 1]) - ey * (robot.x - segs[:, 0]) > 0.0


#: ``visible_share(backend=...)``: "auto" takes the compiled kernel when numba imports.
SHARE_BACKENDS = ("auto", "numpy", "numba")


def visible_share(
    segments: FloatArray,
    view: FloatArray,
    robot: Pose,
    beyond_m: float,
    samples: int = 8,
    *,
    backend: str = "auto",
) -> FloatArray:
    """``(N,)``: the share of ``samples`` points spread along each surface (centres of equal
    pieces) that the robot at ``robot`` sees through the incoming ``view`` (surfaces in the
    same frame): the ray from the viewpoint to the point crosses at least one view surface,
    and the point lies at most ``beyond_m`` beyond the nearest crossing (the view's fan,
    enlarged radially; a point in a gap between view surfaces or hidden behind one is not
    visible). ``backend``: "numpy", "numba" or "auto" (numba when it
    imports); both give the same shares bit for bit."""
    if backend not in SHARE_BACKENDS:
        raise ValueError(f"backend must be one of {SHARE_BACKENDS}, got {backend!r}")
    segs = as_segments(segments)
    vsegs = as_segments(view)
    if len(segs) == 0 or len(vsegs) == 0:
        return np.zeros(len(segs))
    if backend != "numpy":
        kernels = _kernels()
        if kernels is not None:
            return kernels.visible_share_kernel(
                np.ascontiguousarray(segs), np.ascontiguousarray(vsegs),
                float(robot.x), float(robot.y), float(beyond_m), int(samples),
            )  # fmt: skip
        if backend == "numba":
            raise ValueError("backend='numba' needs numba (off under ALBOT2D_KERNELS=numpy)")
    frac = (np.arange(samples) + 0.5) / samples
    pts = segs[:, None, :2] + frac[None, :, None] * (segs[:, None, 2:] - segs[:, None, :2])
    v = pts.reshape(-1, 2) - np.array([robot.x, robot.y])  # rays to the points (K, 2)
    length = np.hypot(v[:, 0], v[:, 1])
    e = vsegs[:, 2:] - vsegs[:, :2]  # (M, 2)
    w = vsegs[:, :2] - np.array([robot.x, robot.y])
    den = v[:, :1] * e[None, :, 1] - v[:, 1:] * e[None, :, 0]  # (K, M)
    ok = np.abs(den) > 1e-12
    den = np.where(ok, den, 1.0)
    t = (w[None, :, 0] * e[None, :, 1] - w[None, :, 1] * e[None, :, 0]) / den  # along ray
    u = (w[None, :, 0] * v[:, 1:] - w[None, :, 1] * v[:, :1]) / den  # along view surface
    crosses = ok & (u >= 0.0) & (u <= 1.0) & (t > 0.0)
    nearest = np.where(crosses, t, np.inf).min(axis=1)  # in units of the ray's length
    seen = np.isfinite(nearest) & ((1.0 - nearest) * length <= beyond_m)
    return seen.reshape(len(segs), samples).mean(axis=1)
