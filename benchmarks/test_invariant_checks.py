"""The deletion invariant's cost per global-map update: the ordered check (cheap tests
first, compiled prefilter when numba imports) against the definition asked in full (every
older surface against P, then facing, seen side and shapely's sight lines, vectorised: the
check as it was before issue 12's last round, without its bounding-box prefilter for P), on
the same recorded updates of a real Albot₁ run.

Run: ``python -m pytest benchmarks/test_invariant_checks.py --benchmark-only
--benchmark-group-by=group``. Both give the same verdicts (``tests/test_deletion_invariant.py``);
the ``ordered`` rows' ``extra_info`` holds their speed-up over ``definition``.
"""

from __future__ import annotations

import types
from typing import Any

import numpy as np
import pytest

from albot2d.evaluation.checks import deletion as di
from albot2d.geometry import transform_segments
from albot2d.mapping import Albot1, UpdateReport
from albot2d.mapping.albot1.route_map import LocalMap
from tests.runs import map_frames, simulate
from tests.test_deletion_invariant import _reference
from worldgen.generate import generate

_seconds: dict[str, float] = {}


@pytest.fixture(scope="module")
def updates() -> list[tuple[Any, ...]]:
    """Every update of an office run as (mapper stand-in, report, pose, view): the map as
    it was right after that update (its snapshot), so the checks can be asked again."""
    frames = simulate(generate("office", seed=3, width_m=30.0, height_m=24.0), 3, length_m=60.0)
    mapper = Albot1()
    out: list[tuple[Any, ...]] = []

    def on_update(report: UpdateReport, lm: LocalMap) -> None:
        snap = mapper.map.snapshot()
        stand_in = types.SimpleNamespace(
            map=types.SimpleNamespace(params=mapper.map.params, snapshot=lambda s=snap: s)
        )
        view = transform_segments(lm.pose.as_array(), lm.view.segments)
        out.append((stand_in, report, lm.pose, view))

    mapper.on_update = on_update
    map_frames(mapper, frames)
    return out


@pytest.mark.parametrize("how", ["definition", "ordered_numpy", "ordered"])
@pytest.mark.benchmark(group="deletion-invariant-per-run")
def test_deletion_invariant_per_run(
    benchmark: Any, updates: list[Any], how: str, monkeypatch
) -> None:  # type: ignore[no-untyped-def]
    if how == "ordered_numpy":  # as without numba
        monkeypatch.setattr(di, "_kernels", lambda: None)

    def check_all() -> int:
        failed = 0
        for m, report, pose, view in updates:
            if how == "definition":
                failed += _reference(m, report, pose, view) is not None
            else:
                try:
                    di.check_update_deleted_facing_overlap(m, report, pose, view)
                except di.InvariantError:
                    failed += 1
        return failed

    assert benchmark.pedantic(check_all, rounds=3, iterations=1, warmup_rounds=1) == 0
    _seconds[how] = benchmark.stats.stats.min
    benchmark.extra_info["updates"] = len(updates)
    benchmark.extra_info["us_per_update"] = 1e6 * _seconds[how] / len(updates)
    if how != "definition" and "definition" in _seconds:
        benchmark.extra_info["speedup"] = _seconds["definition"] / _seconds[how]
        print(f"\n{how}: {_seconds['definition'] / _seconds[how]:.1f}× the definition "
              f"({1e6 * _seconds[how] / len(updates):.0f} µs per update)")  # fmt: skip
    assert np.isfinite(_seconds[how])
