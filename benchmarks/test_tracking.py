"""RTSV per view: the matching's numpy path and compiled kernel side by side, and RTSV whole.

Run: ``python -m pytest benchmarks/test_tracking.py --benchmark-only --benchmark-group-by=group``.
The inputs are the tracked sets and views of 400 views of a simulated office run (a few
tracked and a few candidate surfaces each, as in a real run); one round matches them all.
"""

from __future__ import annotations

import itertools

import pytest

from albot2d.perception import extract_surfaces
from albot2d.perception.tracking import match_surfaces, rtsv, start_tracking, trackable_mask


@pytest.fixture(scope="module")
def rtsv_inputs():  # type: ignore[no-untyped-def]
    from albot2d.evaluation.run.setup import RunSpec, build_run

    run = build_run(RunSpec(tour_length_m=60.0))
    frames = run.simulator.drive(run.tour, run.profile)
    out, tracked, prev = [], None, None
    for frame in itertools.islice(frames, 400):
        view = extract_surfaces(frame.scan)
        if tracked is None or len(tracked) < 2:
            tracked = start_tracking(view)
        else:
            increment = prev.between(frame.odom_pose)
            out.append((tracked, view, increment))
            tracked, _ = rtsv(tracked, view, increment)
        prev = frame.odom_pose
    return out


@pytest.mark.benchmark(group="rtsv matching (400 views)")
@pytest.mark.parametrize("backend", ["numpy", "numba"])
def test_match_surfaces(benchmark, rtsv_inputs, backend: str) -> None:  # type: ignore[no-untyped-def]
    if backend == "numba":
        pytest.importorskip("numba")
    pairs = [(t.current.transformed(inc.inverse().as_array()), v, trackable_mask(v))
             for t, v, inc in rtsv_inputs]  # fmt: skip
    match_surfaces(*pairs[0][:2], None, pairs[0][2], backend=backend)  # compile / load first

    def run() -> int:
        return sum(len(match_surfaces(p, v, None, c, backend=backend)[0]) for p, v, c in pairs)

    assert benchmark(run) > 100


@pytest.mark.benchmark(group="rtsv whole (400 views)")
def test_rtsv(benchmark, rtsv_inputs) -> None:  # type: ignore[no-untyped-def]
    def run() -> int:
        return sum(len(rtsv(t, v, inc)[0]) for t, v, inc in rtsv_inputs)

    assert benchmark(run) > 100


@pytest.fixture(scope="module")
def triangulations():  # type: ignore[no-untyped-def]
    """Albot1's triangulate calls over the first 1,500 views of the default run."""
    from albot2d.evaluation.run.setup import RunSpec, build_run
    from albot2d.mapping import Albot1

    calls = []
    real = __import__("albot2d.mapping.albot1.mapper", fromlist=["triangulate"]).triangulate

    def record(*args, **kwargs):  # type: ignore[no-untyped-def]
        calls.append((args, kwargs))
        return real(*args, **kwargs)

    run = build_run(RunSpec())
    m = Albot1()
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr("albot2d.mapping.albot1.mapper.triangulate", record)
        for frame in itertools.islice(run.simulator.drive(run.tour, run.profile), 1500):
            m.observe(frame)
    return calls


@pytest.mark.benchmark(group="triangulation (Albot1's calls, 1,500 views)")
@pytest.mark.parametrize("path", ["scalar", "array"])
def test_triangulate(benchmark, triangulations, path: str) -> None:  # type: ignore[no-untyped-def]
    """The scalar path for fewer than 8 surfaces against the array path, side by side."""
    import albot2d.mapping.albot1.triangulation as tri

    with pytest.MonkeyPatch.context() as mp:
        if path == "array":
            mp.setattr(tri, "_SMALL", 0)

        def run() -> int:
            return sum(tri.triangulate(*a, **k) is not None for a, k in triangulations)

        assert benchmark(run) > 100
