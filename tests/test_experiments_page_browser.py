"""The experiments page in a real headless Chromium: a small page (one experiment of each
figure kind, marked a smoke run) is generated with its PNGs, opened, and a script in a
copy of it reports into the DOM every image that did not load (naturalWidth 0) or
overflows the page's width; Chromium's --dump-dom gives that back."""

from __future__ import annotations

import pytest

pytest.importorskip("matplotlib")

from tests.browser import chromium, probe_page
from tests.figure_specs import paper_specs

_PROBE = (
    "<script>window.addEventListener('load',()=>{const W=document.documentElement.clientWidth;"
    "const bad=[...document.images].filter(i=>!(i.complete&&i.naturalWidth>0))"
    ".map(i=>i.getAttribute('src'));const wide=[...document.images].filter(i=>"
    "i.getBoundingClientRect().right>W+1).map(i=>i.getAttribute('src'));"
    "document.body.setAttribute('data-probe',JSON.stringify({images:document.images.length,"
    "bad:bad,wide:wide,scroll:document.documentElement.scrollWidth,width:W,"
    "banner:!!document.getElementById('smoke-banner')}));});</script></body>"
)


def _page(out):
    from albot2d.viz.paper import save_figure
    from albot2d.viz.paper_page import render_page

    specs = paper_specs()
    for spec in specs:
        save_figure(spec, out / spec["file"], dpi=110)
    stat = {"mean": 0.4, "sd": 0.1, "n": 2, "per_seed": {"0": 0.3, "1": 0.5}}
    experiments = {
        spec["plot"]: {
            "claim": f"a claim drawn as {spec['plot']}", "rule": "a rule",
            "verdict": "partly", "paper": {"dataset1": {"views": 795}},
            "ours": {"dataset1": {"views": stat, "local_maps": stat}}, "figure_seed": 0,
            "figures": [spec["file"]],
        }
        for spec in specs
    }  # fmt: skip
    data = {"seeds": [0, 1], "quick": True, "odometry_noise": "pioneer3dx", "albot_x": None,
            "verdicts": {k: v["verdict"] for k, v in experiments.items()},
            "experiments": experiments}  # fmt: skip
    figures = {s["plot"]: [{"file": s["file"], "caption": s["caption"], "plot": s["plot"]}]
               for s in specs}  # fmt: skip
    return render_page(data, figures), len(specs)


@pytest.mark.parametrize("width", [1280, 700])
def test_no_image_is_missing_or_overflowing(tmp_path, width):
    chromium()
    page, n_images = _page(tmp_path)
    assert page.count("(smoke run)") >= 2 * n_images  # summary and section of every verdict
    result, _ = probe_page(page, tmp_path, _PROBE, f"--window-size={width},900")
    assert result["images"] == n_images and result["bad"] == []
    assert result["wide"] == [], result
    assert result["scroll"] <= result["width"], result  # nothing wider than the window
    assert result["banner"]
