"""Visual regression: every figure family drawn from small fixed inputs and compared with
a stored reference image by a perceptual tolerance (matplotlib's ``compare_images``, RMS
over the pixels); and the counts a run's figures show, read back from the PNGs, match
report.json.

References live in ``tests/baseline_images/`` (small PNGs: drawn at ``DPI``). After a
deliberate change of a figure, look at the new pictures and store them with
``ALBOT2D_UPDATE_BASELINES=1 python -m pytest tests/test_figures_visual.py``.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest

pytest.importorskip("matplotlib")

from tests.figure_specs import fixed_step_times, paper_specs, small_run

BASELINES = Path(__file__).parent / "baseline_images"
DPI = 40
# RMS pixel difference (0-255) tolerated: font hinting and anti-aliasing differ a little
# across FreeType builds; a moved legend, a lost panel or a changed colour bar is far more.
TOLERANCE = 6.0
RUN_FIGURES = ("paths.png", "maps.png", "errors.png", "albot1_map.png", "albot1_history.png",
               "albot1_route.png", "naive_map.png", "homing.png")  # fmt: skip


@pytest.fixture(scope="module")
def run():
    return small_run()


@pytest.fixture(scope="module")
def run_pngs(run):
    from albot2d.viz import render_experiment_figures

    return render_experiment_figures(run, dpi=DPI)


def _compare(png: bytes, name: str, tmp_path: Path) -> None:
    from matplotlib.testing.compare import compare_images

    reference = BASELINES / name
    if os.environ.get("ALBOT2D_UPDATE_BASELINES") == "1":
        reference.parent.mkdir(parents=True, exist_ok=True)
        reference.write_bytes(png)
    if not reference.is_file():
        pytest.fail(f"no reference image {reference}; store it with ALBOT2D_UPDATE_BASELINES=1")
    actual = tmp_path / name.replace("/", "_")
    actual.write_bytes(png)
    result = compare_images(str(reference), str(actual), tol=TOLERANCE, in_decorator=True)
    assert result is None, f"{name} differs from its reference: {result}"


@pytest.mark.parametrize("name", RUN_FIGURES)
def test_run_figure_matches_its_reference(run_pngs, name, tmp_path):
    assert name in run_pngs
    _compare(run_pngs[name], f"run_{name}", tmp_path)


def test_steps_figure_matches_its_reference(tmp_path):
    from albot2d.viz.steps import render_step_times_png

    _compare(render_step_times_png(fixed_step_times(), dpi=DPI), "run_steps.png", tmp_path)


@pytest.mark.parametrize("spec", paper_specs(), ids=lambda s: s["plot"])
def test_experiments_figure_matches_its_reference(spec, tmp_path):
    from albot2d.viz.paper import save_figure

    path = tmp_path / spec["file"]
    save_figure(spec, path, dpi=DPI)
    _compare(path.read_bytes(), f"paper_{spec['file']}", tmp_path)


def test_the_counts_in_the_figures_are_report_json_s(run, run_pngs):
    """Every count a map title shows is stored in its PNG and equals report.json's."""
    from albot2d.viz.furniture import read_png_counts

    report = run.report["mappers"]
    for figure in ("maps.png", "albot1_map.png", "naive_map.png"):
        counts = read_png_counts(run_pngs[figure])
        names = ["albot1", "naive"] if figure == "maps.png" else [figure.split("_")[0]]
        for name in names:
            shown, known = counts[name], report[name]["counts"]
            assert shown["views"] == known["views"] == run.trace.n_frames
            assert shown["local_maps"] == known["local_maps"]
            assert shown["surfaces"] == known["global_map_surfaces"]
            assert shown["local_maps_in_map"] <= shown["local_maps"]
    history = read_png_counts(run_pngs["albot1_history.png"])
    for snap in report["albot1"]["snapshots"]:
        shown = history[f"albot1@{snap['row']}"]
        assert shown["local_maps"] == snap["update"] and shown["surfaces"] == snap["surfaces"]
        assert shown["views"] == snap["row"] + 1
    route = read_png_counts(run_pngs["albot1_route.png"])["albot1"]
    assert route["local_maps"] == report["albot1"]["counts"]["local_maps"]


def test_map_titles_name_what_they_count(run):
    """The title of a map says views, local maps and surfaces, with report.json's numbers."""
    from albot2d.viz._figure import new_figure
    from albot2d.viz.run_figures import _map_panel

    ax = new_figure(5, 5).subplots()
    _map_panel(ax, run, "albot1")
    title = ax.get_title()
    c = run.report["mappers"]["albot1"]["counts"]
    assert f"{c['views']} views → {c['local_maps']} local maps" in title
    assert f"{c['global_map_surfaces']} surfaces from" in title
