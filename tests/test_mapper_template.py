"""docs/mapper_template.py: a user's mapper as the README shows it, run like the built-ins."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pytest

from albot2d.cli import main
from albot2d.mapping import Mapper, MapSnapshot

DOCS = Path(__file__).resolve().parents[1] / "docs"


@pytest.fixture
def template(monkeypatch: pytest.MonkeyPatch) -> type:
    monkeypatch.syspath_prepend(str(DOCS))
    import mapper_template

    yield mapper_template.LastViewOnly
    sys.modules.pop("mapper_template", None)


def test_the_template_implements_the_protocol(template: type) -> None:
    mapper = template()
    assert isinstance(mapper, Mapper)
    empty = mapper.global_map()
    assert isinstance(empty, MapSnapshot)
    assert empty.segments.shape == (0, 4) and empty.map_ids.shape == (0,)
    assert mapper.trajectory().shape == (0, 3)


def test_the_template_runs_beside_albot1(
    template: type, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "out"
    assert main(["run", "--kind", "rooms", "--width", "15", "--height", "15",
                 "--tour-length", "20", "--profile", "dataset3", "--max-frames", "60",
                 "--mapper", "naive", "mapper_template:LastViewOnly", "--no-figures",
                 "--json", "--out", str(out)]) == 0  # fmt: skip
    report = json.loads(capsys.readouterr().out)
    mine, naive = report["mappers"]["last_views"], report["mappers"]["naive"]
    assert mine["counts"]["views"] == 60
    # Same poses as naive integration, so the same trajectory errors ...
    assert mine["rpe"]["trans_m_mean"] == pytest.approx(naive["rpe"]["trans_m_mean"])
    assert mine["ape"]["trans_m_rmse"] == pytest.approx(naive["ape"]["trans_m_rmse"])
    # ... but a map of only the last three views.
    csv = np.loadtxt(out / "map_last_views.csv", delimiter=",", skiprows=1).reshape(-1, 5)
    assert set(csv[:, 4].astype(int)) == {57, 58, 59}
    assert 0 < mine["map"]["surfaces"] < naive["map"]["surfaces"]
