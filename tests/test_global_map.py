"""Algorithm #5 on constructed maps whose answer is known, and the grid index."""

from __future__ import annotations

import numpy as np
import shapely
from hypothesis import given
from hypothesis import strategies as st

from albot2d.geometry import Pose
from albot2d.mapping.global_map import GlobalMap, GlobalMapParams, view_polygon
from albot2d.mapping.spatial_index import SegmentGridIndex


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


def test_update_deletes_exactly_the_expected_surfaces() -> None:
    g = build_maps_25_to_29()
    # Incoming view 30 from the origin facing +x: a wall 5 m ahead spanning y in [-2, 2].
    incoming = np.array([[5.0, -2.0, 5.0, 2.0]])
    report = g.add_view(incoming, 30, Pose(0.0, 0.0, 0.0))
    assert report.deleted_current == 1  # (1, .5)-(2, .5) of map 29
    assert report.affected_maps == (25, 28)
    assert report.group == (25, 26, 27, 28)
    # Facing side of maps 25..28: the four "ahead" surfaces (26 and 27 ones are far but ahead).
    assert report.deleted_older == 4
    snap = g.snapshot()
    kept = {(int(m), tuple(s)) for s, m in zip(snap.segments.tolist(), snap.map_ids, strict=True)}
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
    assert kept == expected


def test_without_expand_only_affected_maps_lose_surfaces() -> None:
    g = build_maps_25_to_29(GlobalMapParams(expand_group=False))
    report = g.add_view(np.array([[5.0, -2.0, 5.0, 2.0]]), 30, Pose())
    assert report.group == (25, 28)
    assert report.deleted_older == 2


def test_history_snapshots_replay_the_evolution() -> None:
    g = build_maps_25_to_29()
    before = g.snapshot()
    g.add_view(np.array([[5.0, -2.0, 5.0, 2.0]]), 30, Pose())
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
    st.lists(
        st.tuples(*[st.floats(-50, 50) for _ in range(4)]), min_size=1, max_size=60
    ),
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
