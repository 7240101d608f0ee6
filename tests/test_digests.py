"""Behaviour unchanged: three short runs' outputs against the digests stored in the repo.

See ``tests/digests.py`` for what is run and compared; after a deliberate change of
behaviour, ``python -m tests.digests --update`` rewrites ``tests/digests.json``.
"""

from __future__ import annotations

import pytest

from tests import digests


@pytest.mark.parametrize("case", list(digests.CASES))
def test_outputs_match_stored_digests(case: str) -> None:
    if case == "replay" and digests.find_mit_log() is None:
        pytest.skip(
            "the shared MIT CSAIL log is not found ($ALBOT2D_DATA, ../shared/data "
            "or /work/shared/data)"
        )
    stored = digests.load()
    now = digests.compute(case)
    diff = digests.differences(stored["cases"][case], now)
    path = "numba" if digests.numba_available() else "numpy"
    made = {True: "numba", False: "numpy", None: "unknown"}[stored["numba"]]
    assert not diff, (
        f"{case}: {len(diff)} section(s) differ from tests/digests.json (made on the {made} "
        f"path, this is the {path} path); if the change is deliberate, run "
        "`python -m tests.digests --update`:\n" + "\n".join(diff)
    )


def test_canonical_drops_timings_and_paths() -> None:
    report = {
        "wall_time_s": 1.5,
        "log": {"path": "/a/b/mit.clf.gz"},
        "mappers": {"x": {"timing_ms": {"total": 3.0}, "rpe": 0.1 + 0.2}},
    }
    assert digests.canonical(report) == {
        "log": {"path": "mit.clf.gz"},
        "mappers": {"x": {"rpe": 0.3}},
    }
    # a real change (beyond the 12th significant digit) still shows
    assert digests.canonical({"v": 0.3000001}) != digests.canonical({"v": 0.3})
