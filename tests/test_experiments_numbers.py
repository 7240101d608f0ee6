"""``albot2d experiments --quick`` end to end, its numbers checked against the same runs
driven here directly: the world, tour and simulator of each run's spec, every frame fed to
a fresh Albot1, and the views, local maps and path integrations counted from what that
gives (the frames, the route map's length and its links' methods), not read from the
experiments' own records."""

from __future__ import annotations

import itertools
import json

import pytest

from albot2d.cli import main
from albot2d.evaluation.paper.runs import PAPER_NOISE, QUICK_MAX_FRAMES, RUNS
from albot2d.evaluation.run.setup import RunSpec, build_run
from albot2d.mapping import Albot1

pytestmark = pytest.mark.slow  # five runs of 150 views, and the same again here


@pytest.fixture(scope="module")
def counts(tmp_path_factory: pytest.TempPathFactory) -> dict:  # type: ignore[type-arg]
    out = tmp_path_factory.mktemp("exp") / "exp"
    assert main(["experiments", "--quick", "--only", "counts", "--seeds", "0", "--workers",
                 "1", "--no-figures", "--out", str(out)]) == 0  # fmt: skip
    data = json.loads((out / "experiments.json").read_text())
    return data["experiments"]["counts"]  # type: ignore[no-any-return]


def _drive(run_name: str, seed: int) -> tuple[int, int, int]:
    """(views, local maps, path integrations) of Albot1 on the run's first 150 frames."""
    run = RUNS[run_name]
    setup = build_run(RunSpec(
        seed=seed, kind=run.kind, world_params=dict(run.world_params), profile=run.profile,
        noise=PAPER_NOISE, tour_kind=run.tour_kind, tour_length_m=run.tour_length_m,
        route=run.route, mappers=("albot1",),
    ))  # fmt: skip
    albot1 = Albot1()
    frames = itertools.islice(setup.simulator.drive(setup.tour, setup.profile), QUICK_MAX_FRAMES)
    views = 0
    for frame in frames:
        albot1.observe(frame)
        views += 1
    methods = [lm.method for lm in albot1.route]
    return views, len(methods), methods.count("path_integration")


@pytest.mark.parametrize(("dataset", "run_name"), [("dataset3", "fig6_dataset3"),
                                                    ("non_corridor", "fig11_open")])  # fmt: skip
def test_counts_equal_a_direct_run(counts, dataset: str, run_name: str) -> None:  # type: ignore[no-untyped-def]
    views, maps, pis = _drive(run_name, 0)
    assert views == QUICK_MAX_FRAMES
    ours = counts["ours"][dataset]
    assert ours["counted_at"] == "end"
    assert ours["views"]["per_seed"] == {"0": views}
    assert ours["local_maps"]["per_seed"] == {"0": maps}
    assert ours["path_integrations"]["per_seed"] == {"0": pis}
    assert ours["local_maps_per_view"]["per_seed"]["0"] == pytest.approx(maps / views)
    assert ours["local_maps"]["mean"] == maps and ours["local_maps"]["n"] == 1
    # The verdict's rule: the local-maps-per-view ratio within 25 % of the paper's.
    paper = counts["paper"][dataset]
    within = abs(maps / views - paper["local_maps_per_view"]) <= 0.25 * paper["local_maps_per_view"]
    assert ours["ratio_within_25pct"] is within
