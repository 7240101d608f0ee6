"""Algorithm #5 on constructed maps whose answer is known, and the grid index."""

from __future__ import annotations

import numpy as np
import pytest
import shapely
from hypothesis import given
from hypothesis import strategies as st

from albot2d.errors import InputError
from albot2d.geometry import Pose
from albot2d.geometry.spatial_index import SegmentGridIndex
from albot2d.mapping.albot1.deletion import group_maps
from albot2d.mapping.albot1.global_map import GlobalMap, GlobalMapParams, view_polygon


def seg(x0: float, y0: float, x1: float, y1: float) -> np.ndarray:
    return np.array([[x0, y0, x1, y1]], dtype=float)


def build_maps_25_to_29(params: GlobalMapParams | None = None) -> GlobalMap:
    """Maps 24..29 laid out along x; each has one surface ahead (+x) and one behind (-x)
    of a robot at the origin facing +x."""
    g = GlobalMap(params or GlobalMapParams())
    layout = {
        24: [seg(30, 10, 31, 10), seg(-30, 10, -31, 10)],  # far away: must never be touched
        25: [seg(3, 1.0, 4, 1.0), seg(-5, 5, -6, 5)],  # ahead surface is inside the view
        26: [seg(20, -8, 21, -8), seg(-8, -8, -9, -8)],  # nowhere near the view
        27: [seg(25, 8, 26, 8), seg(-12, 0, -13, 0)],
        28: [seg(3, -1.0, 4, -1.0), seg(-7, 7, -8, 7)],  # ahead surface is inside the view
        29: [seg(1, 0.5, 2, 0.5), seg(40, 40, 41, 40)],  # current map: one in, one out
    }
    for mid, segs in layout.items():
        g.insert(np.vstack(segs), mid)
    return g


def _kept(g: GlobalMap) -> set[tuple[int, tuple[float, ...]]]:
    snap = g.snapshot()
    return {(int(m), tuple(s)) for s, m in zip(snap.segments.tolist(), snap.map_ids, strict=True)}


INCOMING = np.array([[5.0, -2.0, 5.0, 2.0]])  # a wall 5 m ahead of a robot at the origin


def test_v1_rule_deletes_the_contiguous_group_on_the_facing_half_plane() -> None:
    g = build_maps_25_to_29(GlobalMapParams.preset("v1"))
    report = g.add_view(INCOMING, 30, Pose(0.0, 0.0, 0.0))
    assert report.deleted_current == 1  # (1, .5)-(2, .5) of map 29
    assert report.affected_maps == (25, 28)
    assert report.group == (25, 26, 27, 28)
    # Facing side of maps 25..28: the four "ahead" surfaces (26 and 27 ones are far but ahead).
    assert report.deleted_older == 4
    expected = {
        (24, (30.0, 10.0, 31.0, 10.0)),
        (24, (-30.0, 10.0, -31.0, 10.0)),
        (25, (-5.0, 5.0, -6.0, 5.0)),
        (26, (-8.0, -8.0, -9.0, -8.0)),
        (27, (-12.0, 0.0, -13.0, 0.0)),
        (28, (-7.0, 7.0, -8.0, 7.0)),
        (29, (40.0, 40.0, 41.0, 40.0)),
        (30, (5.0, -2.0, 5.0, 2.0)),
    }
    assert _kept(g) == expected


def test_paper_rule_deletes_only_what_the_robot_could_see() -> None:
    g = build_maps_25_to_29(GlobalMapParams.preset("paper"))
    report = g.add_view(INCOMING, 30, Pose(0.0, 0.0, 0.0))
    assert report.deleted_current == 1
    assert report.affected_maps == (25, 28, 29)  # the current map joins the group
    assert report.group == (25, 26, 27, 28, 29)
    # Only the two older surfaces inside the view: 26's and 27's are ahead but not in view.
    assert report.deleted_older == 2
    removed = {(25, (3.0, 1.0, 4.0, 1.0)), (28, (3.0, -1.0, 4.0, -1.0)),
               (29, (1.0, 0.5, 2.0, 0.5))}  # fmt: skip
    assert not removed & _kept(g)
    assert len(_kept(g)) == 12 - 3 + 1


