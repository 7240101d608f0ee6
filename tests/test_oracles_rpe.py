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
