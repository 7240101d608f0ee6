"""Metric unit tests with hand-computed answers: RPE of known perturbations, homing signs."""

from __future__ import annotations

import math

import numpy as np
import pytest

from albot2d.errors import InputError
from albot2d.evaluation.metrics.homing import homing, homing_to_start
from albot2d.evaluation.metrics.rpe import relative_pose_error
from albot2d.geometry import Pose, between_arrays


def straight_line(n: int = 5) -> tuple[np.ndarray, np.ndarray]:
    t = np.arange(n, dtype=float)
    poses = np.column_stack([t, np.zeros(n), np.zeros(n)])
    return t, poses


def test_perfect_estimate_has_zero_error() -> None:
    t, truth = straight_line()
    rel = between_arrays(truth[:-1], truth[1:])
    r = relative_pose_error(t, truth, t[:-1], t[1:], rel)
    assert r.overall.relations == 4
    assert r.overall.trans_m_mean == pytest.approx(0.0)
    assert r.overall.rot_deg_mean == pytest.approx(0.0)


def test_known_perturbation() -> None:
    t, truth = straight_line(3)
    est = truth.copy()
    est[2] = [2.0, 0.0, math.radians(10.0)]  # last pose rotated by 10 degrees only
    est[1, 0] = 1.5  # middle pose 0.5 m too far
    rel = between_arrays(truth[:-1], truth[1:])
    r = relative_pose_error(t, est, t[:-1], t[1:], rel)
    # relation 0->1: 1.5 m instead of 1 m -> 0.5 m, 0 deg
    # relation 1->2: 0.5 m instead of 1 m (0.5 m), heading +10 deg
    assert r.overall.trans_m_mean == pytest.approx(0.5)
    assert r.overall.rot_deg_mean == pytest.approx(5.0)
    assert r.overall.rot_deg_std == pytest.approx(5.0)


def test_short_long_split_and_missing_timestamps() -> None:
    t, truth = straight_line(6)
    t1 = np.array([0.0, 0.0, 1.0, 99.0])
    t2 = np.array([1.0, 5.0, 2.0, 100.0])
    rel = np.array([[1, 0, 0], [5, 0, 0], [1, 0, 0], [1, 0, 0]], float)
    est = truth.copy()
    est[5, 1] = 0.3  # the long relation 0->5 is off by 0.3 m sideways
    r = relative_pose_error(t, est, t1, t2, rel)
    assert r.overall.relations == 3  # the relation at t=99..100 has no poses
    assert r.short.relations == 2 and r.long.relations == 1
    assert r.long.trans_m_mean == pytest.approx(0.3)
    assert r.short.trans_m_mean == pytest.approx(0.0)


def test_rpe_rejects_bad_split() -> None:
    t, truth = straight_line()
    with pytest.raises(InputError, match="split_s"):
        relative_pose_error(t, truth, t, t, truth, split_s=-1)


def test_homing_bearing_sign_convention() -> None:
    # Facing +x, start on the left (+y): turn left = positive bearing.
    b, d = homing(Pose(0, 0, 0), (0.0, 2.0))
    assert b == pytest.approx(90.0) and d == pytest.approx(2.0)
    b, _ = homing(Pose(0, 0, 0), (0.0, -2.0))
    assert b == pytest.approx(-90.0)
    b, _ = homing(Pose(1, 1, math.pi / 2), (1.0, 0.0))  # facing +y, start behind
    assert abs(b) == pytest.approx(180.0)


def test_homing_to_start_compares_each_trajectory_in_its_own_frame() -> None:
    truth = np.array([[0, 0, 0], [3, 4, math.pi / 2]], float)
    # The estimate lives in a frame rotated by 30 degrees: homing must not care.
    rot = math.radians(30)
    c, s = math.cos(rot), math.sin(rot)
    est = np.column_stack(
        [c * truth[:, 0] - s * truth[:, 1], s * truth[:, 0] + c * truth[:, 1], truth[:, 2] + rot]
    )
    h = homing_to_start(1, est[1], est[0], truth[1], truth[0])
    assert h.distance_true_m == pytest.approx(5.0)
    assert h.bearing_error_deg == pytest.approx(0.0, abs=1e-9)
    assert h.distance_error_m == pytest.approx(0.0, abs=1e-9)
    unknown = homing_to_start(1, est[1], est[0])  # a real log: no truth, no errors
    assert unknown.bearing_est_deg == h.bearing_est_deg and unknown.bearing_error_deg is None


