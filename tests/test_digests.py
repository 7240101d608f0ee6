"""Behaviour unchanged: four short runs' outputs against the digests (and readable values)
stored in the repo, and the regeneration command's refusal of unexpected changes.

See ``tests/digests.py`` for what is run and compared; after a deliberate change of
behaviour, ``python -m tests.digests --update --expect CASE:SECTIONS`` rewrites
``tests/digests.json`` when only the named sections changed.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from tests import digests


@pytest.mark.parametrize("case", list(digests.CASES))
def test_outputs_match_stored_digests(case: str) -> None:
    if case == "replay" and digests.find_mit_log() is None:
        pytest.skip(
            "the shared MIT CSAIL log is not found ($ALBOT2D_DATA, ../shared/data "
            "or /work/shared/data)"
        )
    if case == "slam" and not digests.slam_available():
        pytest.skip("the [slam] extra is not installed (pip install -e '.[slam]')")
    stored = digests.load()
    now = digests.compute(case)
    diff = digests.differences(stored["cases"][case], now)
    path = "numba" if digests.numba_available() else "numpy"
    made = {True: "numba", False: "numpy", None: "unknown"}[stored["numba"]]
    assert not diff, (
        f"{case}: {len(diff)} section(s) differ from tests/digests.json (made on the {made} "
        f"path, this is the {path} path); if the change is deliberate, run "
        f"`python -m tests.digests --update --expect '{case}:SECTION_GLOB'` naming what "
        "should change:\n" + "\n".join(digests.readable_changes(stored["cases"][case], now, diff))
    )


def test_every_stored_section_shows_what_it_hashes() -> None:
    """Each section keeps its value (or, for a long one, its key numbers) beside the
    digest, and a stored value hashes to the stored digest."""
    stored = digests.load()
    assert {"run", "slam", "fuzz"} <= set(stored["cases"])
    for case, sections in stored["cases"].items():
        for key, entry in sections.items():
            assert set(entry) in ({"sha256", "value"}, {"sha256", "numbers"}), (case, key)
            if "value" in entry:
                assert digests.section(entry["value"])["sha256"] == entry["sha256"], (case, key)


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


def test_a_long_section_keeps_its_key_numbers() -> None:
    value = {"poses": [[float(i), 2.0 * i] for i in range(200)], "name": "x"}
    entry = digests.section(value)
    assert "value" not in entry
    numbers = entry["numbers"]
    assert numbers["count"] == 400 and numbers["min"] == 0.0 and numbers["max"] == 398.0
    assert numbers["sum"] == pytest.approx(sum(range(200)) * 3.0)
    assert numbers["first"]["poses[0][1]"] == 0.0 and len(numbers["first"]) == 12


def test_readable_changes_name_the_values_that_moved() -> None:
    old = {"a": digests.section({"rmse": 0.1, "n": 3}), "b": digests.section([1, 2])}
    new = {"a": digests.section({"rmse": 0.2, "n": 3}), "b": digests.section([1, 2])}
    diff = digests.differences(old, new)
    assert diff == ["a"]
    lines = digests.readable_changes(old, new, diff)
    assert lines == ["a: 1 value(s) differ", "    rmse: 0.1 -> 0.2"]


def test_expect_patterns_cover_cases_and_sections() -> None:
    changed = ["mappers.albot1.rpe", "mappers.naive.rpe", "odometry.ape.poses"]
    assert digests.unexpected("run", changed, ["run:mappers.*"]) == ["odometry.ape.poses"]
    assert digests.unexpected("run", changed, ["run"]) == []
    assert digests.unexpected("run", changed, ["fuzz"]) == changed
    assert digests.unexpected("run", changed, ["run:mappers.albot1.*", "run:odometry.*"]) == [
        "mappers.naive.rpe"
    ]


def test_update_refuses_changes_nobody_expected(tmp_path: Path, monkeypatch, capsys) -> None:  # type: ignore[no-untyped-def]
    """The command on a toy case (real files): a change outside ``--expect`` writes
    nothing and names the section; named, it is written with its value."""
    stored = tmp_path / "digests.json"
    before = {"fast": 1.0, "slow": 2.0}
    stored.write_text(json.dumps({"numba": None, "cases": {"toy": {
        k: digests.section(v) for k, v in before.items()}}}))  # fmt: skip
    after = {"fast": 1.5, "slow": 2.5}
    monkeypatch.setattr(digests, "DIGEST_FILE", stored)
    monkeypatch.setattr(digests, "CASES", {"toy": lambda out: {
        k: digests.section(v) for k, v in after.items()}})  # fmt: skip
    text = stored.read_text()
    assert digests.main(["--update", "--expect", "toy:fast", "toy"]) == 1
    err = capsys.readouterr()
    assert "refused: 1 changed section(s)" in err.err and "toy:slow" in err.err
    assert "fast: 1 value(s) differ" in err.out and "1.0 -> 1.5" in err.out
    assert stored.read_text() == text
    assert digests.main(["--update", "--expect", "toy", "toy"]) == 0
    written = json.loads(stored.read_text())["cases"]["toy"]
    assert written["slow"] == digests.section(2.5) and written["slow"]["value"] == 2.5
    assert digests.main(["toy"]) == 0  # nothing differs now
