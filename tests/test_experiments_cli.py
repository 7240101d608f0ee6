"""``albot2d experiments --quick``: experiments.json's fields, the figures, bad input, the
same results on any number of workers, and index.html in a real headless Chromium."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from albot2d.cli import main
from tests.browser import chromium, probe_page

pytest.importorskip("matplotlib")
# Every experiment of the paper, run --quick (about a minute even on a quiet machine).
pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def quick_out(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("exp") / "exp"
    assert main(["experiments", "--quick", "--seeds", "0", "--workers", "1", "--out",
                 str(out)]) == 0  # fmt: skip
    return out


def test_experiments_json_has_the_issue_fields(quick_out):
    data = json.loads((quick_out / "experiments.json").read_text())
    exps = data["experiments"]
    assert list(exps) == ["counts", "table1", "fig7", "fig10", "fig11_12", "fig13", "fig14",
                          "fig15", "fig16"]  # fmt: skip
    t1 = exps["table1"]
    assert 0.0 <= t1["ours"]["fraction_within_bound"] <= 1.0
    assert t1["ours"]["stops"] and t1["paper"]["fraction_within_bound"] == 1.0
    for stop in t1["ours"]["stops"]:
        assert 17.0 <= stop["distance_true_m"] <= 35.0
    for dataset in ("dataset1", "dataset2", "dataset3", "start_stop", "non_corridor"):
        for field in ("views", "local_maps", "path_integrations"):
            assert set(exps["counts"]["ours"][dataset][field]) == {"mean", "sd", "n", "per_seed"}
    assert exps["counts"]["paper"]["dataset1"]["views"] == 795
    assert exps["counts"]["ours"]["dataset3"]["views"]["mean"] == 150  # cut short by --quick
    for name in ("albot1", "naive"):
        assert exps["fig16"]["ours"]["map_accuracy_p95_m"][name]["mean"] > 0.0
    assert exps["fig16"]["paper"]["path_integrations"] == {"dataset1": 5, "dataset2": 7}
    for name, result in exps.items():
        assert result["verdict"] in ("reproduced", "partly", "not reproduced"), name
        assert data["verdicts"][name] == result["verdict"]
        assert result["claim"] and result["rule"]
        for fig in result["figures"]:
            assert (quick_out / fig).stat().st_size > 1000
    assert data["quick"] is True and data["seeds"] == [0]
    # both default readings, side by side, path-integration counts included
    assert data["readings"] == {
        "default": "albot1",
        "paper_literal": "albot1[preset=paper_literal]",
    }
    for name, result in exps.items():
        assert list(result["readings"]) == ["default", "paper_literal"], name
        assert data["verdicts_by_reading"][name]["default"] == result["verdict"]
        assert result["paper_figure"]
    for reading in exps["fig16"]["readings"].values():
        assert set(reading["ours"]["map_accuracy_p95_m"]) >= {"albot1", "naive"}  # fig16
    pi = exps["counts"]["readings"]["paper_literal"]["ours"]["dataset1"]["path_integrations"]
    assert set(pi) == {"mean", "sd", "n", "per_seed"}


def test_same_results_on_two_workers(quick_out, tmp_path):
    out = tmp_path / "two"
    assert main(["experiments", "--quick", "--only", "table1", "--seeds", "0", "--workers",
                 "2", "--no-figures", "--out", str(out)]) == 0  # fmt: skip
    two = json.loads((out / "experiments.json").read_text())["experiments"]["table1"]
    one = json.loads((quick_out / "experiments.json").read_text())["experiments"]["table1"]
    one.pop("figures"), two.pop("figures")
    assert one == two


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--seeds", "a-b"], "--seeds"),
        (["--only", "fig99"], "unknown experiment 'fig99'"),
        (["--workers", "0"], "--workers"),
        (["--backend", "slurm"], "unknown backend"),
    ],
)
def test_bad_input_is_one_line_and_writes_nothing(argv, message, tmp_path, capsys):
    out = tmp_path / "never"
    assert main(["experiments", "--quick", *argv, "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0]
    assert not out.exists()


# Injected into a copy of the page only: reports, once loaded, the images that did not load
# and how many tables there are, as an attribute the dumped DOM shows.
_PROBE = (
    "<script>window.addEventListener('load',()=>{const bad=[...document.images]"
    ".filter(i=>!(i.complete&&i.naturalWidth>0)).map(i=>i.getAttribute('src'));"
    "document.body.setAttribute('data-probe',JSON.stringify({images:document.images.length,"
    "bad:bad,tables:document.querySelectorAll('table').length}));});</script></body>"
)


def test_page_in_headless_chromium(quick_out):
    chromium()
    page = (quick_out / "index.html").read_text()
    result, proc = probe_page(page, quick_out, _PROBE, "--enable-logging=stderr", "--v=0")
    data = json.loads((quick_out / "experiments.json").read_text())
    # every reading's figures (default: default and paper_literal) are on the page
    n_figures = sum(len(v["figures"]) for r in data["experiments"].values()
                    for v in r["readings"].values())  # fmt: skip
    assert result["bad"] == [] and result["images"] == n_figures >= 8
    assert result["tables"] >= 1 + len(data["experiments"])
    console = [line for line in proc.stderr.splitlines() if ":CONSOLE" in line]
    assert console == []
    for name, verdict in data["verdicts"].items():
        assert f"id='{name}'" in page and verdict in page
