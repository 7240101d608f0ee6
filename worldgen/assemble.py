"""Assemble a ``World`` from a free-space polygon and clutter: walls, bounds, roadmap, start.

Generators and the HouseExpo importer both end here, so this accepts arbitrary polygons:
it repairs invalid input, keeps the largest connected part, clips clutter to free space,
derives the wall segments (every boundary ring of the structural free space; clutter
outlines are kept separately so ``world.obstacle_segments`` = walls + clutter outlines),
builds the roadmap and picks a start pose on it.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from typing import Any

import numpy as np
import shapely
from numpy.typing import NDArray

from albot2d.errors import InputError
from albot2d.geometry import Pose, polygon_ring_segments
from worldgen.roadmap import RoadmapParams, build_roadmap, count_loops
from worldgen.roadmap_links import ClearanceChecker, roadmap_from_links
from worldgen.world import DynamicObstacle, Roadmap, World

__all__ = ["largest_polygon", "make_world", "polygon_walls"]

_MIN_PART_AREA_M2 = 1e-6  # slivers left by clipping clutter are not obstacles


def _polygons(geom: shapely.Geometry) -> list[shapely.Polygon]:
    if geom.is_empty:
        return []
    parts = shapely.get_parts(geom if geom.is_valid else shapely.make_valid(geom))
    out: list[shapely.Polygon] = []
    for part in parts:
        if isinstance(part, shapely.Polygon):
            if part.area > _MIN_PART_AREA_M2:
                out.append(part)
        elif isinstance(part, shapely.MultiPolygon | shapely.GeometryCollection):
            out.extend(_polygons(part))
    return out


def largest_polygon(geom: shapely.Geometry, *, what: str = "free space") -> shapely.Polygon:
    """The largest-area polygon of ``geom`` (repaired if invalid); InputError if none."""
    return _largest(_polygons(geom), what)


def _largest(polys: list[shapely.Polygon], what: str) -> shapely.Polygon:
    if not polys:
        raise InputError(f"{what}: no polygon with positive area")
    return polys[int(np.argmax(shapely.area(np.asarray(polys, dtype=object))))]


def polygon_walls(poly: shapely.Polygon) -> NDArray[np.float64]:
    """All boundary rings of ``poly`` as one ``(N, 4)`` segment array (zero-length dropped)."""
    rings = [poly.exterior, *poly.interiors]
    segs = np.vstack([polygon_ring_segments(np.asarray(r.coords)) for r in rings])
    length = np.hypot(segs[:, 2] - segs[:, 0], segs[:, 3] - segs[:, 1])
    return segs[length > 0.0]


def _clip_clutter(
    clutter: Iterable[shapely.Geometry], structure: shapely.Polygon
) -> tuple[shapely.Polygon, ...]:
    """Clutter clipped to the structural free space; items already inside are kept as is."""
    items = np.asarray(list(clutter), dtype=object)
    if len(items) == 0:
        return ()
    shapely.prepare(structure)
    inside = shapely.covers(structure, items) & shapely.is_valid(items)
    inside &= shapely.get_type_id(items) == shapely.GeometryType.POLYGON
    out: list[shapely.Polygon] = []
    clipped = iter(shapely.intersection(items[~inside], structure))
    for item, ok in zip(items, inside, strict=True):
        if ok:
            out.append(item)
        else:
            out.extend(_polygons(next(clipped)))
    return tuple(shapely.normalize(np.asarray(out, dtype=object))) if out else ()


_START_LINKS = 3  # a given start is linked to this many nearest roadmap nodes


def _check_start(start: Pose, checker: ClearanceChecker, clearance_m: float) -> None:
    if not (np.isfinite(start.x) and np.isfinite(start.y) and np.isfinite(start.theta)):
        raise InputError(f"start pose must be finite, got {start}")
    if not checker.points_ok([[start.x, start.y]], clearance_m)[0]:
        raise InputError(
            f"start pose ({start.x:.3f}, {start.y:.3f}) is not in free space with "
            f"clearance {clearance_m:.2f} m"
        )


def _attach_start(
    roadmap: Roadmap, start: Pose, checker: ClearanceChecker, radius_m: float
) -> Roadmap:
    """The roadmap with the start as a node linked to its nearest safely reachable nodes."""
    xy = np.array([start.x, start.y])
    nodes, edges = roadmap.nodes, roadmap.edges
    hit = np.flatnonzero((nodes == xy).all(axis=1))
    if len(hit):
        return roadmap
    d = np.hypot(*(nodes - xy).T)
    near = np.argsort(d, kind="stable")[:_START_LINKS]
    ok = checker.segments_ok(np.column_stack([np.tile(xy, (len(near), 1)), nodes[near]]), radius_m)
    if not ok.any():
        raise InputError(
            f"start pose ({start.x:.3f}, {start.y:.3f}) cannot be linked to the roadmap"
        )
    new = np.column_stack([near[ok], np.full(int(ok.sum()), len(nodes))])
    return Roadmap(np.vstack([nodes, xy]), np.vstack([edges, new]).astype(np.int64))


def _pick_start(roadmap: Roadmap, rng: np.random.Generator | None) -> Pose:
    """A roadmap node, heading along one of its edges (deterministic without an rng)."""
    nodes, edges = roadmap.nodes, roadmap.edges
    if len(edges) == 0:
        x, y = nodes[0]
        return Pose(float(x), float(y), 0.0)
    if rng is None:
        i, j = int(edges[0, 0]), int(edges[0, 1])
    else:
        i, j = (int(v) for v in edges[int(rng.integers(len(edges)))])
        if rng.random() < 0.5:
            i, j = j, i
    dx, dy = nodes[j] - nodes[i]
    return Pose(float(nodes[i, 0]), float(nodes[i, 1]), float(np.arctan2(dy, dx)))


def make_world(
    free_space: shapely.Polygon | shapely.MultiPolygon,
    *,
    clutter: Iterable[shapely.Geometry] = (),
    kind: str = "custom",
    seed: int | None = None,
    params: Mapping[str, Any] | None = None,
    features: Mapping[str, Any] | None = None,
    robot_radius_m: float = 0.25,
    clearance_margin_m: float = 0.10,
    start: Pose | None = None,
    rng: np.random.Generator | None = None,
    dynamic_obstacles: Iterable[DynamicObstacle] = (),
    seed_points: NDArray[np.float64] | None = None,
    keep_largest: bool = True,
    roadmap_params: RoadmapParams | None = None,
    links: NDArray[np.float64] | None = None,
    bounds: tuple[float, float, float, float] | None = None,
) -> World:
    """Build a World from the structural free space (walls as its boundary) and clutter.

    ``free_space`` is where the floor is, before clutter; clutter polygons are clipped to it
    and subtracted. With ``keep_largest`` (default) only the largest connected part of the
    result is kept; otherwise a disconnected free space is an InputError. ``start``, when
    given, must have clearance ``robot_radius_m + clearance_margin_m`` and is linked into
    the roadmap; otherwise a start is drawn on the roadmap (deterministically without
    ``rng``). ``links`` (``(M, 4)`` planned straight roadmap edges, as generators know
    their corridors and doors) replaces the generic medial-axis roadmap; unsafe links are
    dropped either way. ``features`` gets ``loops`` (independent roadmap cycles) added. ``bounds``
    defaults to the bounding box of the free space (pass it to include outer walls).
    """
    if not (np.isfinite(robot_radius_m) and robot_radius_m > 0):
        raise InputError(f"robot_radius_m must be > 0, got {robot_radius_m!r}")
    if not (np.isfinite(clearance_margin_m) and clearance_margin_m >= 0):
        raise InputError(f"clearance_margin_m must be >= 0, got {clearance_margin_m!r}")
    polys = _polygons(free_space)
    if not polys:
        raise InputError("free space: no polygon with positive area")
    if len(polys) > 1 and not keep_largest:
        raise InputError(f"free space has {len(polys)} disconnected parts, expected one")
    structure = _largest(polys, "free space")
    structure = shapely.normalize(structure)

    items = _clip_clutter(clutter, structure)
    open_floor = structure
    if items:
        open_floor = shapely.difference(structure, shapely.union_all(np.asarray(items, object)))
        open_parts = _polygons(open_floor)
        if len(open_parts) > 1 and not keep_largest:
            raise InputError(
                f"clutter splits free space into {len(open_parts)} parts, expected one"
            )
        open_floor = shapely.normalize(_largest(open_parts, "free space"))

    clearance_m = robot_radius_m + clearance_margin_m
    checker = ClearanceChecker(open_floor)
    if start is not None:
        _check_start(start, checker, clearance_m)
    if links is not None:
        roadmap = roadmap_from_links(
            open_floor,
            links,
            clearance_m=clearance_m,
            robot_radius_m=robot_radius_m,
            checker=checker,
        )
    else:
        roadmap = build_roadmap(
            open_floor,
            clearance_m=clearance_m,
            robot_radius_m=robot_radius_m,
            seed_points=seed_points,
            params=roadmap_params,
        )
    if len(roadmap.nodes) == 0:
        raise InputError(
            f"free space has no place with clearance {clearance_m:.2f} m for the robot "
            f"(robot_radius_m={robot_radius_m}, clearance_margin_m={clearance_margin_m})"
        )
    if start is not None:
        roadmap = _attach_start(roadmap, start, checker, robot_radius_m)
    else:
        start = _pick_start(roadmap, rng)

    walls = polygon_walls(structure)
    minx, miny, maxx, maxy = structure.bounds if bounds is None else bounds
    feats = dict(features or {})
    feats.setdefault("loops", count_loops(roadmap))
    return World(
        walls=walls,
        clutter=items,
        free_space=open_floor,
        bounds=(minx, miny, maxx, maxy),
        start=start,
        roadmap=roadmap,
        kind=kind,
        seed=seed,
        params=dict(params or {}),
        dynamic_obstacles=tuple(dynamic_obstacles),
        features=feats,
        robot_radius_m=robot_radius_m,
    )
