"""Mapping benchmarks: the global-map update at 1k vs 100k surfaces, and Albot1 per view.

Run: ``python -m pytest benchmarks/test_mapping.py --benchmark-only --benchmark-group-by=group``.
The two global-map sizes run side by side in one group, each round on a fresh copy of
the map with spatially coherent map ids. The views are laser views of the map (as Albot1
adds them) and the 1k map is the 100k map's surfaces around them, so both sizes do the
same update; with the grid index its cost should follow the surfaces near the view, not
the size of the map (goal: 100k ≤ 1.5× 1k).
"""

from __future__ import annotations

import copy
from pathlib import Path

import numpy as np
import pytest

from albot2d.geometry import Pose
from albot2d.mapping import Albot1, GlobalMap

SHARED_LOG = Path(__file__).resolve().parents[2] / "shared" / "data" / "raw" / "mit-csail.clf.gz"


def filled_map(n_surfaces: int, rng: np.random.Generator) -> tuple[GlobalMap, np.ndarray]:
    """A map of ``n_surfaces`` 1 m surfaces at the density of a building (≈ 1 per 4 m²),
    remembered along a route: map ``k``'s 20 surfaces lie around the ``k``-th point of a
    lawnmower walk over the square, so neighbouring ids are neighbouring places, as a
    robot's local maps are. Returns the map and the walk (one point per map id)."""
    side = float(np.sqrt(4.0 * n_surfaces))
    per_map = 20
    n_maps = n_surfaces // per_map
    rows = max(int(side // 8.0), 1)
    t = np.linspace(0.0, rows, n_maps, endpoint=False)
    row, along = np.floor(t), (t % 1.0) * side
    walk = np.column_stack([np.where(row % 2 == 0, along, side - along),
                            (row + 0.5) * side / rows])  # fmt: skip
    g = GlobalMap()
    for mid in range(n_maps):
        start = walk[mid] + rng.uniform(-6.0, 6.0, (per_map, 2))
        ang = rng.uniform(-np.pi, np.pi, per_map)
        segs = np.hstack([start, start + np.column_stack([np.cos(ang), np.sin(ang)])])
        g.insert(segs, mid)
    return g, walk


def a_view(rng: np.random.Generator, walk: np.ndarray) -> tuple[np.ndarray, Pose]:
    """A corridor-like view: 20 surfaces within 8 m in front of a pose on the walk's last
    stretch (the robot adds its views where it is now)."""
    here = walk[-rng.integers(1, max(len(walk) // 20, 2))]
    pose = Pose(*(here + rng.uniform(-2.0, 2.0, 2)), rng.uniform(-np.pi, np.pi))
    bearings = np.sort(rng.uniform(-1.5, 1.5, 20))
    r = rng.uniform(1.0, 8.0, 20)
    pts = np.column_stack([r * np.cos(bearings), r * np.sin(bearings)])
    segs = np.hstack([pts, pts + 0.5 * np.column_stack([-np.sin(bearings), np.cos(bearings)])])
    c, s = np.cos(pose.theta), np.sin(pose.theta)
    rot = np.array([[c, -s], [s, c]])
    world = np.hstack(
        [segs[:, :2] @ rot.T + [pose.x, pose.y], segs[:, 2:] @ rot.T + [pose.x, pose.y]]
    )
    return world, pose


def local_part(filled: GlobalMap, walk: np.ndarray, centre: int, n_surfaces: int) -> GlobalMap:
    """The ``n_surfaces`` of ``filled`` around the ``centre``-th point of its walk: whole maps,
    nearest first, plus the last map (so both maps have the same current map), re-inserted
    with their ids. Around the centre the two maps are the same surfaces."""
    snap = filled.snapshot()
    last = int(snap.map_ids.max())
    order = np.argsort(np.hypot(*(walk - walk[centre]).T), kind="stable")
    per_map = np.bincount(snap.map_ids, minlength=len(walk))
    chosen = {last}
    total = int(per_map[last])
    for m in order.tolist():
        if total >= n_surfaces:
            break
        if m not in chosen:
            chosen.add(m)
            total += int(per_map[m])
    g = GlobalMap(filled.params)
    for m in sorted(chosen):
        g.insert(snap.segments[snap.map_ids == m], m)
    return g


def laser_views(
    g: GlobalMap, at: np.ndarray, n: int, seed: int = 12
) -> list[tuple[np.ndarray, Pose]]:
    """``n`` views as Albot1 adds them along its route: a 181-beam noisy scan of the map's own
    surfaces from each pose of a walk from ``at`` (steps of at most 1 m, each pose ≥ 0.3 m
    from every surface, a random heading), its surfaces extracted with Albot1's parameters
    and put in the global frame. Real views are star-shaped around the robot (never
    self-crossing) and see what the map holds there."""
    from albot2d.geometry import point_segment_distance, transform_segments
    from albot2d.perception import ExtractionParams, extract_surfaces
    from albot2d.seeding import make_rng
    from albot2d.sim.laser import Laser

    segs = g.snapshot().segments
    near = segs[np.hypot(segs[:, 0] - at[0], segs[:, 1] - at[1]) < 40.0]
    laser, rng = Laser(near), make_rng(seed)
    views: list[tuple[np.ndarray, Pose]] = []
    here = np.asarray(at, float)
    while len(views) < n:
        xy = here + rng.uniform(-1.0, 1.0, 2)
        if np.hypot(*(xy - at)) > 4.0 or point_segment_distance(xy[None, :], near).min() < 0.3:
            continue
        pose = Pose(float(xy[0]), float(xy[1]), float(rng.uniform(-np.pi, np.pi)))
        view = extract_surfaces(laser.scan(pose, rng), ExtractionParams())
        if len(view):
            views.append((transform_segments(pose.as_array(), view.segments), pose))
            here = xy
    return views


def maps_and_views(
    sizes: tuple[int, ...], n_views: int = 16
) -> tuple[dict[int, GlobalMap], list[tuple[np.ndarray, Pose]]]:
    """Maps of each size that hold the same surfaces within 30 m of the views (the biggest
    map, and the local parts of it; see ``local_part``), and the views."""
    big, walk = filled_map(max(sizes), np.random.default_rng(0))
    per_row = len(walk) // max(int(np.sqrt(4.0 * max(sizes)) // 8.0), 1)
    centre = len(walk) - 1 - 3 * per_row // 2  # mid second-last row: full density around
    maps = {n: big if n == max(sizes) else local_part(big, walk, centre, n) for n in sizes}
    return maps, laser_views(big, walk[centre], n_views)


@pytest.fixture(scope="module")
def size_maps() -> tuple[dict[int, GlobalMap], list[tuple[np.ndarray, Pose]]]:
    return maps_and_views((1_000, 100_000))


@pytest.mark.benchmark(group="global-map update")
@pytest.mark.parametrize("n_surfaces", [1_000, 100_000], ids=["1k", "100k"])
def test_global_map_update(benchmark, n_surfaces: int, size_maps) -> None:  # type: ignore[no-untyped-def]
    """16 updates along a route, on a fresh copy of the filled map each round (an update
    deletes what the view overlaps, so reusing one map would measure an ever emptier map).
    The views are laser views of the map itself and both sizes hold the same surfaces
    around them, so the updates do the same work (checked) and the ratio is the cost of
    the size alone. The time is per round: divide by 16 for one update."""
    maps, views = size_maps
    filled = maps[n_surfaces]
    reports = time_updates(benchmark, filled, views)
    benchmark.extra_info["surfaces"] = len(filled)
    benchmark.extra_info["updates_per_round"] = len(views)
    other = maps[1_000 if n_surfaces != 1_000 else 100_000]
    want = run_updates(copy.deepcopy(other), views)
    assert [(r.deleted_current, r.deleted_older, r.affected_maps) for r in reports] == [
        (r.deleted_current, r.deleted_older, r.affected_maps) for r in want
    ]
    assert sum(r.deleted_current + r.deleted_older for r in reports) > 0  # views meet the map


def run_updates(g: GlobalMap, views) -> list:  # type: ignore[no-untyped-def]
    """Add ``views`` in turn to ``g`` as maps after its last one; returns their reports."""
    return [g.add_view(segs, g.last_map_id + 1, pose) for segs, pose in views]  # type: ignore[operator]


def time_updates(benchmark, filled: GlobalMap, views) -> list:  # type: ignore[no-untyped-def]
    """Time the updates of ``views`` in turn (a route), each round on a fresh copy of
    ``filled``, after one untimed round (compiled kernels loaded, whose reports it returns).
    In a run the map around the robot was touched by the update before, as here."""
    reports = run_updates(copy.deepcopy(filled), views)

    def setup():  # type: ignore[no-untyped-def]
        return (copy.deepcopy(filled), views), {}

    benchmark.pedantic(run_updates, setup=setup, rounds=30, iterations=1)
    return reports


@pytest.mark.benchmark(group="albot1 per view")
def test_albot1_per_view_on_mit_log(benchmark) -> None:  # type: ignore[no-untyped-def]
    if not SHARED_LOG.exists():
        pytest.skip(f"shared MIT CSAIL log not found at {SHARED_LOG}")
    from albot2d.logs import read_frames

    frames = list(read_frames(SHARED_LOG))[:400]

    def run() -> Albot1:
        m = Albot1()
        for f in frames:
            m.observe(f)
        return m

    m = benchmark.pedantic(run, rounds=3, iterations=1)
    per_view = m.timings_ms()
    benchmark.extra_info.update({f"{k}_ms_per_view": round(v, 4) for k, v in per_view.items()})
    benchmark.extra_info["views"] = len(frames)
