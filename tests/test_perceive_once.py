"""Perceive once: drive_mappers extracts each frame's surfaces once per distinct setting and
shares them, with exactly the results of every mapper extracting for itself."""

from __future__ import annotations

import numpy as np

from albot2d.evaluation import drive_mappers
from albot2d.frames import Frame
from albot2d.geometry import Pose
from albot2d.mapping import (
    Albot1,
    Albot1Params,
    GroundTruthIntegration,
    NaiveIntegration,
    PerceivingMapper,
)
from albot2d.mapping.albot1.global_map import MapSnapshot
from albot2d.mapping.protocol import MapperCounts, takes_perceived_views
from albot2d.perception import ExtractionParams
from albot2d.seeding import make_rng
from albot2d.sim.simulator import Simulator
from worldgen.generate import generate
from worldgen.tours import make_tour


class RawScans:
    """A user's mapper that wants raw scans only (no ``perception``)."""

    name = "raw"

    def __init__(self) -> None:
        self.seen: list[int] = []

    def observe(self, frame: Frame) -> None:
        self.seen.append(frame.index)

    def pose(self) -> Pose:
        return Pose()

    def global_map(self) -> MapSnapshot:
        return MapSnapshot(np.zeros((0, 4)), np.zeros(0, np.int64))

    def trajectory(self) -> np.ndarray:
        return np.zeros((len(self.seen), 3))

    def counts(self) -> MapperCounts:
        return MapperCounts(len(self.seen))

    def timings_ms(self) -> dict[str, float]:
        return {}


class CountingNaive(NaiveIntegration):
    """A plugin extending a built-in mapper's ``observe`` only: must still be called."""

    def __init__(self) -> None:
        super().__init__()
        self.calls = 0

    def observe(self, frame: Frame) -> None:
        self.calls += 1
        super().observe(frame)


def frames(n: int) -> list[Frame]:
    world = generate("rooms", seed=4, width_m=15.0, height_m=15.0)
    tour = make_tour(world, make_rng(1), kind="loop", min_length_m=20.0)
    return list(zip(range(n), Simulator(world, seed=2).drive(tour, "dataset3"), strict=False))


def make_mappers() -> dict[str, object]:
    coarse = ExtractionParams(split_distance_m=0.08, merge_distance_m=0.08)
    return {
        "albot1": Albot1(),
        "naive": NaiveIntegration(),
        "truth": GroundTruthIntegration(),
        "coarse": NaiveIntegration(coarse),  # another setting: its own extraction
        "albot1_coarse": Albot1(Albot1Params(extraction=coarse)),
        "raw": RawScans(),
        "counting": CountingNaive(),
    }


def test_shared_extraction_gives_every_mapper_its_own_results_bit_for_bit() -> None:
    stream = [f for _, f in frames(150)]
    shared = make_mappers()
    trace = drive_mappers(iter(stream), shared)  # type: ignore[arg-type]
    alone = make_mappers()
    for frame in stream:
        for mapper in alone.values():
            mapper.observe(frame)  # type: ignore[attr-defined]
    assert sum(isinstance(m, PerceivingMapper) for m in shared.values()) == 6
    assert sum(takes_perceived_views(m) for m in shared.values()) == 5
    for name, mapper in shared.items():
        other = alone[name]
        np.testing.assert_array_equal(mapper.trajectory(), other.trajectory())  # type: ignore[attr-defined]
        np.testing.assert_array_equal(
            mapper.global_map().segments,  # type: ignore[attr-defined]
            other.global_map().segments,
        )  # type: ignore[attr-defined]
        assert mapper.counts() == other.counts()  # type: ignore[attr-defined]
    assert len(shared["albot1"].global_map().segments) > 10  # type: ignore[attr-defined]
    assert shared["albot1"].counts().local_maps > 3  # type: ignore[attr-defined]
    assert shared["counting"].calls == 150  # type: ignore[attr-defined]
    assert shared["raw"].seen == [f.index for f in stream]  # type: ignore[attr-defined]
    # One extraction per distinct setting and view, charged to each mapper's stages.
    steps = trace.step_times
    assert steps.rows == 150 and "albot1.extraction_ms" not in steps.columns
    assert set(shared["albot1"].timings_ms()) >= {"extraction", "tracking"}  # type: ignore[attr-defined]
    assert shared["albot1"].timer.calls["extraction"] == 150  # type: ignore[attr-defined]
