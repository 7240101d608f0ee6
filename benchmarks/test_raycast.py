"""Speed of the laser's raycasting: ours against a per-beam pymunk ``segment_query_first`` loop.

Worlds are office grids of 4 m rooms with a 1 m door in every inner wall (much more to see
than rooms on a corridor): 12 × 12 rooms ≈ 576 walls and 112 × 112 rooms ≈ 50,000 walls.
The robot stands at random poses inside rooms; each call is one 181-beam, 180° scan out to
30 m (the default) or 80 m (SICK LMS200 long range). Both casters see the same segments
(pymunk: static ``Segment`` shapes of radius 0) and give the same ranges (checked).

Ours runs once per kernel: ``numpy`` (vectorised) and ``numba`` (compiled, the default when
numba imports); each is warmed up (and JIT-compiled)
before timing. Run: ``python -m pytest benchmarks/test_raycast.py --benchmark-only
--benchmark-group-by=group``; compare the groups' min and median times (the mean suffers
most from other processes on a shared machine), and ``extra_info['Mrays_per_s']`` (from
the median).
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import pymunk
import pytest

from albot2d.frames import beam_angles
from albot2d.geometry import Pose
from albot2d.sim.laser import Laser, LaserParams, laser_noise_preset
from albot2d.sim.raycast import BeamFan, RayCaster
from tests.raycast_helpers import BACKENDS, office_segments

ROOM_M = 4.0
N_POSES = 64
SIZES = {"500walls": 12, "50kwalls": 112}
RANGES_M = {"30m": 30.0, "80m": 80.0}


def room_poses(n_rooms: int, seed: int = 0) -> list[tuple[float, float, float]]:
    rng = np.random.default_rng(seed)
    centre = (rng.integers(0, n_rooms, (N_POSES, 2)) + 0.5) * ROOM_M
    xy = centre + rng.uniform(-1.3, 1.3, (N_POSES, 2))
    th = rng.uniform(-math.pi, math.pi, N_POSES)
    return [(float(x), float(y), float(t)) for (x, y), t in zip(xy, th, strict=True)]


def pymunk_space(segments: np.ndarray) -> pymunk.Space:
    space = pymunk.Space()
    shapes = [pymunk.Segment(space.static_body, (a, b), (c, d), 0.0) for a, b, c, d in segments]
    space.add(*shapes)
    return space


def pymunk_scan(
    space: pymunk.Space, pose: tuple[float, float, float], angles: np.ndarray, r_max: float
) -> list[float]:
    x, y, th = pose
    ends = np.column_stack([x + r_max * np.cos(angles + th), y + r_max * np.sin(angles + th)])
    query, everything = space.segment_query_first, pymunk.ShapeFilter()
    out = []
    for end in ends.tolist():
        hit = query((x, y), end, 0.0, everything)
        out.append(hit.alpha * r_max if hit is not None else math.inf)
    return out


@pytest.fixture(scope="module", params=list(SIZES))
def office(request):
    n = SIZES[request.param]
    return request.param, office_segments(n, ROOM_M), room_poses(n)


@pytest.fixture(params=list(RANGES_M))
def world(request, office):
    name, segs, poses = office
    return f"{name}-{request.param}", segs, poses, RANGES_M[request.param]


@pytest.fixture(scope="module")
def space(office) -> pymunk.Space:
    return pymunk_space(office[1])


def rays_per_s(benchmark, n_rays: int) -> None:
    if benchmark.stats is None:  # --benchmark-disable: run once, untimed
        return
    stats = benchmark.stats.stats
    benchmark.extra_info["Mrays_per_s"] = round(n_rays / stats.median / 1e6, 3)
    benchmark.extra_info["Mrays_per_s_mean"] = round(n_rays / stats.mean / 1e6, 3)


def agrees_with_pymunk(caster: RayCaster, space: pymunk.Space, poses, r_max: float) -> None:
    """Same answers (pymunk reports hits as a float fraction of the query length)."""
    angles = beam_angles(181)
    for pose in poses[:8]:
        ours = caster.cast(pose[:2], angles + pose[2], r_max)  # also warms up / compiles
        theirs = np.array(pymunk_scan(space, pose, angles, r_max))
        np.testing.assert_allclose(ours, theirs, atol=1e-6)


@pytest.mark.parametrize("backend", BACKENDS)
def test_ours_181(benchmark, world, space, backend: str) -> None:
    name, segs, poses, r_max = world
    benchmark.group = f"raycast-{name}"
    caster = RayCaster(segs, backend=backend)
    agrees_with_pymunk(caster, space, poses, r_max)
    fan = BeamFan.from_angles(beam_angles(181))
    cycle = itertools.cycle(poses)

    def one_scan():
        x, y, th = next(cycle)
        return caster.cast((x, y), fan, r_max, heading=th)

    ranges = benchmark(one_scan)
    assert ranges.shape == (181,)
    benchmark.extra_info["walls"] = len(segs)
    benchmark.extra_info["backend"] = caster.backend
    rays_per_s(benchmark, 181)


def test_pymunk_181(benchmark, world, space) -> None:
    name, segs, poses, r_max = world
    benchmark.group = f"raycast-{name}"
    angles = beam_angles(181)
    for backend in ("numpy", "auto"):
        agrees_with_pymunk(RayCaster(segs, backend=backend), space, poses, r_max)
    cycle = itertools.cycle(poses)
    benchmark(lambda: pymunk_scan(space, next(cycle), angles, r_max))
    benchmark.extra_info["walls"] = len(segs)
    rays_per_s(benchmark, 181)


def test_ours_361(benchmark, world) -> None:
    name, segs, poses, r_max = world
    benchmark.group = f"raycast-{name}"
    caster = RayCaster(segs)
    fan = BeamFan.from_angles(beam_angles(361))
    caster.cast(poses[0][:2], fan, r_max)  # warm up (JIT)
    cycle = itertools.cycle(poses)

    def one_scan():
        x, y, th = next(cycle)
        return caster.cast((x, y), fan, r_max, heading=th)

    benchmark(one_scan)
    benchmark.extra_info["backend"] = caster.backend
    rays_per_s(benchmark, 361)


@pytest.mark.parametrize("noise", ["sick_lms200", "sick_lms200_any_jump", "zero"])
def test_laser_scan_sick_noise(benchmark, world, noise: str) -> None:
    """A whole ``Laser.scan`` with SICK-like noise (mixed pixels, noise, quantisation...),
    beside the former mixed-pixel model (no occluding-edge test) and an exact laser: the
    edge test's cost is the first two's difference."""
    name, segs, poses, r_max = world
    benchmark.group = f"raycast-{name}"
    laser = Laser(segs, LaserParams(max_range_m=r_max), laser_noise_preset(noise))
    rng = np.random.default_rng(0)
    cycle = itertools.cycle([Pose(*p) for p in poses])
    laser.scan(next(cycle), rng)  # warm up (JIT)
    benchmark(lambda: laser.scan(next(cycle), rng))
    benchmark.extra_info["backend"] = laser.caster.backend
    rays_per_s(benchmark, 181)


def test_index_build(benchmark, office) -> None:
    _, segs, _ = office
    benchmark.group = "raycast-index-build"
    benchmark.extra_info["walls"] = len(segs)
    benchmark.pedantic(RayCaster, args=(segs,), rounds=3, iterations=1)
