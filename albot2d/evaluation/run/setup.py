"""The one setup path: a run description (``RunSpec``) → its world, tour and simulator.

``albot2d world``, ``simulate``, ``run`` and ``fuzz`` (and the experiments, through
``run_experiment``) all build a run here, so the same options give the same world, tour
and simulator everywhere:

- ``check_spec(spec)``: every name in the spec resolved (profile, noise presets, mappers,
  world kind and parameters, world file) before anything runs; bad input → ``InputError``;
- ``build_world(spec)``: ``worldgen.generate(kind, seed=spec.seed, **world_params)`` or the
  world file;
- ``plan_run_tour(spec, world)``: the named route (the world's start moved to its first
  waypoint) or ``worldgen.plan_tour`` (the world seed's ``"tour"`` stream);
- ``make_simulator(world, spec)``: seeded with the run seed's ``"simulator"`` stream
  (``albot2d.seeding.RUN_STREAMS``), with the spec's odometry and laser noise presets;
- ``build_run(spec)`` → ``RunSetup``: all of the above.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Mapping
from dataclasses import asdict, dataclass, field
from typing import TYPE_CHECKING, Any

from albot2d.control.exploration import EXPLORE_TOUR
from albot2d.errors import InputError
from albot2d.seeding import RUN_STREAMS, stream_seed
from worldgen.tours import TOUR_KINDS, plan_tour
from worldgen.world import Tour, World

if TYPE_CHECKING:
    from albot2d.mapping.protocol import Mapper
    from albot2d.sim.driving import DrivingProfile
    from albot2d.sim.simulator import Simulator

__all__ = [
    "DEFAULT_MAPPERS",
    "RunSetup",
    "RunSpec",
    "build_run",
    "build_world",
    "check_spec",
    "make_simulator",
    "plan_run_tour",
]

DEFAULT_MAPPERS = ("albot1", "naive", "truth")


@dataclass(frozen=True)
class RunSpec:
    """What to simulate: everything needed to reproduce the run.

    Give ``kind`` (a generated world, with ``world_params`` overrides) or ``world_file``.
    ``noise``/``laser_noise`` name presets; ``max_frames`` cuts the run short.
    """

    seed: int = 0
    kind: str | None = "office"
    world_file: str | None = None
    world_params: Mapping[str, Any] = field(default_factory=dict)
    profile: str = "dataset1"
    noise: str = "typical"
    laser_noise: str = "sick_lms200"
    tour_kind: str = "loop"
    tour_length_m: float = 100.0
    # True: tour_length_m is a minimum (the tour may be much longer: ``--min-tour-length``);
    # False: the tour is tour_length_m long within worldgen's TOUR_LENGTH_TOLERANCE
    tour_length_is_minimum: bool = False
    # a route named by the world (``worldgen.routes``, e.g. the fig6 kind's "fig6"): the
    # tour drives its waypoints from its first one; tour_kind/tour_length_m are then unused
    route: str | None = None
    mappers: tuple[str, ...] = DEFAULT_MAPPERS
    max_frames: int | None = None

    def __post_init__(self) -> None:
        from albot2d.sim.laser import laser_noise_preset

        if isinstance(self.seed, bool) or not isinstance(self.seed, int) or self.seed < 0:
            raise InputError(f"RunSpec.seed must be a non-negative integer, got {self.seed!r}")
        if (self.kind is None) == (self.world_file is None):
            raise InputError("RunSpec needs a world kind or a world file (not both)")
        if self.world_file is not None and self.world_params:
            raise InputError("RunSpec.world_params apply to generated worlds, not a world file")
        length = self.tour_length_m
        if (
            isinstance(length, bool)
            or not isinstance(length, int | float)
            or not (math.isfinite(length) and length > 0)
        ):
            raise InputError(f"RunSpec.tour_length_m must be a positive number, got {length!r}")
        if self.tour_kind not in (*TOUR_KINDS, EXPLORE_TOUR):
            raise InputError(
                f"unknown tour kind {self.tour_kind!r}; valid: "
                f"{', '.join((*TOUR_KINDS, EXPLORE_TOUR))}"
            )
        laser_noise_preset(self.laser_noise)
        if self.max_frames is not None and (
            isinstance(self.max_frames, bool) or not isinstance(self.max_frames, int)
            or self.max_frames <= 0
        ):  # fmt: skip
            raise InputError(f"max_frames must be a positive integer, got {self.max_frames!r}")
        if not self.mappers:
            raise InputError("give at least one mapper")
        object.__setattr__(self, "mappers", tuple(self.mappers))
        object.__setattr__(self, "world_params", dict(self.world_params))

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)

    def tour_record(self, tour: Tour) -> dict[str, Any]:
        """The tour as a report records it: its kind, the length asked for (and whether as
        a minimum or a length), the length planned and its number of waypoints."""
        return {
            "kind": tour.kind,
            "requested_length_m": self.tour_length_m,
            "requested_as": "minimum" if self.tour_length_is_minimum else "length",
            "length_m": tour.length_m,
            "waypoints": len(tour.waypoints),
        }

    @classmethod
    def from_report(cls, report: Mapping[str, Any], where: str = "report") -> RunSpec:
        """The spec recorded in a report written by ``albot2d run``."""
        if report.get("command") != "run":
            raise InputError(
                f"{where}: not a report of `albot2d run` (command "
                f"{report.get('command')!r}); only runs can be reproduced"
            )
        spec = report.get("params", {}).get("spec")
        if not isinstance(spec, dict):
            raise InputError(f"{where}: params.spec is missing; cannot reproduce the run")
        values = dict(spec)
        values["mappers"] = tuple(values.get("mappers", DEFAULT_MAPPERS))
        # reports written before the field existed planned their tour length as a minimum
        values.setdefault("tour_length_is_minimum", True)
        fields = set(cls.__dataclass_fields__)
        unknown = sorted(set(values) - fields)
        if unknown:
            raise InputError(f"{where}: params.spec has unknown field(s) {', '.join(unknown)}")
        return cls(**values)


def check_spec(spec: RunSpec) -> dict[str, Callable[[], Mapper]]:
    """Everything a run needs that can be checked without running it; returns the
    spec's mapper factories (name → factory, in the spec's order)."""
    from pathlib import Path

    from albot2d.mapping.registry import resolve_mappers
    from albot2d.sim.driving import get_profile
    from albot2d.sim.odometry import noise_preset

    get_profile(spec.profile)
    noise_preset(spec.noise)
    factories = resolve_mappers(list(spec.mappers))
    if spec.world_file is not None and not Path(spec.world_file).is_file():
        raise InputError(f"{spec.world_file}: no such world file")
    if spec.kind is not None:
        from worldgen.generate import make_params

        make_params(spec.kind, **spec.world_params)
    return factories


def build_world(spec: RunSpec) -> World:
    """The spec's world: its file, or generated from its kind, parameters and seed."""
    if spec.world_file is not None:
        from worldgen.io import load

        return load(spec.world_file)
    assert spec.kind is not None  # RunSpec: a kind or a world file
    from worldgen.generate import generate

    return generate(spec.kind, seed=spec.seed, **spec.world_params)


