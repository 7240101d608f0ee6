"""Albot1's CPU time per view by stage on the default office run, and sim + Albot1 steps/s.

Run: ``python -m benchmarks.albot1_stages`` (about a minute). CPU time (``process_time``),
so the machine's load counts less; run it in two checkouts to compare them. The stages
are timed by wrappers on the stage functions; the steps/s runs without them, best of
``ROUNDS`` after one untimed round, on the default run's first 3,000 steps and on
``benchmarks/test_simulator.py``'s 60 m loop (which remembers more views per step).
"""

from __future__ import annotations

import dataclasses
import functools
import itertools
import time
from collections.abc import Callable, Iterator
from typing import Any

import albot2d.mapping.albot1.global_map as global_map
import albot2d.mapping.albot1.mapper as albot1
from albot2d.evaluation.run.setup import RunSpec, build_run, make_simulator
from albot2d.frames import Frame
from albot2d.perception import extract_surfaces
from albot2d.seeding import make_rng
from albot2d.sim.odometry import NOISE_PRESETS
from albot2d.sim.simulator import Simulator
from worldgen.generate import generate
from worldgen.tours import make_tour

STAGES = [  # (module or class, function, label); indented labels are parts of the one above
    (global_map.GlobalMap, "add_view", "global-map update (add_view)"),
    (global_map, "quick_touching_mask", "  touching test (compiled, GEOS if unsure)"),
    (global_map, "view_polygon", "  view polygon P (GEOS, when needed)"),
    (global_map, "touching_mask", "  touching test (GEOS, every update before)"),
    (global_map, "visible_share", "  sight lines (visible_share)"),
    (albot1, "rtsv", "tracking (rtsv)"),
    (albot1, "triangulate", "triangulation"),
]

ROUNDS = 3


def _timed(fn: Callable[..., Any], label: str, totals: dict[str, float]) -> Callable[..., Any]:
    @functools.wraps(fn)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        t0 = time.process_time()
        try:
            return fn(*args, **kwargs)
        finally:
            totals[label] = totals.get(label, 0.0) + time.process_time() - t0

    return wrapper


def main(steps: int = 3000) -> None:
    run = build_run(RunSpec())  # the default run's world, tour and driving profile

    def drive():  # type: ignore[no-untyped-def]
        return make_simulator(run.world, run.spec).drive(run.tour, run.profile)

    bench = benchmark_loop()
    for label, frames in (
        ("the default run", list(drive())),
        ("the benchmark's 60 m loop", list(itertools.islice(bench(), BENCHMARK_STEPS))),
    ):
        _stage_times(label, frames)
    for label, loop, n in (
        ("the default run", drive, steps),
        ("the benchmark's 60 m loop", bench, BENCHMARK_STEPS),
    ):
        sim, both, remembered = _steps_per_second(loop, n)
        print(
            f"{label}: simulator step {sim / n * 1e6:.0f} µs CPU; simulator + Albot1 "
            f"(extraction included) {both / n * 1e6:.0f} µs = {n / both:.0f} steps/s per "
            f"core (first {n} steps, best of {ROUNDS} rounds; {remembered / n:.2f} views "
            f"remembered per step)"
        )


def _stage_times(label: str, frames: list[Frame]) -> None:
    """Print Albot1's CPU time per view by stage on ``frames`` (extraction done before)."""
    params = albot1.Albot1().perception()
    views = [extract_surfaces(f.scan, params) for f in frames]
    warm = albot1.Albot1()  # compiled kernels loaded (or built) before the clock starts
    for frame, view in zip(frames[:300], views[:300], strict=True):
        warm.observe_perceived(frame, view)
    totals: dict[str, float] = {}
    originals = [(owner, name, getattr(owner, name)) for owner, name, _ in STAGES
                 if hasattr(owner, name)]  # an older checkout lacks the newer stages  # fmt: skip
    for owner, name, stage in STAGES:
        if hasattr(owner, name):
            setattr(owner, name, _timed(getattr(owner, name), stage, totals))
    mapper = albot1.Albot1()
    t0 = time.process_time()
    for frame, view in zip(frames, views, strict=True):
        mapper.observe_perceived(frame, view)
    total = time.process_time() - t0
    for owner, name, fn in originals:  # the steps/s without the stage timers
        setattr(owner, name, fn)
    n = len(frames)
    print(f"Albot1 on {label}: {total / n * 1e6:.0f} µs CPU per view over {n} views "
          f"({len(mapper.route_map()) / n:.2f} remembered per view)")  # fmt: skip
    for _, _, stage in STAGES:
        print(f"  {stage:44s} {totals.get(stage, 0.0) / n * 1e6:6.0f} µs/view")
    top = sum(v for k, v in totals.items() if not k.startswith(" "))
    print(f"  {'rest of the main loop':44s} {(total - top) / n * 1e6:6.0f} µs/view")


#: ``benchmarks/test_simulator.py::test_simulator_with_albot1_steps_per_second``'s loop.
BENCHMARK_STEPS = 1500


def benchmark_loop() -> Callable[[], Iterator[Frame]]:
    """The steps/s benchmark's drive: office seed 11 without moving obstacles, a 60 m loop
    (tour seed 1), typical odometry noise, simulator seed 3."""
    office = dataclasses.replace(generate("office", seed=11), dynamic_obstacles=())
    tour = make_tour(office, make_rng(1), kind="loop", min_length_m=60.0)
    sim = Simulator(office, seed=3, odometry=NOISE_PRESETS["typical"])
    return lambda: sim.drive(tour, "dataset1")


def _steps_per_second(drive: Callable[[], Iterator[Frame]], steps: int) -> tuple[float, float, int]:
    """Best CPU seconds of ``steps`` simulator steps, and of as many with Albot1 observing
    each frame (after one untimed round); and the views Albot1 remembered."""
    sim = both = float("inf")
    remembered = 0
    for r in range(ROUNDS + 1):  # best of a few rounds: the machine may be shared
        t0 = time.process_time()
        sum(1 for _ in itertools.islice(drive(), steps))
        sim = min(sim, time.process_time() - t0) if r else sim
        mapper = albot1.Albot1()
        t0 = time.process_time()
        for frame in itertools.islice(drive(), steps):
            mapper.observe(frame)
        both = min(both, time.process_time() - t0) if r else both
        remembered = len(mapper.route_map())
    return sim, both, remembered


if __name__ == "__main__":
    main()
