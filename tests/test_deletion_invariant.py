"""The deletion invariant (algorithm #5's postcondition) asks its tests cheapest first and
builds P only when a surface is still in question: its verdict equals, message for message,
the definition asked in full (every older surface tested against P, then facing, seen side
and visible share) on real runs of every deletion preset, on the real updates and on
updates broken on purpose; the prefilters that spare shapely never drop a point shapely
would call seen."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from albot2d.errors import InvariantError
from albot2d.evaluation.checks import deletion as di
from albot2d.geometry import Pose, transform_segments
from albot2d.mapping import Albot1, Albot1Params, UpdateReport
from albot2d.mapping.albot1.deletion import GlobalMapParams
from albot2d.mapping.albot1.route_map import LocalMap
from tests.runs import map_frames, simulate
from worldgen.generate import generate

# The compiled prefilter when numba imports, and the numpy path.
BACKENDS = ("numpy", "numba") if di._kernels() is not None else ("numpy",)
PRESETS = {
    "visible": GlobalMapParams(),
    "visible_half": GlobalMapParams(min_visible_share=0.5),
    "paper": GlobalMapParams.preset("paper"),
    "v1": GlobalMapParams.preset("v1"),
    "original": GlobalMapParams.preset("original"),
}


def _reference(m: Albot1, report: UpdateReport, robot: Pose, view: np.ndarray) -> str | None:
    """The check as the definition reads, every test on every older surface (the
    invariant's implementation before it ordered its tests): the message, or None."""
    params = m.map.params
    snap = m.map.snapshot()
    older = snap.map_ids < report.map_id
    view = np.asarray(view, np.float64).reshape(-1, 4)
    if not older.any() or len(view) == 0:
        return None
    if params.keep_if_all and report.deleted_current + report.deleted_older == 0:
        return None
    segs, ids = snap.segments[older], snap.map_ids[older]
    poly = di._view_polygon(view, robot, params.enlarge_m, params.enlarge, params.include_viewpoint)
    hits = di.shapely.intersects(poly, di.shapely.linestrings(segs.reshape(-1, 2, 2)))
    seeable = hits & di.facing_mask(segs, robot, params.facing_test)
    if params.seen_side == "front":
        d = segs[:, 2:] - segs[:, :2]
        r = np.array([robot.x, robot.y]) - segs[:, :2]
        seeable &= d[:, 0] * r[:, 1] - d[:, 1] * r[:, 0] > 0
    if params.could_see == "visible" and seeable.any():
        share = np.zeros(len(segs))
        share[seeable] = di._seen_samples(
            segs[seeable], view, robot, params.enlarge_m, params.visible_samples
        ).mean(axis=1)
        seeable &= (share > 0) & (share >= params.min_visible_share)
    current = report.map_id - 1
    left = (hits if params.current_map == "touch" else seeable) & (ids == current)
    if left.any():
        return (
            f"update {report.update} (map {report.map_id}): {int(left.sum())} surface(s) "
            "of the map being left remain inside the view polygon"
        )
    stale = seeable & (ids < current)
    if stale.any():
        return (
            f"update {report.update} (map {report.map_id}): {int(stale.sum())} older "
            f"surface(s) of map(s) {sorted(set(ids[stale].tolist()))} remain in view "
            "on the facing side"
        )
    return None


def _verdict(m: Albot1, report: UpdateReport, robot: Pose, view: np.ndarray) -> str | None:
    try:
        di.check_update_deleted_facing_overlap(m, report, robot, view)
    except InvariantError as exc:
        return exc.message
    return None


@pytest.fixture(scope="module")
def frames():  # type: ignore[no-untyped-def]
    return simulate(generate("rooms", seed=4, width_m=14.0, height_m=12.0), 4, length_m=25.0)


@pytest.mark.parametrize("backend", ["auto", "numpy"])
@pytest.mark.parametrize("preset", list(PRESETS))
def test_the_ordered_check_equals_the_definition(
    frames, preset: str, backend: str, monkeypatch
) -> None:  # type: ignore[no-untyped-def]
    if backend == "numpy":  # as without numba installed
        monkeypatch.setattr(di, "_kernels", lambda: None)
    mapper = Albot1(Albot1Params(global_map=PRESETS[preset]))
    rng = np.random.default_rng(len(preset))
    seen: dict[str, int] = {"cases": 0, "violations": 0}

    def on_update(report: UpdateReport, lm: LocalMap) -> None:
        view = transform_segments(lm.pose.as_array(), lm.view.segments)
        cases = [(report, lm.pose, view)]
        # Broken on purpose: an earlier view seen again from near its own pose, as a new
        # map (its surfaces, and others, left behind) or as the map being left.
        for _ in range(3):
            old = mapper.route[int(rng.integers(len(mapper.route)))]
            pose = Pose(*(old.pose.as_array() + rng.normal(0.0, [0.3, 0.3, 0.4])))
            last = int(mapper.map.snapshot().map_ids.max())
            broken = report._replace(map_id=last + int(rng.integers(1, 3)))
            cases.append((broken, pose, transform_segments(old.pose.as_array(), old.view.segments)))
        for rep, pose, v in cases:
            expected = _reference(mapper, rep, pose, v)
            assert _verdict(mapper, rep, pose, v) == expected
            seen["cases"] += 1
            seen["violations"] += expected is not None

    mapper.on_update = on_update
    map_frames(mapper, frames)
    # The real updates pass, the broken ones mostly fail: the comparison tells them apart.
    assert seen["cases"] > 100 and 0.2 * seen["cases"] < seen["violations"] < seen["cases"]


def _views(rng: np.random.Generator, robot: Pose) -> np.ndarray:
    bearings = np.sort(rng.uniform(-1.6, 1.6, 30))
    ranges = rng.uniform(0.5, 6.0, 30)
    ends = np.column_stack([robot.x + ranges * np.cos(robot.theta + bearings),
                            robot.y + ranges * np.sin(robot.theta + bearings)])  # fmt: skip
    return np.hstack([ends[:-1], ends[1:]])[rng.uniform(size=29) < 0.6]


@pytest.mark.parametrize("seed", range(8))
def test_the_prefilters_drop_only_points_shapely_calls_unseen(seed: int) -> None:
    rng = np.random.default_rng(seed)
    robot = Pose(*rng.uniform([-1.0, -1.0, -np.pi], [1.0, 1.0, np.pi]))
    view = _views(rng, robot)
    # Map surfaces all round, near and far, some through the view's own endpoints (sight
    # lines grazing a view surface's end) and some on the view surfaces themselves.
    centre = np.vstack([rng.uniform(-9.0, 9.0, (150, 2)), view[:, :2], view[:, 2:]])
    heading = rng.uniform(0.0, np.pi, len(centre))
    half = rng.uniform(0.05, 1.5, len(centre))[:, None]
    half = half * np.column_stack([np.cos(heading), np.sin(heading)])
    segs = np.vstack([np.hstack([centre - half, centre + half]), view])
    for beyond_m in (0.0, 0.3, 0.5):
        sight = di._SightLines(segs, view, robot, beyond_m, 8)
        every = np.arange(len(sight.dist))
        seen = sight.seen(every)
        far, surely = sight.out_of_reach(), sight.surely_unseen(every)
        assert not (seen & (far | surely)).any()
        assert far.sum() > 100 and (surely & ~far).sum() > 100 and seen.sum() > 50  # all bite
        assert (surely & ~far & sight.meets(every)).sum() > 20  # blocked, proven so
        expected = di._seen_samples(segs, view, robot, beyond_m, 8).mean(axis=1)
        for share in (0.0, 0.3, 0.5, 1.0):
            for backend in BACKENDS:
                got = di.visible_mask(segs, view, robot, beyond_m, 8, share, backend)
                assert np.array_equal(got, (expected > 0) & (expected >= share))
        kernels = di._kernels()
        if kernels is not None:  # the compiled prefilter drops no seen point either
            possible = kernels.possible_points(
                segs, view, robot.x, robot.y, beyond_m, 8, 1, di._MARGIN_M, di._MARGIN_RAD
            )
            assert not (seen & ~possible.ravel()).any()
            assert (~possible.ravel() & ~far).sum() > 100


def test_a_view_through_the_viewpoint_turns_the_fan_prefilter_off() -> None:
    robot = Pose(0.0, 0.0, 0.0)
    view = np.array([[-2.0, 0.0, 2.0, 0.0], [1.0, 1.0, 1.0, 2.0]])  # the first through o
    sight = di._SightLines(np.array([[0.0, -3.0, 1.0, -3.0]]), view, robot, 0.5, 8)
    assert not sight.surely_unseen(np.arange(8)).any()
    view[0] = [-2.0, 1e-9, 2.0, 1e-9]  # passing a nanometre from it: spans nearly π
    sight = di._SightLines(np.array([[0.0, -3.0, 1.0, -3.0]]), view, robot, 0.5, 8)
    assert not sight.surely_unseen(np.arange(8)).any()


def test_the_visible_share_keeps_the_preset_semantics() -> None:
    # min_visible_share above 1 can never be met; 0 still needs one point seen.
    robot = Pose(0.0, 0.0, 0.0)
    view = np.array([[2.0, -1.0, 2.0, 1.0]])
    segs = np.array([[1.0, -0.5, 1.0, 0.5], [3.0, 5.0, 3.0, 6.0]])
    assert _visible_list(segs, view, robot, 1.0) == [True, False]
    assert _visible_list(segs, view, robot, 0.0) == [True, False]
    assert _visible_list(segs, view, robot, 1.5) == [False, False]
    assert dataclasses.is_dataclass(GlobalMapParams)


def _visible_list(segs: np.ndarray, view: np.ndarray, robot: Pose, share: float) -> list[bool]:
    return di.visible_mask(segs, view, robot, 0.5, 8, share).tolist()


@pytest.mark.parametrize("seed", range(3))
def test_the_facing_and_seen_side_tests_compiled_equal_numpy(seed: int, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    rng = np.random.default_rng(seed)
    segs = rng.uniform(-5.0, 5.0, (400, 4))
    segs[:20, 2:] = segs[:20, :2]  # points
    robot = Pose(*rng.uniform([-1.0, -1.0, -np.pi], [1.0, 1.0, np.pi]))
    for test in ("any_endpoint", "both_endpoints", "midpoint"):
        for front in (False, True):
            got = di._facing_front(segs, robot, test, front)
            with monkeypatch.context() as patch:
                patch.setattr(di, "_kernels", lambda: None)
                assert np.array_equal(got, di._facing_front(segs, robot, test, front))
            assert 0 < got.sum() < len(segs)
