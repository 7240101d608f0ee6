"""What a run keeps, kept compactly (issue 12, memory): the naive and truth maps as
blocks of plain arrays (``IntegratedMap``) giving the same answers as the ``GlobalMap``
they replaced, their poses flat (``PoseLog``), a stop's egocentric map read block by block,
region labels in blocks, and figures freed once saved."""

from __future__ import annotations

import numpy as np
import pytest

from albot2d.evaluation.metrics import updates
from albot2d.evaluation.metrics.egocentric import in_robot_frame
from albot2d.evaluation.run import trace as trace_module
from albot2d.evaluation.run.setup import RunSpec, build_run, build_world
from albot2d.mapping import baselines
from albot2d.mapping.albot1.global_map import GlobalMap
from albot2d.mapping.baselines import IntegratedMap, NaiveIntegration, PoseLog


def _views(seed: int, n: int) -> list[np.ndarray]:
    rng = np.random.default_rng(seed)
    return [rng.normal(0.0, 5.0, (int(rng.integers(0, 9)), 4)) for _ in range(n)]


@pytest.mark.parametrize("block", [3, 8, 1 << 15])
def test_integrated_map_answers_as_global_map_insert(
    monkeypatch: pytest.MonkeyPatch, block: int
) -> None:
    monkeypatch.setattr(baselines, "_BLOCK_SURFACES", block)  # views straddle blocks
    views = _views(1, 40)
    ours, theirs = IntegratedMap(), GlobalMap()
    for map_id, view in enumerate(views, start=1):
        ours.insert(view, map_id)
        theirs.insert(view, map_id)
        assert len(ours) == len(theirs)
    assert ours.n_updates == theirs.n_updates and ours.last_map_id == theirs.last_map_id
    for at in [None, -1, 0, 1, 2, 7, 20, 39, 40, 41, 1000]:
        a, b = ours.snapshot(at), theirs.snapshot(at)
        assert a.segments.dtype == b.segments.dtype and a.map_ids.dtype == b.map_ids.dtype
        assert np.array_equal(a.segments, b.segments), at
        assert np.array_equal(a.map_ids, b.map_ids), at
    stored = list(ours.blocks())
    assert sum(len(ids) for _, ids in stored) == len(ours)
    assert np.array_equal(np.vstack([s for s, _ in stored]), theirs.snapshot().segments)
    with pytest.raises(ValueError, match="map ids must increase"):
        ours.insert(views[0], 3)


def test_empty_integrated_map() -> None:
    m = IntegratedMap()
    snap = m.snapshot()
    assert snap.segments.shape == (0, 4) and snap.map_ids.shape == (0,)
    assert len(m) == 0 and list(m.blocks()) == []


def test_pose_log_keeps_every_pose_exactly() -> None:
    rng = np.random.default_rng(2)
    poses = rng.normal(0.0, 3.0, (50, 3))
    log = PoseLog()
    for p in poses:
        log.append(p)
    assert len(log) == 50
    assert np.array_equal(log.as_array(), poses)
    assert np.array_equal(log.last(), poses[-1])
    assert PoseLog().as_array().shape == (0, 3)


def test_naive_mapper_on_real_frames_keeps_its_outputs(monkeypatch: pytest.MonkeyPatch) -> None:
    """The naive mapper over simulated frames, with tiny storage blocks: map, trajectory,
    pose and the stop's egocentric map as with one block (and as a GlobalMap would)."""
    setup = build_run(RunSpec(tour_length_m=15.0))
    frames = list(setup.simulator.drive(setup.tour, setup.profile))[:120]
    outs = []
    for block in (5, 1 << 15):
        monkeypatch.setattr(baselines, "_BLOCK_SURFACES", block)
        naive, reference = NaiveIntegration(), GlobalMap()
        for k, frame in enumerate(frames, start=1):
            naive.observe(frame)
            view = naive.global_map().segments[len(reference) :]
            reference.insert(view, k)
        seen = np.array([[1.0, 0.5], [3.0, -2.0], [-4.0, 1.0]])
        local, count = trace_module._egocentric_map(naive, seen)
        reach = float(np.max(np.hypot(seen[:, 0], seen[:, 1]))) + 1.0  # as _egocentric_map
        whole = in_robot_frame(naive.pose().as_array(), reference.snapshot().segments, reach)
        assert count == len(reference)
        assert np.array_equal(local, whole)
        assert np.array_equal(naive.global_map().segments, reference.snapshot().segments)
        outs.append((naive.trajectory(), naive.global_map(), naive.global_map(at_update=60)))
    (t1, m1, h1), (t2, m2, h2) = outs
    assert len(t1) == len(frames) and np.array_equal(t1, t2)
    assert np.array_equal(m1.segments, m2.segments) and np.array_equal(m1.map_ids, m2.map_ids)
    assert np.array_equal(h1.segments, h2.segments) and h1.map_ids.max() == 60


def test_region_labels_in_blocks_match_one_call(monkeypatch: pytest.MonkeyPatch) -> None:
    from worldgen import regions

    world = build_world(RunSpec())
    rng = np.random.default_rng(3)
    xy = rng.uniform([0.0, 0.0], [world.width_m, world.height_m], (150, 2))
    monkeypatch.setattr(regions, "_BLOCK_POINTS", 7)  # the isovists in blocks of 7 points
    got = updates.region_labels(world, xy)
    monkeypatch.setattr(regions, "_BLOCK_POINTS", 1 << 20)  # all points in one block
    assert got.dtype == np.dtype("<U8")
    assert np.array_equal(got, regions.region_kind_at(world, xy))
    assert set(got) > {"outside"}  # some positions are inside: labels were computed


def test_png_bytes_frees_the_figure_and_draws_the_same() -> None:
    pytest.importorskip("matplotlib")
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    from albot2d.viz._figure import new_figure, png_bytes

    def figure():  # type: ignore[no-untyped-def]
        fig = new_figure(3.0, 2.0)
        ax = fig.subplots()
        ax.plot([0, 1, 2], [0, 1, 0])
        ax.set_title("x")
        return fig

    kept, freed = figure(), figure()
    a = png_bytes(kept, 50, release=False)
    b = png_bytes(freed, 50)
    assert a == b
    assert isinstance(kept.canvas, FigureCanvasAgg) and kept.axes
    assert not isinstance(freed.canvas, FigureCanvasAgg) and not freed.axes


def test_figure_batch_collects_each_figure_and_unfreezes() -> None:
    pytest.importorskip("matplotlib")
    import gc
    import weakref

    from albot2d.viz._figure import figure_batch, new_figure, png_bytes

    frozen = gc.get_freeze_count()
    with figure_batch():
        assert gc.get_freeze_count() > frozen
        fig = new_figure(2.0, 2.0)
        gone = weakref.ref(fig.subplots())
        gone().plot([0, 1], [1, 0])  # type: ignore[union-attr]
        png_bytes(fig, 40)
        assert gone() is None  # the released axes (a web of cycles) collected already
    assert gc.get_freeze_count() == frozen
