"""Plain data for the paper's figures, built from a run's snapshots (no plotting here).

A *panel* is ``{"title", "walls", "segments", "deleted", "path", "marks"}`` in world
coordinates: every map is anchored at the true start pose (as map accuracy is), so
drift and distortion show against the faint true walls.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TypedDict

import numpy as np

from albot2d.evaluation.paper.jobs import FigureRun, FloatArray, Snapshot
from albot2d.geometry import transform_segments

__all__ = ["LABELS", "PanelData", "deleted_surfaces", "map_panel"]

LABELS = {
    "albot1": "Albot₁",
    "naive": "naive integration",
    "slam": "Albot_x (slam)",
    "truth": "ground truth",
}


class PanelData(TypedDict):
    """A map panel of a figure, as the viz layer draws it (plain data)."""

    title: str
    walls: FloatArray
    segments: FloatArray
    deleted: FloatArray | None
    path: FloatArray
    marks: Mapping[str, tuple[float, float]]


def map_panel(
    fig: FigureRun,
    mark: str,
    mapper: str,
    title: str,
    deleted: FloatArray | None = None,
    place: str | None = None,
) -> PanelData | None:
    """The map of ``mapper`` at ``mark`` of a run kept for figures (None if not taken).

    ``title`` may hold ``{at}``: it becomes ``place`` (e.g. "at E5") when the run got
    there, and where a run cut short (``--quick``) actually stopped otherwise, so no
    title claims a place the run never reached."""
    snap = fig.snaps.get(mark)
    if snap is None or mapper not in snap.maps:
        return None
    where = place or ("at the end" if mark == "end" else f"at {mark}")
    if snap.reached:
        title = title.replace("{at}", where)
    else:  # one clause a line, so side-by-side panel titles never run into each other
        cut = (f"run cut short at view {int(snap.frame)}, "
               f"{float(snap.true_travelled_m):.0f} m (not {where})")  # fmt: skip
        before, _, after = title.partition("{at}")
        lines = [before.strip().rstrip(","), cut, after.strip().lstrip(",").strip()]
        title = "\n".join(line for line in lines if line)
    start = fig.true_poses[0]
    row = min(int(snap.frame), len(fig.true_poses) - 1)  # simulated: frame = row
    segs = transform_segments(start, snap.maps[mapper].segments)
    gone = None if deleted is None else transform_segments(start, deleted)
    return {
        "title": title,
        "walls": fig.world_walls,
        "segments": segs,
        "deleted": gone,
        "path": fig.true_poses[: row + 1, :2],
        "marks": fig.waypoints,
    }


def deleted_surfaces(before: Snapshot, after: Snapshot) -> FloatArray:
    """Surfaces of Albot1's map in snapshot ``before`` that are gone in ``after`` (matched
    by local-map id and coordinates)."""
    b, a = before.maps["albot1"], after.maps["albot1"]
    keep = {(int(i), *np.round(s, 6)) for s, i in zip(a.segments, a.map_ids, strict=True)}
    rows = [
        k
        for k, (s, i) in enumerate(zip(b.segments, b.map_ids, strict=True))
        if (int(i), *np.round(s, 6)) not in keep
    ]
    return np.asarray(b.segments)[rows].reshape(-1, 4)
