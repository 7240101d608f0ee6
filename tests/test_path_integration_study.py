"""The path-integration study (``albot2d.studies.path_integrations``): each local map placed
by path integration gets its cause, and each tracked surface lost its reason, from real
``Surfaces`` fed to a real ``Albot1``."""

from __future__ import annotations

import math

import numpy as np
import pytest

from albot2d.geometry import Pose
from albot2d.mapping import Albot1, Albot1Params
from albot2d.perception.surfaces import Surfaces
from albot2d.perception.tracking import TrackingParams
from albot2d.studies.path_integrations import (
    PathIntegrationWatcher,
    lost_reasons,
    main,
)


def _walls(n: int, slide_m: float = 0.0) -> Surfaces:
    """``n`` walls across the robot's path with real ends, each slid ``slide_m`` along
    itself (the same walls; their ends moved)."""
    segs = [[2.0 + 1.5 * k, -1.0 - 0.2 * k + slide_m, 2.0 + 1.5 * k, 1.0 + 0.2 * k + slide_m]
            for k in range(n)]  # fmt: skip
    return Surfaces(np.array(segs, float).reshape(-1, 4), np.zeros((n, 2), bool),
                    np.tile([0, 30], (n, 1)))  # fmt: skip


def _one(seg: list[float], occluded: tuple[bool, bool]) -> Surfaces:
    return Surfaces(np.array([seg], float), np.array([occluded]), np.array([[0, 30]]))


def _feed(params: Albot1Params, views: list[Surfaces]) -> tuple[Albot1, PathIntegrationWatcher]:
    m = Albot1(params)
    watcher = PathIntegrationWatcher(m)
    for k, view in enumerate(views):
        m.observe_view(k, float(k), view, Pose())
    return m, watcher


# five walls; the same two walls with their ends moved 0.7 m (none tracked, two trackable),
# twice; five moved walls, twice
LOST = [_walls(5), _walls(5), _walls(2, 0.7), _walls(2, 0.7), _walls(5, 0.7), _walls(5, 0.7)]


def test_causes_follow_the_reading_of_algorithm_4() -> None:
    m, watcher = _feed(Albot1Params.preset("paper_literal"), LOST)
    rows = watcher.breakdown()
    assert [(p.frame, p.cause, p.trackable, p.tracked_before) for p in rows] == [
        (2, "lost_tracking", 2, 5)]  # fmt: skip
    # view 1 was not remembered: the five walls tracked at view 1 are lost at view 2; the
    # two walls still in view are the same walls with their ends 0.7 m away
    reasons = [loss.reason for loss in rows[0].losses]
    assert reasons.count("end_moved") == 2 and reasons.count("out_of_view") == 3
    moved = [loss.end_moved_m for loss in rows[0].losses if loss.reason == "end_moved"]
    assert moved == pytest.approx([0.7, 0.7])
    lost_m, lost_w = _feed(Albot1Params.preset("paper_literal", move_using_pi="on_lost_tracking"),
                           LOST)  # fmt: skip
    assert [(p.frame, p.cause) for p in lost_w.breakdown()] == [
        (2, "lost_tracking"), (3, "pi_mode"), (4, "pi_mode_exit")]  # fmt: skip
    assert lost_m.counts().path_integrations == 3 and m.counts().path_integrations == 1


def test_a_view_with_no_trackable_surface_is_its_own_cause() -> None:
    views = [_walls(5), _walls(5), Surfaces.empty(), _walls(2), _walls(5)]
    _, watcher = _feed(Albot1Params.preset("paper_literal"), views)
    assert [(p.frame, p.cause) for p in watcher.breakdown()] == [
        (2, "no_trackable"), (3, "pi_mode"), (4, "pi_mode_exit")]  # fmt: skip


def test_lost_reasons_tell_where_the_wall_went() -> None:
    params = TrackingParams()
    predicted = _one([1.0, -1.0, 5.0, -1.0], (True, False))  # a side wall, far end real
    cases = {
        "end_moved": _one([0.5, -1.05, 6.2, -1.05], (True, False)),
        "no_shared_end": _one([0.5, -1.05, 6.2, -1.05], (False, True)),
        "not_trackable": _one([0.5, -1.05, 6.2, -1.05], (True, True)),
        "out_of_view": _one([1.0, 1.2, 5.0, 1.2], (True, False)),  # the other wall
    }
    for reason, view in cases.items():
        (loss,) = lost_reasons(predicted, view, params)
        assert loss.reason == reason
    (loss,) = lost_reasons(predicted, cases["end_moved"], params)
    assert loss.end_moved_m == pytest.approx(math.hypot(1.2, 0.05))
    # the beam meets the wall at its far end at atan(1 / 5) ≈ 11.3°: grazing
    assert loss.incidence_deg == pytest.approx(math.degrees(math.atan2(1.0, 5.0)), abs=0.01)


def test_an_end_at_a_split_point_is_told_from_a_walls_last_hit() -> None:
    # one straight wall extracted as two pieces that share beam 20: the split point counts
    # as a real end of each, though the wall goes on
    earlier = Surfaces(np.array([[1.0, -1.0, 3.0, -1.0], [3.0, -1.0, 5.0, -1.0]]),
                       np.array([[True, False], [False, True]]),
                       np.array([[0, 20], [20, 40]]))  # fmt: skip
    predicted = earlier.select(np.array([0]))
    view = _one([0.5, -1.05, 4.2, -1.05], (True, False))
    (loss,) = lost_reasons(predicted, view, TrackingParams(), earlier)
    assert loss.reason == "end_moved" and loss.split_end
    assert loss.end_moved_m == pytest.approx(math.hypot(1.2, 0.05))
    (alone,) = lost_reasons(predicted, view, TrackingParams())  # no view to tell it by
    assert not alone.split_end


def test_the_command_checks_its_seeds(capsys) -> None:  # type: ignore[no-untyped-def]
    assert main(["--seeds", "x"]) == 2
    assert "--seeds: expected A-B" in capsys.readouterr().out


@pytest.mark.slow
def test_one_route_is_broken_down_and_the_replay_agrees() -> None:
    from albot2d.studies.path_integrations import route_breakdown

    r = route_breakdown(5, "dataset1", "paper_literal")  # the replay is checked inside
    assert r.views > 1000 and 0 < r.local_maps < r.views
    assert sum(r.causes().values()) == len(r.path_integrations)
