"""``generate(kind, seed=..., **params)``: the one entry point for procedural worlds.

Validates the kind and its parameters, draws everything from one Generator made from the
seed, lays the kind out, assembles the World (walls, roadmap, start) and adds moving
obstacles. Same kind, seed and parameters → bit-identical World in any process.

``world.features`` (JSON-ready lists and numbers) holds what each kind promises:

- every kind: ``loops`` (independent cycles of the roadmap); ``dynamic_obstacles`` (count)
  when asked for.
- ``rooms``/``office``/``mixed``: ``doorways`` ``(K, 4)`` segments across each door on the
  wall centre line, ``door_widths_m``, ``wall_thickness_m``.
- ``rooms``: ``rooms``, ``room_rects`` (interiors), ``room_area_m2`` [min, max].
- ``corridors``: ``corridor_segments`` (centre lines), ``corridor_widths_m``,
  ``corridor_width_m`` [min, max], ``dead_ends`` as ``[x, y, ux, uy, reach_m]`` (end of
  the centre line, outward direction, how far the corridor goes on), ``junctions``,
  ``corners``, ``corridor_loops``.
- ``open``: ``hall_area_m2``, ``hall_fill_ratio`` (area / bounding box), ``boundary_vertices``,
  ``pillars``, ``partition_walls``.
- ``office``: ``rooms``, ``corridor_width_m``, ``corridor_ring`` (closed centre line),
  ``ring_length_m``, ``cross_corridors``, ``open_areas`` (hall rectangles), ``openings``.
- ``mixed``: ``parts`` (kind, bounds, connections to the spine, the part's own features),
  ``part_kinds``, ``spine_width_m``.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

from albot2d.plainjson import to_plain
from albot2d.seeding import make_rng
from albot2d.validation import params_from_mapping
from worldgen.assemble import make_world
from worldgen.kinds import get_kind, world_kinds
from worldgen.kinds._dynamic import add_dynamic_obstacles
from worldgen.params import CommonParams
from worldgen.world import World

__all__ = ["generate", "kind_names", "make_params"]


def kind_names() -> tuple[str, ...]:
    """The names of every known world kind (``worldgen.kinds.world_kinds``)."""
    return tuple(world_kinds())


def make_params(kind: str, **params: Any) -> CommonParams:
    """The validated parameter dataclass of ``kind`` (InputError on unknown kind or names)."""
    cls = get_kind(kind).params
    given = {k: v for k, v in params.items() if v is not None or k not in {"width_m", "height_m"}}
    return params_from_mapping(cls, given, where=f"world kind {kind!r}")


def generate(
    kind: str,
    *,
    seed: int,
    width_m: float | None = None,
    height_m: float | None = None,
    **params: Any,
) -> World:
    """A procedural World of ``kind`` (one of ``kind_names()``) from ``seed``.

    ``width_m``/``height_m`` default per kind (40x40 m; office and mixed 60x40 m); other
    keyword parameters are the fields of the kind's dataclass in ``worldgen.params``.
    """
    p = make_params(kind, width_m=width_m, height_m=height_m, **params)
    rng = make_rng(seed)
    rect = np.array([0.0, 0.0, p.width_m, p.height_m])
    record = get_kind(kind)
    layout = record.layout(rect, p, rng)
    doorways = layout.doorway_array()
    features: dict[str, Any] = dict(layout.features)
    if len(doorways) or record.reports_doorways:
        widths = np.hypot(doorways[:, 2] - doorways[:, 0], doorways[:, 3] - doorways[:, 1])
        features["doorways"] = doorways.tolist()
        features["door_widths_m"] = widths.tolist()
    world = make_world(
        layout.floor_geometry(),
        clutter=layout.clutter,
        kind=kind,
        seed=int(seed),
        params=dataclasses.asdict(p),
        features=to_plain(features, where="features", into="a world's features"),
        robot_radius_m=p.robot_radius_m,
        clearance_margin_m=p.clearance_margin_m,
        rng=rng,
        seed_points=layout.seeds(),
        links=layout.link_array(),
        bounds=(0.0, 0.0, p.width_m, p.height_m),
    )
    if p.dynamic_obstacles:
        movers = add_dynamic_obstacles(world, p.dynamic_obstacles, rng)
        feats = dict(world.features, dynamic_obstacles=len(movers))
        world = dataclasses.replace(world, dynamic_obstacles=movers, features=feats)
    return world
