"""Independent oracles beside the twin comparisons: boundary cases worked out by hand
(line extraction at exactly ``min_points`` beams, breakpoint gaps at the threshold,
Expand's group gap at ``group_gap_maps``), RPE against evo's RPE with relations across
±π, and triangulation against the true pose in the geometry that matters (headings
across ±π, ends seen swapped, one usable corner, an outlier), on every backend.

Each scan here is cast by hand (a ray–segment formula, not the simulator's ray caster).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import albot2d.mapping.albot1.triangulation as tri
from albot2d.evaluation.metrics.rpe import relation_errors, relative_pose_error
from albot2d.frames import Scan
from albot2d.geometry import Pose, between_arrays
from albot2d.mapping.albot1.deletion import group_maps
from albot2d.mapping.albot1.triangulation import triangulate
from albot2d.perception.extraction import ExtractionParams, extract_surfaces, numba_available
from albot2d.perception.surfaces import Surfaces

BACKENDS = ["numpy", pytest.param("numba", marks=pytest.mark.skipif(
    not numba_available(), reason="numba not installed"))]  # fmt: skip
ANGLES = np.radians(np.linspace(-90.0, 90.0, 361))  # 0.5° apart; beam 180 straight ahead


def cast(walls: list[tuple[float, float, float, float]]) -> np.ndarray:
    """Exact ranges of every beam of ``ANGLES`` from the origin to the nearest wall."""
    c, s = np.cos(ANGLES), np.sin(ANGLES)
    r = np.full(len(ANGLES), np.inf)
    for x0, y0, x1, y1 in walls:
        dx, dy = x1 - x0, y1 - y0
        den = c * dy - s * dx
        with np.errstate(divide="ignore", invalid="ignore"):
            t = (x0 * dy - y0 * dx) / den
            u = (x0 * s - y0 * c) / den
        hit = (np.abs(den) > 1e-12) & (t > 0) & (u >= 0) & (u <= 1) & (t < r)
        r = np.where(hit, t, r)
    return r


def scan_of(ranges: np.ndarray, valid: np.ndarray) -> Scan:
    valid = valid & np.isfinite(ranges)
    return Scan(np.where(valid, ranges, 0.0), ANGLES, valid, 10.0)


def beams(first: int, count: int) -> np.ndarray:
    valid = np.zeros(len(ANGLES), bool)
    valid[first : first + count] = True
    return valid


# -- line extraction: min_points ------------------------------------------------------------
@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("min_points", [3, 5, 8])
def test_a_wall_seen_by_exactly_min_points_beams_is_a_surface(
    backend: str, min_points: int
) -> None:
    """A wall 3 m ahead lit by exactly ``min_points`` beams is one surface spanning them;
    by one beam fewer, none."""
    params = ExtractionParams(min_points=min_points)
    wall = cast([(3.0, -5.0, 3.0, 5.0)])
    got = extract_surfaces(scan_of(wall, beams(180, min_points)), params, backend=backend)
    assert got.beams.tolist() == [[180, 180 + min_points - 1]]
    np.testing.assert_allclose(got.segments[0, [0, 2]], 3.0, atol=1e-9)
    fewer = extract_surfaces(scan_of(wall, beams(180, min_points - 1)), params, backend=backend)
    assert len(fewer) == 0


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_corner_leg_of_exactly_min_points_beams_survives_the_split(backend: str) -> None:
    """An L: a long wall x = 3 (beams 150–180) turning at (3, 0) towards (1.5, 0.5). The
    split point (the corner beam, 180) belongs to both halves, so the short leg of beams
    180…184 has exactly 5 = min_points beams and is kept, with a real corner; 180…183 is
    dropped (and the long wall keeps the corner)."""
    walls = cast([(3.0, -5.0, 3.0, 0.0), (3.0, 0.0, 1.5, 0.5)])
    five = extract_surfaces(scan_of(walls, beams(150, 35)), backend=backend)
    assert five.beams.tolist() == [[150, 180], [180, 184]]
    assert five.occluded.tolist() == [[True, False], [False, True]]
    np.testing.assert_allclose(five.segments[1, :2], [3.0, 0.0], atol=1e-6)
    four = extract_surfaces(scan_of(walls, beams(150, 34)), backend=backend)
    assert four.beams.tolist() == [[150, 180]]


# -- line extraction: breakpoints at the threshold -----------------------------------------
def _step_ranges(depth_m: float) -> np.ndarray:
    """Beams 170–179 on the wall x = 3, beams 180–189 on a parallel wall ``depth_m`` behind."""
    near = cast([(3.0, -5.0, 3.0, -1e-9)])
    far = cast([(3.0 + depth_m, 0.0, 3.0 + depth_m, 5.0)])
    return np.where(np.arange(len(ANGLES)) < 180, near, far)


def _gap_and_threshold(depth_m: float, params: ExtractionParams) -> tuple[float, float]:
    """By hand: the distance between the points of beams 179 and 180, and Borges & Aldon's
    D_max = r sin Δφ / sin(λ − Δφ) + k σ_r with r the nearer range."""
    r = _step_ranges(depth_m)
    x, y = r * np.cos(ANGLES), r * np.sin(ANGLES)
    gap = math.hypot(x[180] - x[179], y[180] - y[179])
    dphi = abs(float(ANGLES[180] - ANGLES[179]))
    lam = math.radians(params.breakpoint_lambda_deg)
    d_max = min(r[179], r[180]) * math.sin(dphi) / math.sin(lam - dphi)
    return gap, d_max + params.breakpoint_sigma_factor * params.range_sigma_m


def _depth_for_gap(share: float, params: ExtractionParams) -> float:
    """The step depth whose gap is ``share`` × the threshold (bisection: the gap grows
    with the depth, the threshold does not change)."""
    lo, hi = 0.0, 1.0
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        gap, d_max = _gap_and_threshold(mid, params)
        lo, hi = (mid, hi) if gap < share * d_max else (lo, mid)
    return 0.5 * (lo + hi)


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize(
    "params", [ExtractionParams(), ExtractionParams(breakpoint_lambda_deg=20.0, range_sigma_m=0.03)]
)
def test_a_gap_just_within_the_threshold_joins_and_just_beyond_breaks(
    backend: str, params: ExtractionParams
) -> None:
    """Two parallel walls one step apart in depth, the step's gap a millionth below the
    adaptive threshold: one run (split at the step, so the far wall's first end is a real
    end); a millionth above: two runs, and the far wall's end next to the nearer beam is
    occluded."""
    for share, joined in ((1.0 - 1e-6, True), (1.0 + 1e-6, False)):
        depth = _depth_for_gap(share, params)
        gap, d_max = _gap_and_threshold(depth, params)
        assert gap / d_max == pytest.approx(share, abs=1e-9)
        got = extract_surfaces(scan_of(_step_ranges(depth), beams(170, 20)), params,
                               backend=backend)  # fmt: skip
        assert len(got) == 2, share
        assert got.occluded[1, 0] == (not joined), share


def test_expand_splits_groups_exactly_past_the_gap() -> None:
    """Expand fills 5…25 when the ids differ by exactly ``group_gap_maps`` (20) and keeps
    5 and 26 apart when they differ by 21."""
    ids = range(40)
    assert group_maps((5, 25), "split", 20, ids) == tuple(range(5, 26))
    assert group_maps((5, 26), "split", 20, ids) == (5, 26)
    assert group_maps((5, 26), "split", 21, ids) == tuple(range(5, 27))


# -- RPE against evo ------------------------------------------------------------------------
def _spinning(n: int, seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A robot turning 25° a step (its heading crosses ±π every ~7 steps) and an estimate
    off by noise of a few degrees and centimetres."""
    rng = np.random.default_rng(seed)
    t = np.arange(n, dtype=np.float64)
    heading = np.radians(170.0) + np.radians(25.0) * t
    truth = np.column_stack([np.cos(t / 5.0), np.sin(t / 3.0), np.angle(np.exp(1j * heading))])
    est = truth + np.column_stack([rng.normal(0, 0.03, n), rng.normal(0, 0.03, n),
                                   rng.normal(0, math.radians(3.0), n)])  # fmt: skip
    est[:, 2] = np.angle(np.exp(1j * est[:, 2]))
    return t, truth, est


