"""The campaign's faster paths give what the slower definitions gave: an episode's metrics
scored lean equal those read off a fully scored run, a failing episode's report completed
afterwards equals a fully scored run's, the laser-hit grid equals a nearest-wall tree query,
and the deletion invariant's visible share (shapely predicates) equals the share measured
from the constructed sight-line meetings."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest
import shapely
import shapely.affinity

from albot2d.evaluation.checks import hit_geometry
from albot2d.evaluation.checks.deletion import _seen_samples, ahead_square
from albot2d.evaluation.checks.simulator import SegmentGrid
from albot2d.evaluation.fuzz.campaign import CampaignParams
from albot2d.evaluation.fuzz.episode import EpisodeSpec
from albot2d.evaluation.fuzz.episode_metrics import complete_scores, episode_metrics
from albot2d.evaluation.run.experiment import ExperimentResult, run_experiment
from albot2d.evaluation.run.scoring import EvaluationParams
from albot2d.geometry import Pose
from tests.campaign_helpers import SMALL
from tests.digests import canonical


def _metrics_from_scores(result: ExperimentResult) -> dict[str, Any]:
    """The record's metrics read off the typed scores of a fully scored run (how the
    campaign read them before it scored lean)."""
    (m,) = result.scores.mappers.values()
    odo, trace = result.scores.odometry, result.trace
    assert m.rpe is not None and odo.rpe is not None
    assert m.end_pose_error is not None and odo.end_pose_error is not None
    home, quality = m.homing_summary, m.map.quality
    return {
        "frames": trace.n_frames, "travelled_m": float(trace.travelled_m[-1]),
        "collided_frames": int(trace.collided.sum()), "local_maps": m.counts.local_maps,
        "triangulations": m.counts.triangulations,
        "path_integrations": m.counts.path_integrations,
        "global_map_surfaces": m.counts.global_map_surfaces, "homing_stops": home.stops,
        "homing_bearing_error_max_deg": home.bearing_abs_max_deg,
        "homing_distance_error_max_m": home.distance_abs_max_m,
        "rpe_trans_m": m.rpe.overall.trans_m_mean, "rpe_rot_deg": m.rpe.overall.rot_deg_mean,
        "odometry_rpe_trans_m": odo.rpe.overall.trans_m_mean,
        "odometry_rpe_rot_deg": odo.rpe.overall.rot_deg_mean,
        "end_trans_m": m.end_pose_error.trans_m, "end_rot_deg": m.end_pose_error.rot_deg,
        "odometry_end_trans_m": odo.end_pose_error.trans_m,
        "odometry_end_rot_deg": odo.end_pose_error.rot_deg,
        "map_accuracy_m": quality.accuracy_m_mean, "map_accuracy_p95_m": quality.accuracy_m_p95,
        "map_completeness": quality.completeness,
    }  # fmt: skip


@pytest.fixture(scope="module")
def runs() -> tuple[ExperimentResult, ExperimentResult]:
    # A rooms world with homing stops (the tour is long enough for a few).
    campaign = CampaignParams(episodes=1, seed=5, **SMALL)
    spec = EpisodeSpec.draw(campaign, 0).run_spec()
    return run_experiment(spec), run_experiment(spec, score=False)


def test_lean_metrics_equal_the_fully_scored_ones(runs) -> None:  # type: ignore[no-untyped-def]
    full, lean = runs
    params = EvaluationParams()
    expected = _metrics_from_scores(full)
    assert expected["homing_stops"] > 0 and expected["homing_bearing_error_max_deg"] is not None
    assert episode_metrics(full, params).to_json() == expected
    assert episode_metrics(lean, params).to_json() == expected  # bit for bit, not approximately


def test_completed_scores_equal_a_fully_scored_run(runs) -> None:  # type: ignore[no-untyped-def]
    full, lean = runs
    assert lean.report["mappers"] == {} and lean.relations is None
    done = complete_scores(lean, EvaluationParams())
    assert list(done.report) == list(full.report)  # the sections in the same order
    assert canonical(done.report) == canonical(full.report)
    assert done.relations is not None and len(done.relations) == len(full.relations or [])
    assert complete_scores(done, EvaluationParams()) is done  # already scored


@pytest.mark.parametrize("seed", range(4))
def test_segment_grid_equals_a_within_distance_tree_query(seed: int) -> None:
    rng = np.random.default_rng(seed)
    walls = rng.uniform(0.0, 20.0, (60, 4))
    walls[:5, 2:] = walls[:5, :2]  # zero-length segments are points
    walls[5:15, 3] = walls[5:15, 1]  # axis-parallel walls, as in the generated worlds
    pts = np.vstack([rng.uniform(-1.0, 21.0, (3000, 2)), walls[:, :2] + 1e-3])
    tol = rng.uniform(0.0, 0.3, len(pts))
    tree = shapely.STRtree(shapely.linestrings(walls.reshape(-1, 2, 2)))
    near, _ = tree.query(shapely.points(pts), predicate="dwithin", distance=tol)
    expected = np.zeros(len(pts), dtype=bool)
    expected[near] = True
    for cell in (0.5, 1.0, 3.0):
        for backend in ("numpy", "auto"):  # auto: the compiled kernel when numba imports
            assert np.array_equal(SegmentGrid(walls, 0.3, cell).within(pts, tol, backend), expected)
    with pytest.raises(ValueError, match="reach"):
        SegmentGrid(walls, 0.1).within(pts, tol)


@pytest.mark.parametrize("seed", range(3))
def test_ray_ranges_compiled_equal_numpy_and_shapely(seed: int) -> None:
    rng = np.random.default_rng(seed)
    walls = rng.uniform(0.0, 10.0, (80, 4))
    walls[:10, 3] = walls[:10, 1]  # axis-parallel walls, rays along them
    origins = rng.uniform(1.0, 9.0, (300, 2))
    angles = rng.uniform(-np.pi, np.pi, (300, 3))
    angles[::7, 1] = np.nan  # no neighbour past a scan's end
    angles[::11, 2] = 0.0  # parallel to the axis-parallel walls
    got = {b: hit_geometry.ray_ranges(origins, angles, walls, b) for b in ("numpy", "auto")}
    assert np.array_equal(got["numpy"], got["auto"])
    assert np.isinf(got["numpy"][::7, 1]).all() and np.isfinite(got["numpy"]).mean() > 0.5
    # The nearest crossing, constructed by shapely along each ray (to 1e-9 m).
    tree = shapely.STRtree(shapely.linestrings(walls.reshape(-1, 2, 2)))
    for i, j in zip(*np.nonzero(np.isfinite(angles)), strict=True):
        if (i + j) % 9:
            continue  # a sample of the rays keeps this quick
        o, a = origins[i], angles[i, j]
        ray = shapely.LineString([o, o + 30.0 * np.array([np.cos(a), np.sin(a)])])
        hits = [ray.intersection(tree.geometries[k]) for k in tree.query(ray, "intersects")]
        near = min((shapely.distance(shapely.Point(o), h) for h in hits), default=np.inf)
        assert got["numpy"][i, j] == pytest.approx(near, abs=1e-9)


def _visible_share_by_meetings(
    segs: np.ndarray, view: np.ndarray, robot: Pose, beyond_m: float, samples: int
) -> np.ndarray:
    """The definition, constructed: each sight line's meetings with the view and the
    distance to the nearest (the deletion invariant's implementation before it used
    predicates)."""
    frac = (np.arange(samples) + 0.5) / samples
    pts = segs[:, None, :2] + frac[None, :, None] * (segs[:, None, 2:] - segs[:, None, :2])
    pts = pts.reshape(-1, 2)
    o = np.array([robot.x, robot.y])
    dist = np.linalg.norm(pts - o, axis=1)
    reach = float(np.linalg.norm(view.reshape(-1, 2) - o, axis=1).max()) + 1.0
    far = o + (pts - o) * ((reach + dist) / np.maximum(dist, 1e-12))[:, None]
    sight = shapely.linestrings(np.stack([np.broadcast_to(o, pts.shape), far], axis=1))
    meets = shapely.intersection(sight, shapely.multilinestrings(view.reshape(-1, 2, 2)))
    near = shapely.distance(shapely.points(o), meets)
    seen = ~shapely.is_empty(meets) & (dist - near <= beyond_m)
    return seen.reshape(len(segs), samples).mean(axis=1)


@pytest.mark.parametrize("seed", range(6))
def test_visible_share_equals_the_constructed_meetings(seed: int) -> None:
    rng = np.random.default_rng(seed)
    x, y, theta = rng.uniform([-1.0, -1.0, -np.pi], [1.0, 1.0, np.pi])
    robot = Pose(float(x), float(y), float(theta))
    # A view: a chain of surfaces around the robot (scan order), with gaps.
    bearings = np.sort(rng.uniform(-1.5, 1.5, 24))
    ranges = rng.uniform(2.0, 6.0, 24)
    ends = np.column_stack([robot.x + ranges * np.cos(robot.theta + bearings),
                            robot.y + ranges * np.sin(robot.theta + bearings)])  # fmt: skip
    view = np.hstack([ends[:-1], ends[1:]])[rng.uniform(size=23) < 0.7]
    # Map surfaces before, at and behind the view.
    centre = ends[rng.integers(0, 24, 40)] + rng.normal(0.0, 0.6, (40, 2))
    heading = rng.uniform(0.0, np.pi, 40)
    half = rng.uniform(0.1, 1.0, 40)[:, None] * np.column_stack([np.cos(heading), np.sin(heading)])
    segs = np.hstack([centre - half, centre + half])
    for beyond_m in (0.0, 0.5):
        expected = _visible_share_by_meetings(segs, view, robot, beyond_m, 8)
        share = _seen_samples(segs, view, robot, beyond_m, 8).mean(axis=1)
        assert np.array_equal(share, expected)
        for least in (0.5, 1.0):  # surfaces that cannot reach the share are left out early
            some = _seen_samples(segs, view, robot, beyond_m, 8, least_share=least).mean(axis=1)
            assert np.array_equal(some >= least, expected >= least)
    assert 0.0 < share.mean() < 1.0  # some seen, some not: the test can tell them apart
    assert 0 < np.count_nonzero(share == 1.0) < len(share)


@pytest.mark.parametrize("seed", range(3))
def test_the_half_plane_square_is_the_affine_transform_of_the_robot_frame_one(seed: int) -> None:
    rng = np.random.default_rng(seed)
    for x, y, theta, big in rng.uniform([-50, -50, -4, 1], [50, 50, 4, 200], (50, 4)):
        square = shapely.Polygon([(0, -big), (big, -big), (big, big), (0, big)])
        c, s = math.cos(theta), math.sin(theta)
        moved = shapely.affinity.affine_transform(square, [c, -s, s, c, x, y])
        assert shapely.equals_exact(ahead_square(Pose(x, y, theta), big), moved, tolerance=0.0)
