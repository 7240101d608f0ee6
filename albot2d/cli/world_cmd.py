"""``albot2d world``: generate (or import) a world, save it as JSON, optionally draw it.

Everything is built in memory first; the JSON and the PNG are then written atomically
together, so a failure (bad parameter, unplottable world, unwritable path) leaves no
output file at all. Prints a one-line summary.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TYPE_CHECKING, TypedDict

from albot2d.atomic import atomic_paths
from albot2d.cli.common import choices
from albot2d.cli.options import ParamValue, parse_param, positive_number, seed_value, world_params
from albot2d.errors import InputError
from worldgen.tours import TOUR_KINDS, TOUR_LENGTH_TOLERANCE

if TYPE_CHECKING:
    from albot2d.cli.options import Subcommands
    from worldgen.world import Tour, World

__all__ = ["parse_param", "register", "run", "summary"]

DEFAULT_TOUR_LENGTH_M = 100.0
HOUSEEXPO_PARAMS = ("robot_radius_m", "clearance_margin_m")


def register(subparsers: Subcommands) -> None:
    p = subparsers.add_parser(
        "world",
        help="generate a world (or import a HouseExpo plan) and save it as JSON",
        description=__doc__,
    )
    source = p.add_argument_group("what to build (give --kind or --from-houseexpo)")
    source.add_argument("--kind", help=f"world kind: {', '.join(choices().world_kinds)}")
    source.add_argument("--from-houseexpo", metavar="PLAN.json", help="import a HouseExpo plan")
    p.add_argument(
        "--seed", metavar="N",
        help="non-negative integer seed (default 0; for --from-houseexpo it picks the start)",
    )  # fmt: skip
    p.add_argument("--width", metavar="W", help="world width in metres (param width_m)")
    p.add_argument("--height", metavar="H", help="world height in metres (param height_m)")
    p.add_argument(
        "--param", action="append", default=[], metavar="NAME=VALUE",
        help="set a generator parameter, e.g. --param door_width_min_m=0.9 (repeatable)",
    )  # fmt: skip
    p.add_argument("--out", required=True, metavar="world.json", help="output world file")
    p.add_argument("--png", metavar="world.png", help="also draw the world to this PNG")
    p.add_argument("--tour-kind", default="loop", help=f"tour to plan: {', '.join(TOUR_KINDS)}")
    p.add_argument(
        "--tour-length", metavar="METRES",
        help=f"tour length in metres: the tour is METRES to {1 + TOUR_LENGTH_TOLERANCE:g}×METRES "
        f"long (default {DEFAULT_TOUR_LENGTH_M:g})",
    )  # fmt: skip
    p.add_argument(
        "--min-tour-length", metavar="METRES",
        help="plan a tour at least METRES long (it may be several times longer) instead",
    )  # fmt: skip
    p.add_argument("--no-tour", action="store_true", help="do not plan a tour")
    p.set_defaults(handler=run)


class _HouseExpoSizes(TypedDict, total=False):
    """The ``--param`` values ``--from-houseexpo`` takes (``HOUSEEXPO_PARAMS``)."""

    robot_radius_m: float
    clearance_margin_m: float


def _houseexpo_sizes(params: dict[str, ParamValue]) -> _HouseExpoSizes:
    """The robot's sizes given for an imported plan: numbers (metres), nothing else."""
    unknown = sorted(set(params) - set(HOUSEEXPO_PARAMS))
    if unknown:
        raise InputError(
            f"--from-houseexpo takes only {', '.join(HOUSEEXPO_PARAMS)}; "
            f"got {', '.join(unknown)} (size comes from the plan)"
        )
    metres: dict[str, float] = {}
    for name, value in params.items():
        if isinstance(value, bool | str):
            raise InputError(f"--param {name} must be a number of metres, got {value!r}")
        metres[name] = value
    sizes = _HouseExpoSizes()
    if "robot_radius_m" in metres:
        sizes["robot_radius_m"] = metres["robot_radius_m"]
    if "clearance_margin_m" in metres:
        sizes["clearance_margin_m"] = metres["clearance_margin_m"]
    return sizes


def _build_world(
    args: argparse.Namespace, seed: int | None, params: dict[str, ParamValue]
) -> World:
    import worldgen

    if args.from_houseexpo is not None:
        if args.kind is not None:
            raise InputError("give --kind or --from-houseexpo, not both")
        return worldgen.from_houseexpo(args.from_houseexpo, seed=seed, **_houseexpo_sizes(params))
    if args.kind is None:
        raise InputError("give --kind KIND or --from-houseexpo PLAN.json")
    from albot2d.evaluation.run.setup import RunSpec, build_world

    # generate() rejects an unknown kind with the list of valid kinds, and bad
    # parameters with the field name and value.
    return build_world(
        RunSpec(seed=0 if seed is None else seed, kind=args.kind, world_params=params)
    )


def _tour_options(args: argparse.Namespace) -> tuple[str, float, bool] | None:
    """Checked (kind, length, whether the length is a minimum) of the tour to plan, or
    None for ``--no-tour``."""
    if args.tour_kind not in TOUR_KINDS:
        raise InputError(f"unknown --tour-kind {args.tour_kind!r}; valid: {', '.join(TOUR_KINDS)}")
    length = positive_number(args.tour_length, "--tour-length")
    minimum = positive_number(args.min_tour_length, "--min-tour-length")
    if length is not None and minimum is not None:
        raise InputError("give --tour-length or --min-tour-length, not both")
    if args.no_tour:
        return None
    if minimum is not None:
        return args.tour_kind, float(minimum), True
    return args.tour_kind, float(length or DEFAULT_TOUR_LENGTH_M), False


def _plan_tour(world: World, options: tuple[str, float, bool] | None) -> Tour | None:
    if options is None:
        return None
    from worldgen.tours import plan_tour

    kind, length, at_least = options
    # the tour of ``albot2d simulate``/``run`` (the world seed's "tour" stream)
    return plan_tour(world, kind=kind, length_m=length, at_least=at_least)


def _write_together(outputs: dict[Path, bytes]) -> None:
    """Write every file atomically; if any write fails, none of them appears."""
    with atomic_paths(outputs) as temps:
        for path, tmp in temps.items():
            tmp.write_bytes(outputs[path])


def summary(world: World, tour: Tour | None, out: Path) -> str:
    seed = "-" if world.seed is None else world.seed
    line = (
        f"{world.kind} seed {seed}: {world.width_m:.1f} x {world.height_m:.1f} m, "
        f"{len(world.walls)} walls, {len(world.clutter)} clutter, "
        f"{len(world.roadmap.nodes)} roadmap nodes"
    )
    if tour is not None:
        line += f", {tour.kind} tour {tour.length_m:.1f} m"
    return f"{line} -> {out}"


def run(args: argparse.Namespace) -> int:
    from worldgen.io import world_to_json

    out = Path(args.out)
    png = None if args.png is None else Path(args.png)
    if png is not None and png.resolve() == out.resolve():
        raise InputError(f"--out and --png are the same file: {out}")
    seed = seed_value(args.seed)
    params = world_params(args)
    tour_options = _tour_options(args)
    world = _build_world(args, seed, params)
    tour = _plan_tour(world, tour_options)
    outputs = {out: world_to_json(world).encode("utf-8")}
    if png is not None:
        try:
            from albot2d.viz.world import render_world_png

            outputs[png] = render_world_png(world, tour=tour)
        except ImportError as exc:
            raise InputError(f"--png needs matplotlib ({exc}); pip install 'albot2d[viz]'") from exc
    _write_together(outputs)
    print(summary(world, tour, out))
    return 0
