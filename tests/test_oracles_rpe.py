"""RPE's argument checks and its short/long split, by hand (the metric itself is checked
against evo's RPE in ``tests/test_oracles.py``)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from albot2d.errors import InputError
from albot2d.evaluation.metrics.rpe import relative_pose_error

T = np.array([0.0, 1.0, 2.0, 3.0])
POSES = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0], [3.0, 0.0, 0.0]])


@pytest.mark.parametrize("split_s", [0.0, -1.0, math.nan, math.inf])
def test_split_must_be_a_positive_finite_time(split_s: float) -> None:
    with pytest.raises(InputError, match="split_s must be > 0"):
        relative_pose_error(T, POSES, [0.0], [1.0], [[1.0, 0.0, 0.0]], split_s=split_s)


def test_relations_are_split_at_split_s_and_measured_by_hand() -> None:
    """Relations 0→1 s (measured 1.1 m: error 0.1 m), 0→3 s (3 m, exact) and 1→3 s
    (2 m, heading off by 2°): split at 2 s, the first is short, the others long
    (heading errors 0° and 2°: mean 1°)."""
    rel = [[1.1, 0.0, 0.0], [3.0, 0.0, 0.0], [2.0, 0.0, math.radians(2.0)]]
    got = relative_pose_error(T, POSES, [0.0, 0.0, 1.0], [1.0, 3.0, 3.0], rel, split_s=2.0)
    assert got.split_s == 2.0
    assert got.short.trans_m_mean == pytest.approx(0.1, abs=1e-12)
    assert got.long.trans_m_mean == pytest.approx(0.0, abs=1e-12)
    assert got.long.rot_deg_mean == pytest.approx(1.0, abs=1e-9)
    assert (got.short.relations, got.long.relations, got.overall.relations) == (1, 2, 3)
    assert got.overall.trans_m_mean == pytest.approx(0.1 / 3, abs=1e-12)


def test_a_relation_ending_at_the_first_pose_is_used() -> None:
    """A relation back in time, from 2 s to 0 s (the first pose): measured (−2, 0, 0),
    estimated exactly; and a zero-length one at 0 s measured 0.05 m off."""
    rel = [[-2.0, 0.0, 0.0], [0.05, 0.0, 0.0]]
    got = relative_pose_error(T, POSES, [2.0, 0.0], [0.0, 0.0], rel)
    assert got.overall.relations == 2
    assert got.overall.trans_m_mean == pytest.approx(0.025, abs=1e-12)


def test_no_estimate_uses_no_relation() -> None:
    got = relative_pose_error([], np.zeros((0, 3)), [0.0, 1.0], [1.0, 3.0], [[1, 0, 0]] * 2)
    assert got.overall.relations == 0
    assert got.overall.trans_m_mean is None
    assert (got.short.relations, got.long.relations) == (0, 0)


def test_to_dict_nests_short_and_long_under_the_overall_numbers() -> None:
    """Errors 0.1 and 0.3 m (mean 0.2, population std 0.1), no heading error."""
    rel = [[1.1, 0.0, 0.0], [3.3, 0.0, 0.0]]
    got = relative_pose_error(T, POSES, [0.0, 0.0], [1.0, 3.0], rel, split_s=2.0).to_dict()
    assert got["trans_m_mean"] == pytest.approx(0.2, abs=1e-12)
    assert got["trans_m_std"] == pytest.approx(0.1, abs=1e-12)
    assert got["rot_deg_mean"] == 0.0
    assert got["relations"] == 2
    assert got["split_s"] == 2.0
    assert got["short"] == {"trans_m_mean": pytest.approx(0.1), "trans_m_std": 0.0,
                            "rot_deg_mean": 0.0, "rot_deg_std": 0.0, "relations": 1}  # fmt: skip
    assert got["long"]["relations"] == 1  # type: ignore[index]


def test_a_split_under_a_second_is_allowed() -> None:
    rel = [[1.1, 0.0, 0.0]]
    got = relative_pose_error(T, POSES, [0.0], [1.0], rel, split_s=0.5)
    assert (got.short.relations, got.long.relations) == (0, 1)


def test_relation_errors_without_an_estimate_are_nan() -> None:
    from albot2d.evaluation.metrics.rpe import relation_errors

    trans, rot, used = relation_errors([], np.zeros((0, 3)), [0.0], [1.0], [[1.0, 0.0, 0.0]])
    assert np.isnan(trans).all() and np.isnan(rot).all()
    assert trans.dtype == rot.dtype == np.float64
    assert used.tolist() == [False]