def test_original_rule_deletes_group_members_in_front_even_out_of_view() -> None:
    g = build_maps_25_to_29(GlobalMapParams.preset("original"))
    report = g.add_view(INCOMING, 30, Pose(0.0, 0.0, 0.0))
    assert report.group == (25, 26, 27, 28, 29)
    assert report.deleted_current == 1
    assert report.deleted_older == 4


def test_paper_rule_keeps_surfaces_behind_or_straddling_the_robot() -> None:
    """A side wall of the map being left that reaches behind the robot stays (v1 deletes it:
    its polygon is buffered behind the robot and the current map goes whole on touch)."""
    side_wall = seg(-3.0, 1.0, 2.0, 1.0)  # from 3 m behind to 2 m ahead, 1 m to the left
    behind = seg(-0.2, -0.3, -2.0, -0.3)  # entirely behind, within 0.5 m of the viewpoint
    view = np.array([[3.0, -1.0, 3.0, 1.0]])
    for rule, survivors in (("paper", 2), ("v1", 0)):
        g = GlobalMap(GlobalMapParams.preset(rule))
        g.insert(np.vstack([side_wall, behind]), 0)
        report = g.add_view(view, 1, Pose())
        assert report.deleted_current == 2 - survivors, rule
        assert len(g) == survivors + 1, rule


def test_forward_enlargement_adds_nothing_behind_the_robot() -> None:
    segs = np.array([[2.0, -1.0, 2.0, 1.0]])
    forward = view_polygon(segs, Pose(), 0.5, "forward")
    all_round = view_polygon(segs, Pose(), 0.5, "all_round")
    assert all_round.contains(shapely.Point(-0.3, 0.0))
    assert not forward.contains(shapely.Point(-0.3, 0.0))
    assert forward.contains(shapely.Point(2.4, 0.0)) and forward.contains(shapely.Point(1.0, 0.8))
    # Rotated robot: "behind" turns with it.
    turned = view_polygon(np.array([[-1.0, 2.0, 1.0, 2.0]]), Pose(0, 0, np.pi / 2), 0.5)
    assert turned.contains(shapely.Point(0.0, 2.4))
    assert not turned.contains(shapely.Point(0.0, -0.3))


def test_radial_enlargement_pushes_vertices_out_from_the_viewpoint() -> None:
    poly = view_polygon(np.array([[2.0, -1.0, 2.0, 1.0]]), Pose(), 0.3, "radial")
    assert poly.contains(shapely.Point(2.2, 0.0))
    assert not poly.contains(shapely.Point(2.5, 0.0))
    assert not poly.contains(shapely.Point(-0.1, 0.0))


def test_groups_split_where_map_ids_jump() -> None:
    existing = set(range(200))
    assert group_maps((3, 10, 40, 45), "split", 20, existing) == (*range(3, 11), *range(40, 46))
    assert group_maps((3, 10, 40, 45), "contiguous", 20, existing) == tuple(range(3, 46))
    assert group_maps((3, 10, 40, 45), "none", 20, existing) == (3, 10, 40, 45)
    assert group_maps((3, 23, 44), "split", 20, existing) == (*range(3, 24), 44)
    assert group_maps((), "split", 20, existing) == ()