def plan_run_tour(spec: RunSpec, world: World) -> tuple[World, Tour]:
    """The tour the spec drives, and the world with the start it begins at.

    A named route starts at its own first waypoint (the world's start is moved there);
    otherwise ``worldgen.plan_tour`` plans ``spec.tour_kind`` on the world's seed.
    """
    if spec.route is not None:
        from worldgen.routes import route_start, route_tour

        tour = route_tour(world, spec.route)
        return dataclasses.replace(world, start=route_start(world, spec.route)), tour
    if spec.tour_kind == EXPLORE_TOUR:
        # Nothing is planned: the explorer decides as it goes (the run's tour becomes the
        # path it drove, ``albot2d.control.exploration``).
        return world, Tour(waypoints=world.start.position[None, :], kind=EXPLORE_TOUR)
    return world, plan_tour(
        world,
        kind=spec.tour_kind,
        length_m=spec.tour_length_m,
        at_least=spec.tour_length_is_minimum,
    )


def make_simulator(world: World, spec: RunSpec) -> Simulator:
    """The simulator of a run: the run seed's ``"simulator"`` stream, the spec's noise."""
    from albot2d.sim.laser import laser_noise_preset
    from albot2d.sim.odometry import noise_preset
    from albot2d.sim.simulator import Simulator

    return Simulator(
        world, seed=stream_seed(spec.seed, RUN_STREAMS, "simulator"),
        odometry=noise_preset(spec.noise), laser_noise=laser_noise_preset(spec.laser_noise),
    )  # fmt: skip


@dataclass(frozen=True, eq=False)
class RunSetup:
    """A run ready to drive: ``simulator.drive(tour, profile)`` gives its frames, and
    ``mapper_factories`` make the spec's mappers."""

    spec: RunSpec
    world: World
    tour: Tour
    profile: DrivingProfile
    simulator: Simulator
    mapper_factories: Mapping[str, Callable[[], Mapper]]

    def __repr__(self) -> str:
        return (
            f"RunSetup({self.world.kind} seed {self.world.seed}, {self.tour.kind} tour "
            f"{self.tour.length_m:.0f} m, {self.profile.name})"
        )


def build_run(spec: RunSpec) -> RunSetup:
    """World, tour, driving profile and simulator of ``spec`` (checked first)."""
    from albot2d.sim.driving import get_profile

    factories = check_spec(spec)
    world, tour = plan_run_tour(spec, build_world(spec))
    return RunSetup(
        spec, world, tour, get_profile(spec.profile), make_simulator(world, spec), factories
    )
