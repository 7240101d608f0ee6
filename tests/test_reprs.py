"""Printing big values shows what they are in one short line, not their arrays."""

from __future__ import annotations

import itertools

from albot2d.geometry import Pose
from albot2d.mapping import Albot1
from albot2d.perception import extract_surfaces
from albot2d.sim.simulator import Simulator
from worldgen import plan_tour
from worldgen.generate import generate


def test_compact_reprs() -> None:
    world = generate("rooms", seed=3, width_m=15.0, height_m=15.0)
    frames = list(itertools.islice(Simulator(world, seed=3).drive(
        plan_tour(world, "loop", 20.0), "dataset3"), 12))  # fmt: skip
    mapper = Albot1()
    for frame in frames:
        mapper.observe(frame)
    values = [
        frames[-1],
        frames[-1].scan,
        extract_surfaces(frames[-1].scan),
        mapper.route,
        mapper.route[-1],
        world,
        world.roadmap,
        plan_tour(world, "loop", 20.0),
        mapper.global_map(),
    ]
    for value in values:
        text = repr(value)
        assert "array(" not in text and "\n" not in text and len(text) < 400, text
    assert repr(frames[0].scan).startswith("Scan(181 beams, ")
    assert repr(mapper.route).startswith(f"RouteMap({len(mapper.route)} local maps: 1 start")
    assert "view=Surfaces(segments=<(" in repr(mapper.route[-1])
    assert repr(Pose(1.0, 2.5, -0.25)) == "Pose(x=1.0, y=2.5, theta=-0.25)"
    assert repr(world).startswith("World(kind='rooms', seed=3, size_m=(15, 15), walls=")
    assert repr(mapper.global_map()).startswith("MapSnapshot(segments=<(")
