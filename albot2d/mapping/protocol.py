"""The mapper protocol that the CLI, experiments and fuzzing use, and users implement.

A mapper consumes ``Frame``s one at a time (``observe``) and can be asked at any moment
for its pose estimate, its global map and its counters. ``trajectory()`` gives the pose
estimate of every frame observed so far, as the mapper now believes it.

Perceive once: a mapper that works on extracted surfaces can also implement
``PerceivingMapper`` (``perception()`` names the ``ExtractionParams`` it wants and
``observe_perceived(frame, view)`` takes the frame with its surfaces already extracted).
``albot2d.evaluation.drive_mappers`` then extracts each frame's surfaces once per distinct
``ExtractionParams`` and shares them; ``observe_perceived(frame, view)`` must do exactly
what ``observe(frame)`` does after extracting ``view``. Mappers that want raw scans
implement ``observe`` only and still get every frame, and so does a subclass that
overrides ``observe`` but not ``observe_perceived`` (``takes_perceived_views``), so a
plugin extending a built-in mapper's ``observe`` keeps working.

View-based mappers (Albot1) also implement ``ViewBasedMapper``: their route map of
remembered views, their global map as it was after any past update (the map history) and
the record of each update; loop-closing mappers implement ``LoopClosingMapper``
(``slam_stats``). Scoring and the figures use these protocols, never attribute probing.
"""

from __future__ import annotations

import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import NamedTuple, Protocol, TypeGuard, runtime_checkable

import numpy as np
from numpy.typing import NDArray

from albot2d.frames import Frame
from albot2d.geometry import Pose
from albot2d.mapping.albot1.route_map import RouteMap
from albot2d.perception import ExtractionParams, Surfaces
from albot2d.reprs import compact_fields

__all__ = [
    "LoopClosingMapper",
    "MapSnapshot",
    "MapUpdate",
    "Mapper",
    "MapperCounts",
    "PerceivingMapper",
    "StageTimer",
    "ViewBasedMapper",
    "takes_perceived_views",
]


class MapSnapshot(NamedTuple):
    """Surfaces of the map at one moment: ``segments (M, 4)`` and ``map_ids (M,)``."""

    segments: NDArray[np.float64]
    map_ids: NDArray[np.int64]

    def __repr__(self) -> str:
        return compact_fields("MapSnapshot", segments=self.segments, map_ids=self.map_ids)


@dataclass(frozen=True, slots=True)
class MapperCounts:
    """Process counts: views seen, local maps remembered, and how they were localised."""

    views: int = 0
    local_maps: int = 0
    triangulations: int = 0
    path_integrations: int = 0


class StageTimer:
    """Accumulates wall time per named stage with ``perf_counter_ns`` (≈ 100 ns per use).

    Besides the run totals it keeps the time of each stage since the last ``take_view()``,
    so a driver can record per-view stage times (``steps.csv``).
    """

    def __init__(self) -> None:
        self.total_ns: dict[str, int] = {}
        self.calls: dict[str, int] = {}
        self.view_ns: dict[str, int] = {}

    def stage(self, name: str) -> _Stage:
        """A context manager timing its block as ``name`` (a class, not a generator: a
        mapper times a few stages per view and ``contextlib``'s cost 1–2 µs each)."""
        return _Stage(self, name)

    def add(self, name: str, ns: int) -> None:
        """Count ``ns`` nanoseconds measured elsewhere (e.g. a shared extraction) to ``name``."""
        self.total_ns[name] = self.total_ns.get(name, 0) + ns
        self.calls[name] = self.calls.get(name, 0) + 1
        self.view_ns[name] = self.view_ns.get(name, 0) + ns

    def take_view(self) -> dict[str, int]:
        """Nanoseconds per stage since the previous call (the view just processed)."""
        out, self.view_ns = self.view_ns, {}
        return out

    def mean_ms_per(self, n_views: int) -> dict[str, float]:
        """Mean milliseconds per view for each stage (total stage time / views)."""
        if n_views <= 0:
            return {k: 0.0 for k in self.total_ns}
        return {k: v / 1e6 / n_views for k, v in self.total_ns.items()}


class _Stage:
    """``StageTimer.stage``'s context manager: adds the block's time on exit, even on error."""

    __slots__ = ("_name", "_t0", "_timer")

    def __init__(self, timer: StageTimer, name: str) -> None:
        self._timer, self._name = timer, name

    def __enter__(self) -> None:
        self._t0 = time.perf_counter_ns()

    def __exit__(self, *exc: object) -> None:
        self._timer.add(self._name, time.perf_counter_ns() - self._t0)


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


@runtime_checkable
class PerceivingMapper(Mapper, Protocol):
    """A mapper that can take a frame's surfaces extracted for it (see the module docstring)."""

    def perception(self) -> ExtractionParams:
        """The extraction settings this mapper's views are made with."""

    def observe_perceived(self, frame: Frame, view: Surfaces) -> None:
        """Consume the next frame, its surfaces ``view`` extracted with ``perception()``."""


class MapUpdate(Protocol):
    """What one global-map update of a view-based mapper deleted (``oldest_affected``: the
    oldest local map whose surfaces the view touched, -1 for none)."""

    @property
    def map_id(self) -> int: ...
    @property
    def frame_index(self) -> int: ...
    @property
    def deleted_current(self) -> int: ...
    @property
    def deleted_older(self) -> int: ...
    @property
    def oldest_affected(self) -> int: ...


@runtime_checkable
class ViewBasedMapper(Mapper, Protocol):
    """A mapper that remembers views as local maps on a route, like Albot1."""

    update_log: Sequence[MapUpdate]

    def route_map(self) -> RouteMap:
        """The remembered views (local maps) and how each was placed."""

    def global_map(self, at_update: int | None = None) -> MapSnapshot:
        """The global map now, or as it was right after update ``at_update`` (history)."""


@runtime_checkable
class LoopClosingMapper(Mapper, Protocol):
    """A mapper that closes loops (keyframes, verified closures, optimisations)."""

    def slam_stats(self) -> Mapping[str, int]:
        """Counters of its loop closing: keyframes, candidates accepted/rejected, …"""


def takes_perceived_views(mapper: object) -> TypeGuard[PerceivingMapper]:
    """Whether a driver may call ``mapper.observe_perceived`` instead of ``observe``.

    True for a ``PerceivingMapper`` whose ``observe`` is defined no later in its class
    hierarchy than its ``observe_perceived``: a subclass that overrides only ``observe``
    (to add to it) must be fed through its ``observe``.
    """
    if not isinstance(mapper, PerceivingMapper):
        return False
    mro = type(mapper).__mro__
    defines = [next((i for i, c in enumerate(mro) if name in vars(c)), len(mro))
               for name in ("observe", "observe_perceived")]  # fmt: skip
    return defines[0] >= defines[1]