def test_a_revisit_deletes_only_the_group_near_the_revisited_maps() -> None:
    """Maps 0–4 at a place, 5–59 elsewhere, then the robot returns: the 'contiguous' Expand
    deletes the facing surfaces of every map in between; 'split' only those of 0–4."""

    def build(params: GlobalMapParams) -> GlobalMap:
        g = GlobalMap(params)
        for m in range(5):
            g.insert(seg(3.0, -1.0 + 0.3 * m, 4.0, -1.0 + 0.3 * m), m)
        for m in range(5, 59):
            g.insert(seg(10.0 + m, 20.0, 10.5 + m, 20.0), m)  # ahead of the robot, far off
        g.insert(seg(2.0, -0.5, 2.5, -0.5), 59)  # the map being left, in view
        return g

    for expand, lost_far in (("contiguous", 54), ("split", 0)):
        g = build(GlobalMapParams.preset("paper", could_see="half_plane", expand=expand))
        report = g.add_view(INCOMING, 60, Pose())
        far = g.snapshot().map_ids
        assert 54 - int(np.count_nonzero((far >= 5) & (far < 59))) == lost_far, expand
        assert report.deleted_current == 1 and report.deleted_older >= 5, expand


def test_keep_if_all_deletes_nothing_when_everything_would_go() -> None:
    g = GlobalMap(GlobalMapParams.preset("original"))
    g.insert(seg(3.0, -0.5, 3.0, 0.5), 0)
    report = g.add_view(INCOMING, 1, Pose())
    assert report.deleted_current == 0 and len(g) == 2
    g2 = GlobalMap(GlobalMapParams.preset("original", keep_if_all=False))
    g2.insert(seg(3.0, -0.5, 3.0, 0.5), 0)
    assert g2.add_view(INCOMING, 1, Pose()).deleted_current == 1


def test_forward_ray_touches_what_lies_across_the_heading() -> None:
    far_wall = seg(2.8, -0.2, 2.8, 0.2)  # across the heading, outside a view closed at 1 m
    view = np.array([[1.0, -3.0, 1.0, -2.0], [1.0, 2.0, 1.0, 3.0]])
    for ray, deleted in ((0.0, 0), (3.0, 1)):
        g = GlobalMap(
            GlobalMapParams.preset(
                "paper", enlarge_m=0.0, forward_ray_m=ray, include_viewpoint=False
            )
        )
        g.insert(far_wall, 0)
        assert g.add_view(view, 1, Pose()).deleted_current == deleted


def test_unknown_rule_names_are_refused_with_the_valid_ones() -> None:
    with pytest.raises(InputError, match="valid: visible, paper, v1, original"):
        GlobalMapParams.preset("papr")
    with pytest.raises(InputError, match="could_see must be one of"):
        GlobalMapParams(could_see="maybe")  # type: ignore[arg-type]


def test_history_snapshots_replay_the_evolution() -> None:
    g = build_maps_25_to_29(GlobalMapParams.preset("v1"))
    before = g.snapshot()
    g.add_view(INCOMING, 30, Pose())
    after = g.snapshot()
    assert len(before.segments) == 12 and len(after.segments) == 8
    np.testing.assert_array_equal(g.snapshot(at_update=6).segments, before.segments)
    np.testing.assert_array_equal(g.snapshot(at_update=7).segments, after.segments)
    assert len(g.snapshot(at_update=1).segments) == 2


def test_view_polygon_is_enlarged_view_area() -> None:
    segs = np.array([[2.0, -1.0, 2.0, 1.0]])
    poly = view_polygon(segs, Pose(), 0.5)
    assert poly.contains(shapely.Point(1.0, 0.0))  # between robot and wall
    assert poly.contains(shapely.Point(2.4, 0.0))  # just behind the wall, within 0.5 m
    assert not poly.contains(shapely.Point(2.6, 0.0))


