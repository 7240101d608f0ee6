"""Algorithm #5 checked both ways (albot2d.evaluation.checks.deletion_partition): on real runs
every deletion reading deletes exactly what its rule says; an update that deletes too
much or too little is caught, by the check and by a fuzzing campaign's episode."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from albot2d.errors import InvariantError
from albot2d.evaluation.checks import deletion_partition as dp
from albot2d.evaluation.checks.invariants import UpdateRecorder
from albot2d.evaluation.fuzz.campaign import CampaignParams
from albot2d.evaluation.fuzz.episode import EpisodeSpec, run_episode
from albot2d.frames import Frame
from albot2d.geometry import Pose
from albot2d.mapping import Albot1, Albot1Params
from albot2d.mapping.albot1.deletion import DELETION_PRESETS, GlobalMapParams
from albot2d.mapping.albot1.global_map import GlobalMap
from albot2d.mapping.protocol import MapSnapshot
from tests.plants import OverDeletingMap, UnderDeletingMap
from tests.runs import map_frames, simulate
from worldgen.generate import generate

READINGS = {
    **{name: GlobalMapParams.preset(name) for name in DELETION_PRESETS},
    "touch_contiguous": GlobalMapParams(current_map="touch", expand="contiguous"),
    "in_range_midpoint": GlobalMapParams(could_see="in_range", facing_test="midpoint"),
    "half_share_none": GlobalMapParams(min_visible_share=0.5, expand="none"),
    "all_round_any": GlobalMapParams(
        enlarge="all_round", facing_test="any_endpoint", current_in_group=False
    ),
    "gap_3_keep_if_all": GlobalMapParams(group_gap_maps=3, keep_if_all=True, seen_side="any"),
}


@pytest.fixture(scope="module")
def frames() -> list[Frame]:
    world = generate("rooms", seed=4, width_m=14.0, height_m=12.0)
    return simulate(world, 4)


def _mapper(params: GlobalMapParams, map_class: type[GlobalMap] = GlobalMap) -> Albot1:
    m = Albot1(Albot1Params(global_map=params))
    m.map = map_class(params)
    return m


@pytest.mark.parametrize("reading", list(READINGS))
def test_every_reading_deletes_exactly_what_its_rule_says(frames, reading: str) -> None:  # type: ignore[no-untyped-def]
    m = _mapper(READINGS[reading])
    recorder = UpdateRecorder().attach(m)  # raises at the first wrong update
    map_frames(m, frames)
    assert recorder.updates == len(m.route) > 40
    deleted = sum(u.deleted_current + u.deleted_older for u in m.update_log)
    assert deleted > 0, reading  # every reading deletes something on this run


@pytest.mark.parametrize(
    ("map_class", "message"),
    [(OverDeletingMap, "deleted that the rule keeps"), (UnderDeletingMap, "kept that the rule")],
)
def test_an_update_deleting_too_much_or_too_little_is_caught(frames, map_class, message) -> None:  # type: ignore[no-untyped-def]
    m = _mapper(GlobalMapParams(), map_class)
    UpdateRecorder().attach(m)
    with pytest.raises(InvariantError, match=f"update_deletes_facing_overlap: .*{message}"):
        map_frames(m, frames)


def test_the_fuzz_campaign_catches_an_over_deleting_mapper() -> None:
    """A user's mapper (``module:Class``) whose updates delete every older surface: its
    fuzzing episode reports update_deletes_facing_overlap, with the direction named."""
    campaign = CampaignParams(
        episodes=1, seed=5, kinds=("rooms",), mapper="tests.plants:OverDeletingAlbot1",
        world_size_min_m=12.0, world_size_max_m=14.0, tour_length_min_m=15.0,
        tour_length_max_m=15.0,
    )  # fmt: skip
    record = run_episode(EpisodeSpec.draw(campaign, 0)).record
    assert record.status == "violation"
    messages = record.violations["update_deletes_facing_overlap"]
    assert any("deleted that the rule keeps" in msg for msg in messages)
    # The same episode with Albot1 as it is passes the invariant.
    plain = run_episode(EpisodeSpec.draw(dataclasses.replace(campaign, mapper="albot1"), 0))
    assert "update_deletes_facing_overlap" in plain.record.checked
    assert "update_deletes_facing_overlap" not in plain.record.violations


# -- the definition's parts, by hand ---------------------------------------------------------
def test_expand_groups_by_hand() -> None:
    existing = set(range(40))
    assert dp.expand_groups([25, 28], "split", 20, existing) == set(range(25, 29))
    assert dp.expand_groups([2, 3, 30], "split", 20, existing) == {2, 3, 30}
    assert dp.expand_groups([2, 30], "contiguous", 20, existing) == set(range(2, 31))
    assert dp.expand_groups([2, 30], "none", 20, existing) == {2, 30}
    assert dp.expand_groups([2, 5], "split", 3, existing - {4}) == {2, 3, 5}
    assert dp.expand_groups([], "split", 20, existing) == set()


def test_a_wall_seen_again_is_deleted_and_one_behind_the_robot_kept() -> None:
    """Map 0 holds the wall 5 m ahead and one 3 m behind; map 1 (the current one) sees
    nothing; the view of map 2 is the wall ahead again. The rule deletes the old copy of
    the wall ahead (in view, facing, seen from its front, all visible) and keeps the one
    behind; a map that deletes either way wrongly is caught."""
    wall = np.array([[5.0, -2.0, 5.0, 2.0]])
    behind = np.array([[-3.0, 2.0, -3.0, -2.0]])
    before = MapSnapshot(np.vstack([wall, behind]), np.array([0, 0]))
    want = dp.expected_deletions(
        before.segments, before.map_ids, wall, Pose(), 1, GlobalMapParams(), {0, 1}
    )
    assert want.tolist() == [True, False]
    right = MapSnapshot(np.vstack([behind, wall]), np.array([0, 2]))
    dp.check_update_partition(before, right, 3, 2, Pose(), wall, GlobalMapParams(), {0, 1})
    kept_all = MapSnapshot(np.vstack([wall, behind, wall]), np.array([0, 0, 2]))
    with pytest.raises(InvariantError, match=r"1 surface.* kept that the rule deletes"):
        dp.check_update_partition(before, kept_all, 3, 2, Pose(), wall, GlobalMapParams(), {0, 1})
    emptied = MapSnapshot(wall, np.array([2]))
    with pytest.raises(InvariantError, match=r"1 surface.* deleted that the rule keeps"):
        dp.check_update_partition(before, emptied, 3, 2, Pose(), wall, GlobalMapParams(), {0, 1})
    moved = MapSnapshot(np.vstack([behind + 0.01, wall]), np.array([0, 2]))
    with pytest.raises(InvariantError, match="moved or changed"):
        dp.check_update_partition(before, moved, 3, 2, Pose(), wall, GlobalMapParams(), {0, 1})