# -- map quality ----------------------------------------------------------------------
def test_map_quality_known_offsets() -> None:
    from albot2d.evaluation.metrics.map_quality import map_quality, sample_segments

    truth = np.array([[0.0, 0.0, 10.0, 0.0]])
    # A map surface 5 cm off the wall, expressed in a mapper frame whose origin is the
    # true start pose (2, 1) facing +y.
    start = Pose(2.0, 1.0, math.pi / 2)
    world_seg = np.array([[1.0, 0.05, 3.0, 0.05]])
    local = np.hstack(
        [
            start.inverse().transform_points(world_seg[:, :2]),
            start.inverse().transform_points(world_seg[:, 2:]),
        ]
    )
    seen = sample_segments(np.array([[0.0, 0.0, 4.0, 0.0]]), 0.5)  # 4 m seen, 2 m mapped
    q = map_quality(local, truth, start_pose=start, seen_points=seen)
    assert q.accuracy_m_mean == pytest.approx(0.05)
    assert q.accuracy_m_max == pytest.approx(0.05)
    assert q.completeness == pytest.approx(5 / 9)  # points x = 1.0 … 3.0 of 0, 0.5, … 4.0
    empty = map_quality(np.zeros((0, 4)), truth, start_pose=start)
    assert empty.accuracy_m_mean is None and empty.surfaces == 0


def test_sample_segments_spacing_and_endpoints() -> None:
    from albot2d.evaluation.metrics.map_quality import sample_segments

    pts = sample_segments(np.array([[0, 0, 1, 0], [0, 0, 0, 0.01]], float), 0.25)
    assert len(pts) == 5 + 2
    np.testing.assert_allclose(pts[:5, 0], [0, 0.25, 0.5, 0.75, 1.0])


@pytest.mark.parametrize(("seed", "small_blocks"), [(0, False), (1, False), (2, True)])
def test_map_sample_distances_equal_the_nearest_wall_tree_query(
    seed: int, small_blocks: bool, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The bounded per-surface candidate search gives every sample the tree's nearest-wall
    distance (up to rounding), including samples far from every wall."""
    import importlib

    import shapely

    from albot2d.evaluation.metrics.map_quality import _sample_distances, sample_segments

    if small_blocks:  # many blocks and chunks, as on a long run's maps
        module = importlib.import_module("albot2d.evaluation.metrics.map_quality")
        monkeypatch.setattr(module, "_BLOCK_SAMPLES", 700)
        monkeypatch.setattr(module, "_CHUNK_PAIRS", 900)

    rng = np.random.default_rng(seed)
    walls = rng.uniform(0.0, 20.0, (60, 4))
    walls[:5, 2:] = walls[:5, :2]  # degenerate (point) walls too
    near = walls[rng.integers(0, 60, 300)] + rng.normal(0.0, 0.05, (300, 4))
    far = rng.uniform(-30.0, 50.0, (40, 4))  # many samples > 0.5 m from any wall
    segs = np.vstack([near, far, [[3.0, 3.0, 3.0, 3.0]]])
    samples = sample_segments(segs, 0.05)
    tree = shapely.STRtree(shapely.linestrings(walls.reshape(-1, 2, 2)))
    _, expected = tree.query_nearest(shapely.points(samples), return_distance=True,
                                     all_matches=False)  # fmt: skip
    got = _sample_distances(segs, 0.05, walls)
    assert (got > 0.5).any() and (got < 0.01).any()
    np.testing.assert_allclose(got, expected, rtol=0.0, atol=1e-12)


@pytest.mark.parametrize("seed", [0, 3])
def test_pruning_candidate_walls_changes_no_distance(
    seed: int, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Dropping the candidate walls that cannot be nearest to any point of a surface
    (``_may_be_nearest``) gives the same distances bit for bit as measuring them all,
    on walls meeting at corners, parallel faces and a map drifted off them."""
    import importlib

    module = importlib.import_module("albot2d.evaluation.metrics.map_quality")
    rng = np.random.default_rng(seed)
    # A grid of rooms: two faces 0.15 m apart per wall, so parallel candidates abound.
    lines = [[x + dx, 0.0, x + dx, 20.0] for x in range(0, 21, 5) for dx in (0.0, 0.15)]
    lines += [[0.0, y + dy, 20.0, y + dy] for y in range(0, 21, 5) for dy in (0.0, 0.15)]
    walls = np.array(lines, float)
    pieces = walls[rng.integers(0, len(walls), 400)]
    t0, t1 = np.sort(rng.uniform(0.0, 1.0, (2, 400)), axis=0)
    span = pieces[:, 2:] - pieces[:, :2]
    segs = np.hstack([pieces[:, :2] + t0[:, None] * span, pieces[:, :2] + t1[:, None] * span])
    segs = np.vstack([segs + rng.normal(0.0, 0.02, segs.shape),  # along the walls
                      segs + rng.normal(0.0, 0.6, segs.shape)])  # a drifted map  # fmt: skip
    kept = []

    def counting(surfaces: np.ndarray, which: np.ndarray, cand: np.ndarray) -> np.ndarray:
        keep = may_be_nearest(surfaces, which, cand)
        kept.append((int(keep.sum()), len(keep)))
        return keep

    may_be_nearest = module._may_be_nearest
    monkeypatch.setattr(module, "_may_be_nearest", counting)
    pruned = module._sample_distances(segs, 0.05, walls)
    monkeypatch.setattr(module, "_may_be_nearest", lambda s, w, c: np.ones(len(w), bool))
    every = module._sample_distances(segs, 0.05, walls)
    np.testing.assert_array_equal(pruned, every)
    assert sum(k for k, _ in kept) < sum(n for _, n in kept)  # some were dropped
