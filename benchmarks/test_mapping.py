"""Mapping benchmarks: the global-map update at 1k vs 100k surfaces, and Albot1 per view.

Run: ``python -m pytest benchmarks/test_mapping.py --benchmark-only --benchmark-group-by=group``.
The two global-map sizes run side by side in one group; with the grid index the update
cost should follow the surfaces near the view, not the size of the map.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from albot2d.geometry import Pose
from albot2d.mapping import Albot1, GlobalMap

SHARED_LOG = Path(__file__).resolve().parents[2] / "shared" / "data" / "raw" / "mit-csail.clf.gz"


def filled_map(n_surfaces: int, rng: np.random.Generator) -> tuple[GlobalMap, float]:
    """A map of ``n_surfaces`` 1 m surfaces at the density of a building (≈ 1 per 4 m²)."""
    side = float(np.sqrt(4.0 * n_surfaces))
    g = GlobalMap()
    per_map = 20
    for mid in range(n_surfaces // per_map):
        start = rng.uniform(0, side, (per_map, 2))
        ang = rng.uniform(-np.pi, np.pi, per_map)
        segs = np.hstack([start, start + np.column_stack([np.cos(ang), np.sin(ang)])])
        g.insert(segs, mid)
    return g, side


def a_view(rng: np.random.Generator, side: float) -> tuple[np.ndarray, Pose]:
    """A corridor-like view: 20 surfaces within 8 m in front of a random pose."""
    pose = Pose(*rng.uniform(10, side - 10, 2), rng.uniform(-np.pi, np.pi))
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
    rng = np.random.default_rng(0)
    g, side = filled_map(n_surfaces, rng)
    views = [a_view(rng, side) for _ in range(64)]
    next_id = [g.last_map_id + 1]  # type: ignore[operator]

    def update() -> None:
        segs, pose = views[next_id[0] % len(views)]
        g.add_view(segs, next_id[0], pose)
        next_id[0] += 1

    benchmark(update)


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
