"""StageTimer: stage times add up per name and per view, also when the block raises."""

from __future__ import annotations

import time

import pytest

from albot2d.mapping.protocol import StageTimer


def test_stages_add_their_time_per_name_and_per_view() -> None:
    timer = StageTimer()
    with timer.stage("a"):
        time.sleep(0.002)
    with timer.stage("b"), timer.stage("a"):
        time.sleep(0.001)
    assert timer.calls == {"a": 2, "b": 1}
    assert timer.total_ns["a"] >= 3_000_000 and timer.total_ns["b"] >= 1_000_000
    assert timer.take_view() == timer.total_ns
    assert timer.take_view() == {}


def test_a_stage_that_raises_still_counts_and_the_error_propagates() -> None:
    timer = StageTimer()
    with pytest.raises(KeyError), timer.stage("lookup"):
        raise KeyError("x")
    assert timer.calls == {"lookup": 1} and timer.total_ns["lookup"] > 0
