"""Shared test helpers: simulate a run, then map it ("simulate + map").

The invariant, property and SLAM tests drive the same sequence: a world, a tour, the
simulator's frames, a mapper fed every frame. ``simulate`` and ``office_loop`` make the
frames (real pymunk simulations); ``map_frames`` feeds any mapper; ``run_albot1`` maps with
Albot1 and its invariant recorders attached (global-map updates and the views given);
``check_mapper_contract`` checks a mapper against the protocol's signatures and on a run;
``small_run`` is the quick ``RunSpec`` the run-pipeline tests share.
"""

from __future__ import annotations

import inspect
import typing
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, TypeVar

import numpy as np

from albot2d.evaluation.checks.invariants import UpdateRecorder, ViewRecorder
from albot2d.evaluation.run.setup import RunSpec
from albot2d.frames import Frame
from albot2d.mapping import Albot1, Albot1Params, Mapper, MapperCounts
from albot2d.seeding import make_rng
from albot2d.sim.laser import LaserNoise
from albot2d.sim.odometry import NOISE_PRESETS, noise_preset
from albot2d.sim.simulator import Simulator
from worldgen import plan_tour
from worldgen.generate import generate
from worldgen.tours import make_tour
from worldgen.world import World

__all__ = [
    "Albot1Run",
    "check_mapper_contract",
    "map_frames",
    "office_loop",
    "run_albot1",
    "simulate",
    "small_run",
]

M = TypeVar("M", bound=Mapper)


def simulate(
    world: World,
    seed: int,
    *,
    noise: str = "typical",
    laser: LaserNoise | None = None,
    profile: str = "dataset3",
    length_m: float = 20.0,
) -> list[Frame]:
    """The frames of a loop tour of at least ``length_m`` through ``world``."""
    tour = make_tour(world, make_rng(seed), kind="loop", min_length_m=length_m)
    sim = Simulator(
        world,
        seed=seed,
        odometry=NOISE_PRESETS[noise],
        laser_noise=laser if laser is not None else LaserNoise(),
    )
    return list(sim.drive(tour, profile=profile))


def small_run(seed: int, **changes: Any) -> RunSpec:
    """A short run: a 20 m tour (profile dataset3) through a 15 m × 15 m rooms world;
    ``changes`` set any other ``RunSpec`` field."""
    return RunSpec(
        kind="rooms",
        seed=seed,
        world_params={"width_m": 15.0, "height_m": 15.0},
        profile="dataset3",
        tour_length_m=20.0,
        **changes,
    )


SLAM_MISSING = "the [slam] extra is not installed (pip install -e '.[slam]')"


def require_slam_extra() -> None:
    """Skip (with the reason) unless kiss-icp and gtsam import."""
    import pytest

    pytest.importorskip("kiss_icp", reason=SLAM_MISSING)
    pytest.importorskip("gtsam", reason=SLAM_MISSING)


def office_loop() -> tuple[World, list[Frame]]:
    """The SLAM tests' run: a ~30 m loop through a small office, dataset3 profile, typical
    odometry noise."""
    world = generate("office", seed=0, width_m=30, height_m=24)
    tour = plan_tour(world, "loop", 30.0, at_least=True)  # the loop these tests were written on
    sim = Simulator(world, seed=0, odometry=noise_preset("typical"))
    return world, list(sim.drive(tour, "dataset3"))


def map_frames(mapper: M, frames: list[Frame]) -> M:
    """Feed every frame to ``mapper``; returns it."""
    for frame in frames:
        mapper.observe(frame)
    return mapper


@dataclass(frozen=True)
class Albot1Run:
    """Albot1 after a run, with what its invariant recorders saw."""

    mapper: Albot1
    frames: list[Frame]
    updates: UpdateRecorder
    views: ViewRecorder


def run_albot1(frames: list[Frame], params: Albot1Params | None = None) -> Albot1Run:
    """Map ``frames`` with Albot1, checking algorithm #5 at every update (raises at once)
    and keeping every view for ``check_local_map_rule``."""
    mapper = Albot1(params)
    updates = UpdateRecorder().attach(mapper)
    views = ViewRecorder().attach(mapper)
    return Albot1Run(map_frames(mapper, frames), frames, updates, views)


def _hints(func: Callable[..., object]) -> dict[str, object]:
    return typing.get_type_hints(func)


def check_mapper_contract(mapper: Mapper, frames: list[Frame]) -> None:
    """What ``isinstance(mapper, Mapper)`` does not check (it looks at member names only):

    - every protocol method takes the protocol's parameters (same names and kinds, extras
      only with defaults) and is annotated with the protocol's return type;
    - on a real run: ``observe`` takes every frame; ``trajectory`` is ``(F, 3)`` finite
      float64, one row per frame, its last row ``pose()``; ``counts().views`` is F and at
      least one local map is kept; ``global_map`` is ``(M, 4)`` finite surfaces with M map
      ids; ``timings_ms`` maps stage names to non-negative milliseconds.
    """
    assert isinstance(mapper, Mapper) and isinstance(mapper.name, str) and mapper.name
    for member in ("observe", "pose", "global_map", "trajectory", "counts", "timings_ms"):
        spec = inspect.signature(getattr(Mapper, member))
        impl = inspect.signature(getattr(type(mapper), member))
        wanted = [(p.name, p.kind) for p in spec.parameters.values()]
        given = [(p.name, p.kind) for p in impl.parameters.values()][: len(wanted)]
        assert given == wanted, (member, impl, spec)
        extra = list(impl.parameters.values())[len(wanted) :]
        assert all(p.default is not inspect.Parameter.empty for p in extra), (member, impl)
        protocol_return = _hints(getattr(Mapper, member))["return"]
        assert _hints(getattr(type(mapper), member))["return"] == protocol_return, member
    map_frames(mapper, frames)
    trajectory = mapper.trajectory()
    assert trajectory.dtype == np.float64 and trajectory.shape == (len(frames), 3)
    assert np.isfinite(trajectory).all()
    assert np.allclose(mapper.pose().as_array(), trajectory[-1])
    counts = mapper.counts()
    assert isinstance(counts, MapperCounts)
    assert counts.views == len(frames) and counts.local_maps >= 1
    snap = mapper.global_map()
    assert snap.segments.shape == (len(snap.map_ids), 4) and len(snap.segments) > 0
    assert np.isfinite(snap.segments).all()
    timings = mapper.timings_ms()
    assert timings and all(isinstance(k, str) and v >= 0.0 for k, v in timings.items())
