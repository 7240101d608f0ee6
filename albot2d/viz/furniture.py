"""What every albot2d figure shares: type sizes, a map's scale bar and axes arrows, colour
bars the height of their axes, legends kept off the data, and the counts a figure shows,
stored in its PNG so a test (or a reader) can check them against report.json.

Terms, defined here once and used by every title, table and report field that counts:

- a *view* is one laser scan given to a mapper (report ``counts.views``);
- a *local map* is a view the mapper remembered (Albot₁'s route map; the integrators
  remember every view; report ``counts.local_maps``);
- a *surface* is one line segment of a map (report ``counts.global_map_surfaces`` for the
  global map at the end); a global map's surfaces come from some of its local maps
  (Albot₁ deletes the surfaces of old local maps it sees again), counted as
  ``local maps in the map``.

matplotlib is imported inside the functions.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.cm import ScalarMappable
    from matplotlib.colorbar import Colorbar
    from matplotlib.figure import Figure

__all__ = [
    "COUNTS_KEY",
    "LABEL_PT",
    "LEGEND_PT",
    "TERMS",
    "TICK_PT",
    "TITLE_PT",
    "axes_colorbar",
    "count_text",
    "draw_map_furniture",
    "emptiest_corner",
    "figure_counts",
    "read_png_counts",
    "set_figure_counts",
]

TITLE_PT = 10.0
LABEL_PT = 9.0
TICK_PT = 8.0
LEGEND_PT = 8.0
COUNTS_KEY = "albot2d:counts"
"""The PNG text chunk holding a figure's counts (JSON), written by ``png_bytes``."""
TERMS = {
    "views": "views",
    "local_maps": "local maps",
    "surfaces": "surfaces",
    "local_maps_in_map": "local maps in the map",
}
_CORNERS = ("lower right", "lower left", "upper right", "upper left")


def count_text(n: int, term: str) -> str:
    """``n`` and the term it counts (``TERMS``), singular for one."""
    word = TERMS[term]
    if n == 1:
        word = {"views": "view", "local maps": "local map", "surfaces": "surface"}.get(word, word)
    return f"{n} {word}"


def set_figure_counts(fig: Figure, name: str, counts: Mapping[str, Any]) -> None:
    """Record ``counts`` (term → number) shown by ``fig`` under ``name`` (a mapper, a
    panel); ``png_bytes`` writes them into the PNG (``COUNTS_KEY``)."""
    store: dict[str, Any] = fig.__dict__.setdefault("_albot2d_counts", {})
    store[name] = dict(counts)


def figure_counts(fig: Figure) -> dict[str, Any]:
    return dict(fig.__dict__.get("_albot2d_counts", {}))


def read_png_counts(png: bytes) -> dict[str, Any]:
    """The counts a figure stored in its PNG (``{}`` if none)."""
    import io

    from PIL import Image

    with Image.open(io.BytesIO(png)) as image:
        text = image.info.get(COUNTS_KEY)
    return json.loads(text) if text else {}


def png_metadata(fig: Figure) -> dict[str, str]:
    counts = figure_counts(fig)
    return {COUNTS_KEY: json.dumps(counts, sort_keys=True)} if counts else {}