@given(
    st.lists(st.tuples(*[st.floats(-50, 50) for _ in range(4)]), min_size=1, max_size=60),
    st.tuples(st.floats(-60, 60), st.floats(-60, 60), st.floats(0.1, 30), st.floats(0.1, 30)),
    st.floats(0.3, 7.0),
)
def test_grid_index_returns_a_superset_of_box_hits(segments, box, cell) -> None:  # type: ignore[no-untyped-def]
    segs = np.asarray(segments, dtype=float)
    idx = SegmentGridIndex(cell)
    idx.insert(np.arange(len(segs)), segs)
    x, y, w, h = box
    found = set(idx.query_box(x, y, x + w, y + h).tolist())
    lines = shapely.linestrings(segs.reshape(-1, 2, 2))
    truth = set(np.flatnonzero(shapely.intersects(shapely.box(x, y, x + w, y + h), lines)))
    assert truth <= found


def test_a_revisit_deletes_old_surfaces_in_view_and_rebuilds_them() -> None:
    """Fig. 10 on a constructed loop: map 0 sees a wall ahead from the start; maps 1–39 are
    along the rest of a loop far away; map 40, back at the start and facing the same way,
    deletes map 0's wall (it is in view) and puts its own in its place, while the walls of
    the rest of the loop (out of view) stay."""
    g = GlobalMap()
    start_wall = np.array([[4.0, -1.0, 4.0, 1.0]])
    g.add_view(start_wall, 0, Pose())
    for m in range(1, 40):
        g.add_view(np.array([[10.0 + m, 30.0, 10.5 + m, 30.0]]), m, Pose(10.0 + m, 28.0, 0.0))
    assert len(g) == 40
    rebuilt = start_wall + np.array([0.05, 0.0, 0.05, 0.0])  # seen again, slightly off
    report = g.add_view(rebuilt, 40, Pose(0.02, 0.0, 0.0))
    assert report.affected_maps == (0,)
    assert report.deleted_older == 1
    snap = g.snapshot()
    assert 0 not in snap.map_ids.tolist() and len(g) == 40
    np.testing.assert_array_equal(snap.segments[snap.map_ids == 40], rebuilt)
    # The history still has the map before the revisit (the "before" panel of Fig. 10).
    assert 0 in g.snapshot(at_update=40).map_ids.tolist()


@given(
    st.integers(0, 50),
    st.integers(1, 120),
    st.lists(st.integers(0, 200), max_size=12, unique=True),
    st.sampled_from(["split", "contiguous", "none"]),
)
def test_groups_over_a_range_of_ids_are_those_over_the_set(
    first: int, count: int, picks: list[int], rule: str
) -> None:
    """The global map passes its ids as a range while they are consecutive: the same groups
    as the set of those ids, affected ids outside it included."""
    ids = range(first, first + count)
    affected = tuple(sorted(picks))
    assert group_maps(affected, rule, 20, ids) == group_maps(affected, rule, 20, set(ids))  # type: ignore[arg-type]


def test_updates_group_the_same_with_consecutive_and_gapped_map_ids() -> None:
    """Map ids 0–9 (a range inside) against 0–8 then 20 (a dict inside): the same groups
    where the ids agree, and no id that was never added."""
    views = [np.array([[float(k), 1.0, float(k) + 0.8, 1.0]]) for k in range(10)]
    dense, gapped = (
        GlobalMap(GlobalMapParams(expand="contiguous")),
        GlobalMap(GlobalMapParams(expand="contiguous")),
    )
    for k, v in enumerate(views[:-1]):
        dense.insert(v, k)
        gapped.insert(v, k)
    dense.insert(views[-1], 9)
    gapped.insert(views[-1], 20)
    assert isinstance(dense._ids, range) and dense._ids == range(10)
    assert gapped._ids is gapped._by_map
    robot = Pose(4.5, -1.0, np.pi / 2)
    seen = np.array([[0.0, 1.0, 9.0, 1.0]])  # sees every map's surface ahead
    a, b = dense.add_view(seen, 30, robot), gapped.add_view(seen, 30, robot)
    assert a.affected_maps == tuple(range(10)) and a.group == tuple(range(10))
    assert b.affected_maps == (*range(9), 20) and b.group == (*range(9), 20)
    assert dense._ids is dense._by_map  # 30 after 9: no longer consecutive
