"""The Albot1 main loop (algorithms #2–#4) on hand-built views with known answers,
and the local-map rule on the real MIT CSAIL log."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from albot2d.evaluation.checks.invariants import ViewRecorder
from albot2d.geometry import Pose, point_segment_distance, transform_segments, wrap_angle
from albot2d.mapping import Albot1, Albot1Params
from albot2d.perception.surfaces import Surfaces
from tests.albot1_checks import check_local_map_rule
from tests.runs import check_mapper_contract, map_frames, simulate
from worldgen.generate import generate

# A corridor lined with 1 m wall panels and 0.5 m gaps, so panel ends are real corners.
PANELS = np.array(
    [[x, side, x + 1.0, side] for x in np.arange(0.0, 40.0, 1.5) for side in (-1.2, 1.2)]
)


def view_from(pose: Pose, walls: np.ndarray = PANELS, max_range_m: float = 6.0) -> Surfaces:
    """Panels fully in front of ``pose`` and within range, in the robot frame, scan order."""
    local = transform_segments(pose.inverse().as_array(), walls)
    ahead = (local[:, 0] > 0.3) & (local[:, 2] > 0.3)
    near = np.hypot(local[:, 0], local[:, 1]).clip(max=np.hypot(local[:, 2], local[:, 3]))
    segs = local[ahead & (near < max_range_m)]
    b0 = np.arctan2(segs[:, 1], segs[:, 0])
    b1 = np.arctan2(segs[:, 3], segs[:, 2])
    segs = np.where((b0 <= b1)[:, None], segs, segs[:, [2, 3, 0, 1]])
    segs = segs[np.argsort(np.minimum(b0, b1))]
    return Surfaces.from_segments(segs)


def drive(
    mapper: Albot1, poses: list[Pose], odometry: list[Pose] | None = None
) -> list[tuple[int, Surfaces, Pose]]:
    """Feed ``mapper`` the views seen from ``poses`` (odometry from ``odometry``); returns
    the views as given (for ``check_local_map_rule``)."""
    recorder = ViewRecorder().attach(mapper)
    odometry = odometry or poses
    for k, pose in enumerate(poses):
        inc = Pose() if k == 0 else odometry[k - 1].between(odometry[k])
        mapper.observe_view(k, float(k), view_from(pose), inc)
    return recorder.views


def corridor_poses(n: int = 200, step_m: float = 0.1) -> list[Pose]:
    return [
        Pose(0.5 + step_m * k, 0.05 * math.sin(k / 15), 0.03 * math.cos(k / 20)) for k in range(n)
    ]


def test_albot1_satisfies_the_mapper_protocol() -> None:
    """The protocol's signatures, and its promises on a real simulated run."""
    world = generate("rooms", seed=2, width_m=12.0, height_m=10.0)
    check_mapper_contract(Albot1(), simulate(world, 2, length_m=10.0))


def test_exact_views_give_exact_poses_and_a_map_on_the_walls() -> None:
    poses = corridor_poses()
    m = Albot1()
    drive(m, poses)
    counts = m.counts()
    assert counts.views == len(poses)
    assert 1 < counts.local_maps < counts.views  # views are remembered, but not all of them
    assert counts.triangulations == counts.local_maps - 1
    truth = np.array([p.as_array() for p in poses])
    est = m.trajectory()
    origin = Pose.from_array(truth[0])
    expected = np.array([origin.between(p).as_array() for p in poses])
    np.testing.assert_allclose(est[:, :2], expected[:, :2], atol=1e-9)
    assert np.abs(wrap_angle(est[:, 2] - expected[:, 2])).max() < 1e-9
    # Every map surface lies on a true wall (in the first view's frame).
    walls_local = transform_segments(origin.inverse().as_array(), PANELS)
    snap = m.global_map()
    assert len(snap.segments) > 0
    d = point_segment_distance(snap.segments.reshape(-1, 2), walls_local).min(axis=1)
    assert d.max() < 1e-9


