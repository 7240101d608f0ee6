"""Mapping benchmarks: the global-map update at 1k vs 100k surfaces, and Albot1 per view.

Run: ``python -m pytest benchmarks/test_mapping.py --benchmark-only --benchmark-group-by=group``.
The two global-map sizes run side by side in one group, each round on a fresh copy of
the map with spatially coherent map ids; with the grid index the update cost should
follow the surfaces near the view, not the size of the map (goal: 100k ≤ 1.5× 1k).
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


@pytest.mark.benchmark(group="global-map update")
@pytest.mark.parametrize("n_surfaces", [1_000, 100_000], ids=["1k", "100k"])
def test_global_map_update(benchmark, n_surfaces: int) -> None:  # type: ignore[no-untyped-def]
    """One update on a fresh copy of the filled map each round (an update deletes what the
    view overlaps, so reusing one map would measure an ever emptier map)."""
    rng = np.random.default_rng(0)
    filled, walk = filled_map(n_surfaces, rng)
    time_updates(benchmark, filled, rng, walk)
    benchmark.extra_info["surfaces"] = len(filled)


def time_updates(benchmark, filled: GlobalMap, rng: np.random.Generator, walk) -> None:  # type: ignore[no-untyped-def]
    """Time one update of 16 views near ``walk``, each on a fresh copy of ``filled``.

    The views come from their own stream (not ``rng``, which filled the map), so maps of
    every size get the same view shapes: a self-crossing view polygon costs GEOS's
    make_valid ~1 ms, which otherwise decided the size ratio more than the size did."""
    del rng  # the views' shapes must not depend on how the map was filled
    view_rng = np.random.default_rng(12)
    views = [a_view(view_rng, walk) for _ in range(16)]
    rounds = iter(range(10**9))

    def setup():  # type: ignore[no-untyped-def]
        segs, pose = views[next(rounds) % len(views)]
        return (copy.deepcopy(filled), segs, pose), {}

    def update(g: GlobalMap, segs: np.ndarray, pose: Pose) -> None:
        g.add_view(segs, g.last_map_id + 1, pose)  # type: ignore[operator]

    benchmark.pedantic(update, setup=setup, rounds=32, iterations=1)


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
