"""Relations files: round trips, bad lines, relations from truth, and the real MIT benchmark."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from albot2d.errors import InputError
from albot2d.geometry import between_arrays, compose_arrays, wrap_angle
from albot2d.logs import (
    Relations,
    RelationsOptions,
    match_timestamps,
    read_frames,
    read_relations,
    relations_from_truth,
    write_relations,
)

finite = st.floats(min_value=-1e4, max_value=1e4, allow_subnormal=False)


@st.composite
def relations(draw: st.DrawFn) -> Relations:
    n = draw(st.integers(min_value=0, max_value=20))
    values = draw(st.lists(finite, min_size=5 * n, max_size=5 * n))
    table = np.array(values, dtype=np.float64).reshape(n, 5)
    return Relations(t1=table[:, 0], t2=table[:, 1], motion=table[:, 2:])


@pytest.mark.parametrize("name", ["a.relations", "a.relations.gz"])
@given(rel=relations())
def test_relations_round_trip(tmp_path_factory, name, rel):
    path = tmp_path_factory.mktemp("rel") / name
    write_relations(path, rel, header=["made by a test"])
    back = read_relations(path)
    for field in ("t1", "t2", "motion"):
        np.testing.assert_array_equal(getattr(back, field), getattr(rel, field))
    assert len(back) == len(rel)


def test_reader_accepts_comments_blank_lines_and_ignores_3d_fields(tmp_path):
    path = tmp_path / "r.relations"
    path.write_text("# header\n\n1.0 2.0 0.5 -0.25 9 9 9 0.1  # trailing comment\n   \n")
    rel = read_relations(path)
    assert rel.t1.tolist() == [1.0] and rel.t2.tolist() == [2.0]
    assert rel.motion.tolist() == [[0.5, -0.25, 0.1]]
    assert not rel.motion.flags.writeable


@pytest.mark.parametrize(
    ("line", "reason"),
    [
        ("1 2 3 4 5 6 7", "7 fields, expected 8"),
        ("1 2 3 4 5 6 7 8 9", "9 fields, expected 8"),
        ("1 2 x 4 5 6 7 8", "field x 'x' is not a finite number"),
        ("1 nan 3 4 5 6 7 8", "field t2 'nan'"),
        ("1 2 3 4 5 6 7 inf", "field yaw 'inf'"),
    ],
)
def test_bad_relation_lines(tmp_path, line, reason):
    path = tmp_path / "bad.relations"
    path.write_text("0 1 0 0 0 0 0 0\n" + line + "\n")
    with pytest.raises(InputError) as info:
        read_relations(path)
    assert str(info.value).startswith(f"{path}:2: ")
    assert reason in str(info.value)


def test_relations_from_truth_hand_computed():
    t = [0.0, 1.0, 2.0]
    poses = [[0.0, 0.0, 0.0], [1.0, 0.0, math.pi / 2], [1.0, 1.0, math.pi]]
    rel = relations_from_truth(t, poses)
    assert rel.t1.tolist() == [0.0, 1.0] and rel.t2.tolist() == [1.0, 2.0]
    # Pose 1 faces +y; the step to (1, 1) is 1 m straight ahead, then a left turn of 90°.
    expected = [[1.0, 0.0, math.pi / 2], [1.0, 0.0, math.pi / 2]]
    np.testing.assert_allclose(rel.motion, expected, atol=1e-12)


def _square_loop(laps: float = 1.0, side_m: float = 10.0, step_m: float = 0.5):
    """Drive counter-clockwise around a square at 1 step/s, back to the start."""
    per_side = round(side_m / step_m)
    poses = []
    for k in range(round(4 * per_side * laps) + 1):
        side, along = divmod(k % (4 * per_side), per_side)
        heading = side * math.pi / 2
        corner = [(0, 0), (side_m, 0), (side_m, side_m), (0, side_m)][side]
        poses.append(
            [corner[0] + along * step_m * math.cos(heading),
             corner[1] + along * step_m * math.sin(heading), wrap_angle(heading)]
        )  # fmt: skip
    return np.arange(len(poses), dtype=np.float64), np.array(poses)


def test_loop_closing_relation_found_on_revisit():
    t, poses = _square_loop()  # 81 poses; pose 80 is back at the start
    options = RelationsOptions(long_range_every=40, long_range_min_gap_s=30.0)
    rel = relations_from_truth(t, poses, options=options)
    consecutive = rel.t2 - rel.t1 == 1.0
    assert consecutive.sum() == 80
    # Anchor 0 revisited at 80 (same place and heading); anchor 40 (the far corner) never is.
    assert list(zip(rel.t1[~consecutive], rel.t2[~consecutive], strict=True)) == [(0.0, 80.0)]
    np.testing.assert_allclose(rel.motion[~consecutive], [[0.0, 0.0, 0.0]], atol=1e-12)
    # A revisit 0.3 m to the anchor's right, heading the other way, is the nearest (pose 79 is
    # 0.5 m away), so it is the one chosen.
    poses[80] = [0.0, -0.3, math.pi]
    rel = relations_from_truth(t, poses, options=options)
    assert rel.t2[~consecutive].tolist() == [80.0]
    np.testing.assert_allclose(rel.motion[~consecutive], [[0.0, -0.3, -math.pi]], atol=1e-12)


@given(
    steps=st.lists(
        st.tuples(finite, finite, st.floats(-math.pi, math.pi)), min_size=1, max_size=30
    ),
    every=st.integers(min_value=1, max_value=5),
)
def test_every_relation_is_the_truth_between_its_poses(steps, every):
    poses = np.array(steps) * [1e-2, 1e-2, 1.0]  # keep revisits likely: stay within metres
    t = np.arange(len(poses)) * 4.0
    rel = relations_from_truth(
        t, poses, options=RelationsOptions(long_range_every=every, long_range_min_gap_s=8.0)
    )
    i = match_timestamps(rel.t1, t)
    j = match_timestamps(rel.t2, t)
    assert np.all(j > i)
    assert len(np.unique(np.column_stack([i, j]), axis=0)) == len(rel)
    np.testing.assert_allclose(compose_arrays(poses[i], rel.motion)[:, :2], poses[j, :2], atol=1e-9)
    assert np.all(np.abs(wrap_angle(rel.motion[:, 2] - (poses[j, 2] - poses[i, 2]))) < 1e-9)
    assert relations_from_truth(t, poses).t1.tolist() == relations_from_truth(t, poses).t1.tolist()


def test_relations_from_truth_rejects_bad_input():
    with pytest.raises(InputError, match="increase strictly"):
        relations_from_truth([0.0, 1.0, 1.0], np.zeros((3, 3)))
    with pytest.raises(InputError, match=r"\(N, 3\)"):
        relations_from_truth([0.0, 1.0], np.zeros((3, 3)))
    with pytest.raises(InputError, match="finite"):
        relations_from_truth([0.0, 1.0], [[0, 0, 0], [math.nan, 0, 0]])
    with pytest.raises(InputError, match="long_range_every"):
        RelationsOptions(long_range_every=0)
    with pytest.raises(InputError, match="long_range_max_distance_m"):
        RelationsOptions(long_range_max_distance_m=-1.0)
    assert len(relations_from_truth([], np.zeros((0, 3)))) == 0


def test_match_timestamps():
    ref = [1.0, 2.0, 3.0]
    assert match_timestamps([2.00001, 1.0, 3.0], ref).tolist() == [1, 0, 2]
    with pytest.raises(InputError, match=r"timestamp \[1\] = 2.5 matches no reference"):
        match_timestamps([1.0, 2.5], ref)


def test_mit_relations_against_raw_odometry(shared_data):
    """Validates both readers: the SOURCES.md reference error of raw odometry."""
    rel = read_relations(shared_data / "relations" / "mit-csail.relations")
    assert len(rel) == 1172
    frames = list(read_frames(shared_data / "raw" / "mit-csail.clf.gz"))
    stamps = np.array([f.timestamp for f in frames])
    odom = np.array([f.odom_pose.as_array() for f in frames])
    # The relations file keeps 5 decimals of the log's 6: every stamp is within 5 µs of a scan.
    i = match_timestamps(rel.t1, stamps, tolerance_s=6e-6)
    j = match_timestamps(rel.t2, stamps, tolerance_s=6e-6)
    estimate = between_arrays(odom[i], odom[j])
    error = between_arrays(rel.motion, estimate)  # (δ*)⁻¹ ⊕ δ
    trans = np.hypot(error[:, 0], error[:, 1])
    rot = np.degrees(np.abs(wrap_angle(error[:, 2])))
    measured = [trans.mean(), trans.std(), rot.mean(), rot.std()]
    np.testing.assert_allclose(measured, [1.68, 5.29, 5.07, 8.24], atol=0.005)