def test_tracked_surfaces_are_readable_after_each_view() -> None:
    """``tracked`` is nothing before the first view, then the surfaces still tracked:
    each a surface of the latest view, with ids that survive from view to view until a
    new local map starts the tracking afresh."""
    m = Albot1()
    assert m.tracked is None
    poses = corridor_poses(30)
    ids: list[set[int]] = []
    local_maps: list[int] = []
    for k, pose in enumerate(poses):
        view = view_from(pose)
        m.observe_view(k, float(k), view, Pose() if k == 0 else poses[k - 1].between(pose))
        tracked = m.tracked
        assert tracked is not None and 0 < len(tracked) <= len(view)
        seen = transform_segments(pose.as_array(), tracked.current.segments)
        d = point_segment_distance(seen.reshape(-1, 2), PANELS).min(axis=1)
        assert d.max() < 1e-9  # the latest observation, in the latest view's frame
        ids.append(set(tracked.ids.tolist()))
        local_maps.append(m.counts().local_maps)
    kept = [bool(a & b) for a, b in itertools.pairwise(ids)]
    fresh = [b > a for a, b in itertools.pairwise(local_maps)]
    assert kept == [not f for f in fresh] and 0 < sum(fresh) < sum(kept)


def test_triangulation_corrects_odometry_errors() -> None:
    poses = corridor_poses()
    rng = np.random.default_rng(5)
    # Odometry that over-reports each step by 3 % and drifts 0.2 degrees per step.
    odo = [poses[0]]
    for a, b in itertools.pairwise(poses):
        inc = a.between(b)
        noisy = Pose(inc.x * 1.03, inc.y, inc.theta + math.radians(0.2) + rng.normal(0, 1e-4))
        odo.append(odo[-1] @ noisy)
    m = Albot1()
    drive(m, poses, odo)
    truth = poses[0].between(poses[-1])
    est = Pose.from_array(m.trajectory()[-1])
    raw = odo[0].between(odo[-1])
    assert abs(wrap_angle(est.theta - truth.theta)) < 0.5 * abs(wrap_angle(raw.theta - truth.theta))
    assert est.distance_to(truth) < 0.5 * raw.distance_to(truth)


def test_local_map_rule_and_use_vc_on_hand_built_views() -> None:
    poses = corridor_poses(120)
    m = Albot1()
    views = drive(m, poses)
    check_local_map_rule(m, views, min_tracked=4)


def test_featureless_stretch_uses_path_integration_then_recovers() -> None:
    # Panels only at the start and at the end; nothing in view in between.
    walls = PANELS[(PANELS[:, 0] < 6.0) | (PANELS[:, 0] > 18.0)]
    poses = [Pose(0.5 + 0.2 * k, 0.0, 0.0) for k in range(110)]
    m = Albot1()
    recorder = ViewRecorder().attach(m)
    for k, pose in enumerate(poses):
        inc = Pose() if k == 0 else poses[k - 1].between(pose)
        m.observe_view(k, float(k), view_from(pose, walls), inc)
    methods = m.route.methods()
    assert "path_integration" in methods
    last_pi = max(i for i, meth in enumerate(methods) if meth == "path_integration")
    assert "triangulation" in methods[last_pi:]  # back to view navigation after the gap
    # With exact odometry, path integration is exact too.
    origin = poses[0]
    np.testing.assert_allclose(m.trajectory()[-1], origin.between(poses[-1]).as_array(), atol=1e-9)
    check_local_map_rule(m, recorder.views, min_tracked=4)


def test_params_are_validated() -> None:
    from albot2d.errors import InputError

    with pytest.raises(InputError, match="min_tracked"):
        Albot1Params(min_tracked=0)


def test_mit_csail_log_runs_through(shared_data) -> None:  # type: ignore[no-untyped-def]
    from albot2d.evaluation.metrics.rpe import relative_pose_error
    from albot2d.logs import read_frames, read_relations

    frames = list(read_frames(shared_data / "raw" / "mit-csail.clf.gz"))
    rel = read_relations(shared_data / "relations" / "mit-csail.relations")
    m = Albot1()
    recorder = ViewRecorder().attach(m)
    map_frames(m, frames)
    counts = m.counts()
    assert counts.views == len(frames) == 1988
    assert counts.local_maps == counts.triangulations + counts.path_integrations + 1
    check_local_map_rule(m, recorder.views, 4)
    ts = np.array([f.timestamp for f in frames])
    odo = np.array([f.odom_pose.as_array() for f in frames])
    ours = relative_pose_error(ts, m.trajectory(), rel.t1, rel.t2, rel.motion)
    raw = relative_pose_error(ts, odo, rel.t1, rel.t2, rel.motion)
    assert ours.short.relations == raw.short.relations > 1000
    # Triangulation beats raw odometry on short-relation heading error (paper's claim).
    assert ours.short.rot_deg_mean < raw.short.rot_deg_mean
    assert set(m.timings_ms()) == {"extraction", "tracking", "localization", "global_map"}