def _evo_rpe(t: np.ndarray, truth: np.ndarray, est: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """evo's own RPE between consecutive poses (SE(3), yaw only), per relation."""
    from evo.core import metrics
    from evo.core.trajectory import PoseTrajectory3D

    def traj(p: np.ndarray) -> PoseTrajectory3D:
        quat = np.column_stack([np.cos(p[:, 2] / 2), np.zeros(len(p)), np.zeros(len(p)),
                                np.sin(p[:, 2] / 2)])  # fmt: skip
        return PoseTrajectory3D(np.column_stack([p[:, :2], np.zeros(len(p))]), quat, t)

    out = []
    for relation in (
        metrics.PoseRelation.translation_part,
        metrics.PoseRelation.rotation_angle_rad,
    ):
        rpe = metrics.RPE(relation, delta=1, delta_unit=metrics.Unit.frames, all_pairs=False)
        rpe.process_data((traj(truth), traj(est)))
        out.append(np.asarray(rpe.error))
    return out[0], out[1]


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_rpe_equals_evos_rpe_with_headings_across_pi(seed: int) -> None:
    pytest.importorskip("evo", reason="evo is the [eval] extra (also in the test extra)")
    t, truth, est = _spinning(60, seed)
    rel = between_arrays(truth[:-1], truth[1:])
    across = np.abs(truth[1:, 2] - truth[:-1, 2]) > math.pi  # the raw headings jump by ~2π
    assert across.sum() >= 5
    trans, rot, used = relation_errors(t, est, t[:-1], t[1:], rel)
    evo_trans, evo_rot = _evo_rpe(t, truth, est)
    assert used.all()
    np.testing.assert_allclose(trans, evo_trans, atol=1e-9)
    np.testing.assert_allclose(rot, evo_rot, atol=1e-9)
    assert rot.max() < math.radians(20.0)  # a few degrees of noise, never ~360°
    r = relative_pose_error(t, est, t[:-1], t[1:], rel)
    assert r.overall.rot_deg_mean == pytest.approx(math.degrees(evo_rot.mean()), abs=1e-7)


def test_rpe_of_an_exact_estimate_across_pi_is_zero() -> None:
    """Headings 179° then −179° (2° of turn) estimated exactly as 179° and 181°: no error."""
    t = np.array([0.0, 1.0])
    truth = np.array([[0.0, 0.0, math.radians(179.0)], [1.0, 0.0, math.radians(-179.0)]])
    est = truth.copy()
    est[1, 2] = math.radians(181.0)
    rel = between_arrays(truth[:1], truth[1:])
    trans, rot, _ = relation_errors(t, est, t[:1], t[1:], rel)
    assert trans[0] == pytest.approx(0.0, abs=1e-12) and rot[0] == pytest.approx(0.0, abs=1e-12)


# -- triangulation against the true pose -----------------------------------------------------
def _observed(walls: np.ndarray, pose: Pose) -> np.ndarray:
    inv = pose.inverse()
    return np.hstack([inv.transform_points(walls[:, :2]), inv.transform_points(walls[:, 2:])])


def _both_paths(local: Surfaces, current: Surfaces, pi: Pose) -> list[Pose | None]:
    """The small (compiled) path and the array path."""
    fast = triangulate(local, current, pi, steps=3)
    small, tri._SMALL = tri._SMALL, 0
    try:
        slow = triangulate(local, current, pi, steps=3)
    finally:
        tri._SMALL = small
    return [fast, slow]


ROOM = np.array([[4.0, -3.0, 4.0, 3.0], [4.0, 3.0, -1.0, 3.0], [-1.0, -3.0, 4.0, -3.0],
                 [2.0, 1.0, 2.5, 0.2]])  # fmt: skip


@pytest.mark.parametrize(
    ("case", "true", "pi_off"),
    [
        ("heading across pi", Pose(0.3, -0.2, math.radians(179.5)), (0.05, -0.04, 1.5)),
        ("heading across -pi", Pose(-0.2, 0.1, math.radians(-179.2)), (-0.05, 0.05, -1.8)),
        ("ordinary", Pose(0.4, 0.3, math.radians(12.0)), (0.1, 0.1, 2.0)),
    ],
)
def test_exact_views_triangulate_to_the_true_pose_on_both_paths(
    case: str, true: Pose, pi_off: tuple[float, float, float]
) -> None:
    """The room seen from the origin and from ``true``, ends swapped on two surfaces of the
    later view (the π ambiguity of a direction), and only one real corner usable in both
    views: both paths find the true pose from path integration a little off."""
    walls = ROOM
    seen = _observed(walls, true)
    seen[[0, 3]] = seen[[0, 3]][:, [2, 3, 0, 1]]
    occluded = np.ones((len(walls), 2), bool)
    occluded[3] = False  # the free-standing surface: both its ends are real corners
    local = Surfaces.from_segments(walls, occluded)
    current = Surfaces.from_segments(seen, occluded)
    pi = Pose(true.x + pi_off[0], true.y + pi_off[1], true.theta + math.radians(pi_off[2]))
    for got in _both_paths(local, current, pi):
        assert got is not None, case
        assert math.hypot(got.x - true.x, got.y - true.y) < 1e-9, case
        assert abs(math.remainder(got.theta - true.theta, 2 * math.pi)) < 1e-9, case


def test_a_mistracked_surface_is_outvoted_on_both_paths() -> None:
    """Five tracked surfaces, one of them wrongly associated (its observation moved
    0.3 m): heuristic 1 drops it and the pose is the true one on both paths."""
    walls = np.array([[4.0, -3.0, 4.0, 3.0], [4.0, 3.0, -1.0, 3.0], [-1.0, -3.0, 4.0, -3.0],
                      [2.0, 1.0, 2.5, 0.2], [1.0, -2.0, 1.8, -1.5]])  # fmt: skip
    true = Pose(0.3, 0.2, math.radians(6.0))
    seen = _observed(walls, true)
    seen[4] += [0.3, 0.0, 0.3, 0.0]
    local = Surfaces.from_segments(walls)
    current = Surfaces.from_segments(seen)
    for got in _both_paths(local, current, Pose(0.35, 0.15, math.radians(7.0))):
        assert got is not None
        assert math.hypot(got.x - true.x, got.y - true.y) < 1e-6
        assert abs(got.theta - true.theta) < 1e-6


@pytest.mark.parametrize("seed", range(40))
def test_both_triangulation_paths_find_the_true_pose_where_one_is_afforded(seed: int) -> None:
    """The twin comparison on views that do afford a pose (no trivial None/None), with
    the true pose as the oracle: a few surfaces seen from a random heading (any, ±π
    included) with noise, some ends occluded or swapped, path integration near the truth."""
    rng = np.random.default_rng(5000 + seed)
    n = int(rng.integers(1, 8))
    start = rng.uniform(-4.0, 4.0, (n, 2))
    ang = rng.uniform(-np.pi, np.pi, n)
    length = rng.uniform(0.5, 3.0, n)
    direction = np.column_stack([np.cos(ang), np.sin(ang)])
    walls = np.hstack([start, start + length[:, None] * direction])
    x, y = rng.normal(0.0, 0.3, 2)
    true = Pose(float(x), float(y), float(rng.uniform(-np.pi, np.pi)))
    seen = _observed(walls, true) + rng.normal(0.0, 0.005, (n, 4))
    swap = rng.random(n) < 0.3
    seen[swap] = seen[swap][:, [2, 3, 0, 1]]
    occluded = rng.random((n, 2)) < 0.3
    occluded[0] = False  # one surface with two real corners: a pose is afforded
    local = Surfaces.from_segments(walls, occluded)
    current = Surfaces.from_segments(seen, np.where(swap[:, None], occluded[:, ::-1], occluded))
    pi = Pose(true.x + rng.normal(0, 0.05), true.y + rng.normal(0, 0.05),
              true.theta + rng.normal(0, 0.02))  # fmt: skip
    fast, slow = _both_paths(local, current, pi)
    assert fast is not None and slow is not None
    assert repr(fast) == repr(slow)
    assert math.hypot(fast.x - true.x, fast.y - true.y) < 0.05
    assert abs(math.remainder(fast.theta - true.theta, 2 * math.pi)) < math.radians(1.0)


def test_rpe_matches_timestamps_within_the_tolerance_only() -> None:
    """A relation whose times lie 0.5 s from every pose is not used (tolerance 1 ms), and
    one 0.5 ms off still is."""
    t = np.arange(4, dtype=np.float64)
    truth = np.column_stack([t, np.zeros(4), np.zeros(4)])
    rel = np.array([[1.0, 0.0, 0.0], [1.0, 0.0, 0.0]])
    _, _, used = relation_errors(t, truth, [0.5, 1.0005], [1.5, 2.0005], rel)
    assert used.tolist() == [False, True]


def test_rpe_counts_a_relation_of_exactly_split_s_as_long() -> None:
    """Short relations span less than ``split_s``; one of exactly ``split_s`` is long."""
    t = np.arange(5, dtype=np.float64)
    truth = np.column_stack([t, np.zeros(5), np.zeros(5)])
    rel = between_arrays(truth[[0, 0]], truth[[1, 2]])
    r = relative_pose_error(t, truth, [0.0, 0.0], [1.0, 2.0], rel, split_s=2.0)
    assert r.short.relations == 1 and r.long.relations == 1
