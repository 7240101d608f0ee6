"""Perception on the real MIT CSAIL log: sensible surface counts and tracking across scans.

Skipped when ../shared is absent. Bounds are loose on purpose (they check that extraction
and RTSV behave sensibly on real data, not a tuned score); measured values at the time of
writing are in the comments.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from albot2d.frames import Frame
from albot2d.geometry import Pose
from albot2d.logs import match_timestamps, read_frames, read_relations
from albot2d.perception import Surfaces, extract_surfaces, rtsv, start_tracking, trackable_mask

SHORT_RELATION_S = 2.0


@pytest.fixture(scope="module")
def mit(shared_data: Path) -> tuple[list[Frame], list[Surfaces]]:
    frames = list(read_frames(shared_data / "raw" / "mit-csail.clf.gz"))
    return frames, [extract_surfaces(f.scan) for f in frames]


def _tracked_through(views: list[Surfaces], pairs: list[tuple[int, int, Pose]]) -> np.ndarray:
    """``(P, 2)``: per scan pair, how many surfaces were tracked and how many survived."""
    counts = []
    for i, j, increment in pairs:
        tracked = start_tracking(views[i])
        survivors, _ = rtsv(tracked, views[j], increment)
        counts.append((len(tracked), len(survivors)))
    return np.array(counts).reshape(-1, 2)


def test_every_scan_gives_a_sensible_number_of_surfaces(
    mit: tuple[list[Frame], list[Surfaces]],
) -> None:
    frames, views = mit
    assert len(frames) == 1988
    n = np.array([len(v) for v in views])
    n_trackable = np.array([trackable_mask(v).sum() for v in views])
    assert 8 <= np.median(n) <= 20  # measured: 13
    assert n.min() >= 1
    assert 0.2 <= n_trackable.sum() / n.sum() <= 0.5  # measured: 0.32
    assert np.median(n_trackable) >= 3  # measured: 4
    assert np.mean(n_trackable == 0) < 0.05  # measured: 0.015


def test_consecutive_scans_track_several_surfaces(
    mit: tuple[list[Frame], list[Surfaces]],
) -> None:
    frames, views = mit
    pairs = [(i - 1, i, frames[i].odom_increment) for i in range(1, len(frames))]
    counts = _tracked_through(views, pairs)
    assert counts[:, 1].sum() / counts[:, 0].sum() > 0.55  # measured: 0.67
    assert np.median(counts[:, 1]) >= 2  # measured: 3
    assert np.mean(counts[:, 1] >= 1) > 0.8  # measured: 0.89
    # Without the motion, fewer survive: the increment is used, and the right way round.
    still = [(i, j, Pose()) for i, j, _ in pairs]
    assert _tracked_through(views, still)[:, 1].sum() < 0.9 * counts[:, 1].sum()


def test_ground_truth_motion_tracks_surfaces(
    shared_data: Path, mit: tuple[list[Frame], list[Surfaces]]
) -> None:
    frames, views = mit
    relations = read_relations(shared_data / "relations" / "mit-csail.relations")
    short = np.flatnonzero(relations.t2 - relations.t1 < SHORT_RELATION_S)
    stamps = np.array([f.timestamp for f in frames])
    i = match_timestamps(relations.t1[short], stamps)
    j = match_timestamps(relations.t2[short], stamps)
    pairs = [
        (int(a), int(b), Pose.from_array(m))
        for a, b, m in zip(i, j, relations.motion[short], strict=True)
    ]
    counts = _tracked_through(views, pairs)
    assert len(pairs) > 500  # measured: 980 relations spanning about 0.4 s
    assert counts[:, 1].sum() / counts[:, 0].sum() > 0.55  # measured: 0.66