def emptiest_corner(ax: Axes, points: Any, fraction: float = 0.25) -> str:
    """The corner of ``ax`` (a ``loc`` string) with the fewest of ``points`` (``(N, 2)``,
    data coordinates) within ``fraction`` of the axes' width and height: where a scale
    bar or legend covers least."""
    pts = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    pts = pts[np.all(np.isfinite(pts), axis=1)]
    if not len(pts):
        return _CORNERS[0]
    (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
    u = (pts[:, 0] - x0) / max(x1 - x0, 1e-12)
    v = (pts[:, 1] - y0) / max(y1 - y0, 1e-12)
    low_u, high_u = u < fraction, u > 1.0 - fraction
    low_v, high_v = v < fraction, v > 1.0 - fraction
    counts = [
        int(np.count_nonzero(high_u & low_v)),
        int(np.count_nonzero(low_u & low_v)),
        int(np.count_nonzero(high_u & high_v)),
        int(np.count_nonzero(low_u & high_v)),
    ]
    return _CORNERS[int(np.argmin(counts))]  # ties: the first, lower right


def nice_length(span_m: float) -> float:
    """A round scale-bar length (1, 2 or 5 × 10^k) near a fifth of ``span_m``."""
    target = max(span_m, 1e-9) / 5.0
    power = 10.0 ** math.floor(math.log10(target))
    return max(m * power for m in (1.0, 2.0, 5.0) if m * power <= target)


def draw_map_furniture(ax: Axes, points: Any = None, *, loc: str | None = None) -> str:
    """A scale bar and the frame's axes (x →, y ↑: REP-103's map frame, metres) in the
    emptiest corner of a map's axes (``loc`` to choose it); axis labels in metres and
    equal aspect. Call after the limits are set. Returns the corner used."""
    from matplotlib.offsetbox import AnchoredOffsetbox, AuxTransformBox, TextArea, VPacker
    from matplotlib.patches import FancyArrow
    from matplotlib.transforms import IdentityTransform
    from mpl_toolkits.axes_grid1.anchored_artists import AnchoredSizeBar

    ax.set_aspect("equal")
    ax.set_xlabel("x (m)", fontsize=LABEL_PT)
    ax.set_ylabel("y (m)", fontsize=LABEL_PT)
    ax.tick_params(labelsize=TICK_PT)
    corner = loc or emptiest_corner(ax, points if points is not None else np.zeros((0, 2)))
    x0, x1 = ax.get_xlim()
    span = max(abs(x1 - x0), 1e-9)
    length = nice_length(span)
    bar = AnchoredSizeBar(
        ax.transData, length, f"{length:g} m", loc=corner, pad=0.3, borderpad=0.5, sep=2,
        frameon=True, size_vertical=0.0, fontproperties={"size": TICK_PT},
    )  # fmt: skip
    bar.patch.set(alpha=0.85, edgecolor="#bbbbbb", linewidth=0.5)
    bar.size_bar.get_children()[0].set(linewidth=2.0, edgecolor="k")
    bar.zorder = 20
    ax.add_artist(bar)
    # the frame's axes, opposite the scale bar horizontally, in the same row
    side = "left" if "right" in corner else "right"
    arrow_loc = corner.split()[0] + " " + side
    box = AuxTransformBox(IdentityTransform())  # arrows in pixels, whatever the zoom
    for dx, dy in ((1.0, 0.0), (0.0, 1.0)):
        box.add_artist(FancyArrow(0, 0, 18 * dx, 18 * dy, width=1.2, head_width=6,
                                  head_length=6, length_includes_head=True, color="k"))  # fmt: skip
    label = TextArea("x →, y ↑", textprops={"size": TICK_PT - 1})
    packed = VPacker(children=[box, label], align="center", pad=0, sep=2)
    frame = AnchoredOffsetbox(loc=arrow_loc, child=packed, pad=0.3, borderpad=0.5, frameon=True)
    frame.patch.set(alpha=0.85, edgecolor="#bbbbbb", linewidth=0.5)
    frame.zorder = 20
    ax.add_artist(frame)
    return corner


def axes_colorbar(
    fig: Figure, mappable: ScalarMappable, ax: Axes, label: str, *, width: float = 0.035
) -> Colorbar:
    """A colour bar exactly the height of ``ax`` as drawn (after its aspect is applied),
    just right of it: an inset of the axes, so it follows the axes' drawn box, and
    layout engines make room for it."""
    cax = ax.inset_axes((1.02, 0.0, width, 1.0))
    bar = fig.colorbar(mappable, cax=cax)
    bar.set_label(label, fontsize=LABEL_PT)
    bar.ax.tick_params(labelsize=TICK_PT)
    return bar


def legend_below(fig: Figure, handles: Sequence[Any], *, ncols: int | None = None) -> None:
    """One legend for the whole figure, below its panels (off every panel's data)."""
    fig.legend(
        handles=list(handles), loc="outside lower center", ncols=ncols or min(len(handles), 6),
        fontsize=LEGEND_PT, frameon=False,
    )  # fmt: skip
