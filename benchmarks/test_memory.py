"""Peak memory of drawing and scoring a long run's map, beside the paths they replaced
(issue 12: "a 10x longer tour must not need 10x the memory").

Run: ``python -m pytest benchmarks/test_memory.py --benchmark-only
--benchmark-group-by=group``; each case runs in a fresh Python process and reports the
growth of its peak RSS (``ru_maxrss``) over the imports in ``extra_info["peak_mb"]``
(the benchmark's time is that process's, start to end). The map is synthetic: short
surfaces along the default office world's walls, as many as a ``--tour-length 1200``
run's naive map holds at the end (820,000).

- draw: a ``LineCollection`` of one ``(2, 2)`` line per surface (matplotlib makes a Path
  object each) against ``plot_map`` (a few NaN-separated lines per colour of the map);
- score: ``map_quality`` with completeness (the seen points of the last views);
- run: the default ``albot2d run --out DIR`` (figures included) in a child process, its
  whole peak RSS (``ru_maxrss`` of the child, not a growth over imports; the issue's
  target is 300 MB), and with ``--no-figures``. File-backed pages (numba's LLVM library
  is ~70 MB of it) count as the kernel maps them, so the number moves by ~10 MB with what
  other processes keep in the page cache.
"""

from __future__ import annotations

import json
import subprocess
import sys
import textwrap
from pathlib import Path
from typing import Any

import pytest

pytest.importorskip("matplotlib")

SURFACES = 820_000

_SETUP = """
import json, resource, numpy as np
from albot2d.evaluation.run.setup import RunSpec, build_run
walls = build_run(RunSpec()).world.obstacle_segments
rng = np.random.default_rng(0)
n = {n}
i = rng.integers(0, len(walls), n)
d = walls[i, 2:] - walls[i, :2]
a = walls[i, :2] + rng.uniform(0.0, 0.8, (n, 1)) * d
b = a + 0.2 * d / np.maximum(np.hypot(d[:, 0], d[:, 1]), 1e-9)[:, None]
segs = np.hstack([a, b]) + rng.normal(0.0, 0.02, (n, 4))
ids = np.sort(rng.integers(0, n // 6, n))
import matplotlib.collections, albot2d.viz.maps, albot2d.evaluation.metrics.map_quality
base = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
"""

_CASES = {
    "draw_per_surface": """
from albot2d.viz._figure import line_segments, new_figure, png_bytes
fig = new_figure(8.0, 8.0)
ax = fig.add_subplot()
lines = matplotlib.collections.LineCollection(line_segments(segs), linewidths=1.6, cmap="viridis")
lines.set_array(ids.astype(float))
ax.add_collection(lines)
ax.autoscale_view()
png_bytes(fig, 100)
""",
    "draw_plot_map": """
from albot2d.viz._figure import png_bytes
ax = albot2d.viz.maps.plot_map(segs, map_ids=ids)
png_bytes(ax.get_figure(root=True), 100)
""",
    "score_map_quality": """
from albot2d.evaluation.metrics.map_quality import map_quality
from albot2d.geometry import Pose
seen = walls[:, :2][np.hypot(*(walls[:, :2] - [30.0, 20.0]).T) < 8.0]
map_quality(segs, walls, start_pose=Pose(0.0, 0.0, 0.0), seen_points=seen)
""",
}


def _peak_mb(case: str, n: int) -> float:
    code = (
        textwrap.dedent(_SETUP.format(n=n))
        + textwrap.dedent(_CASES[case])
        + ("print(json.dumps((resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - base) / 1e3))")
    )
    out = subprocess.run([sys.executable, "-c", code], check=True, capture_output=True, text=True)
    return float(json.loads(out.stdout.strip().splitlines()[-1]))


@pytest.mark.parametrize("case", list(_CASES))
def test_peak_memory(benchmark: Any, case: str) -> None:
    benchmark.group = "draw" if case.startswith("draw") else "score"
    peak = benchmark.pedantic(_peak_mb, args=(case, SURFACES), rounds=1, iterations=1)
    benchmark.extra_info.update({"surfaces": SURFACES, "peak_mb": round(peak, 1)})


_RUN = """
import resource, sys
from albot2d.cli import main
code = main(sys.argv[1:])
print("peak_kb", resource.getrusage(resource.RUSAGE_SELF).ru_maxrss)
sys.exit(code)
"""


def _run_peak_mb(out: Path, *extra: str) -> float:
    """Peak RSS (MB) of one ``albot2d run`` in a fresh process (what ``albot2d run`` does:
    ``albot2d.cli.main``, then the process's own ``ru_maxrss``)."""
    done = subprocess.run(
        [sys.executable, "-c", _RUN, "run", "--out", str(out), *extra],
        check=True, capture_output=True, text=True,
    )  # fmt: skip
    line = [x for x in done.stdout.splitlines() if x.startswith("peak_kb ")][-1]
    return int(line.split()[1]) / 1e3


@pytest.mark.parametrize("figures", [True, False], ids=["figures", "no_figures"])
def test_default_run_peak_rss(benchmark: Any, tmp_path: Path, figures: bool) -> None:
    benchmark.group = "run"
    extra = () if figures else ("--no-figures",)
    peak = benchmark.pedantic(_run_peak_mb, args=(tmp_path / "out", *extra), rounds=1, iterations=1)
    assert (tmp_path / "out" / "report.json").is_file()
    benchmark.extra_info.update({"peak_rss_mb": round(peak, 1), "target_mb": 300})
