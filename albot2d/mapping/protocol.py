"""The mapper protocol that the CLI, experiments and fuzzing use, and users implement.

A mapper consumes ``Frame``s one at a time (``observe``) and can be asked at any moment
for its pose estimate, its global map and its counters. ``trajectory()`` gives the pose
estimate of every frame observed so far, as the mapper now believes it.
"""

from __future__ import annotations

import time
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np
from numpy.typing import NDArray

from albot2d.frames import Frame
from albot2d.geometry import Pose
from albot2d.mapping.global_map import MapSnapshot

__all__ = ["Mapper", "MapperCounts", "StageTimer"]


@dataclass(frozen=True, slots=True)
class MapperCounts:
    """Process counts: views seen, local maps remembered, and how they were localised."""

    views: int = 0
    local_maps: int = 0
    triangulations: int = 0
    path_integrations: int = 0


class StageTimer:
    """Accumulates wall time per named stage with ``perf_counter_ns`` (≈ 100 ns per use)."""

    def __init__(self) -> None:
        self.total_ns: dict[str, int] = {}
        self.calls: dict[str, int] = {}

    @contextmanager
    def stage(self, name: str) -> Iterator[None]:
        t0 = time.perf_counter_ns()
        try:
            yield
        finally:
            self.total_ns[name] = self.total_ns.get(name, 0) + time.perf_counter_ns() - t0
            self.calls[name] = self.calls.get(name, 0) + 1

    def mean_ms_per(self, n_views: int) -> dict[str, float]:
        """Mean milliseconds per view for each stage (total stage time / views)."""
        if n_views <= 0:
            return {k: 0.0 for k in self.total_ns}
        return {k: v / 1e6 / n_views for k, v in self.total_ns.items()}


@runtime_checkable
class Mapper(Protocol):
    """What every mapper (Albot1, baselines, a user's ``module:Class``) provides."""

    name: str

    def observe(self, frame: Frame) -> None:
        """Consume the next frame of the run."""

    def pose(self) -> Pose:
        """Current pose estimate in the mapper's global frame."""

    def global_map(self) -> MapSnapshot:
        """Current map surfaces (global frame) and the id of the local map each came from."""

    def trajectory(self) -> NDArray[np.float64]:
        """``(F, 3)`` pose estimate of every observed frame, in the global frame."""

    def counts(self) -> MapperCounts:
        """Process counters."""

    def timings_ms(self) -> dict[str, float]:
        """Mean milliseconds per view for each processing stage."""
