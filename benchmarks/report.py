"""Re-measure the numbers in ``docs/benchmarks.md`` on this machine and rewrite the page.

Run: ``python -m benchmarks.report`` (a few minutes; ``--out FILE`` writes elsewhere,
``--quick`` measures fewer steps, for a smoke test). Each number says what was measured and
how; the page records the machine, its load before and after, the date and the versions,
so a number is never read without the conditions it was measured under. CPU time
(``process_time``) is used where the machine may be shared; wall time only for the
default run a user waits for.

The measurements:

- line extraction per 181- and 361-beam scan, compiled kernel against the numpy path;
- Albot₁'s CPU time per view on the default run, and the simulator's per step;
- simulator + Albot₁ steps per CPU-second on the default run's first steps;
- ``albot2d run --out D`` (the default run): wall time, CPU time and peak memory, in a
  fresh process;
- ``Simulator.step`` with a 181-beam scan every step.
"""

from __future__ import annotations

import argparse
import datetime
import itertools
import os
import platform
import resource
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
DEFAULT_OUT = ROOT / "docs" / "benchmarks.md"


def _cpu_model() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def _best_cpu(fn: Callable[[], Any], rounds: int = 5, number: int = 1) -> float:
    """Best CPU seconds per call of ``fn`` over ``rounds`` rounds of ``number`` calls."""
    fn()  # warm: compiled kernels built, caches filled
    best = float("inf")
    for _ in range(rounds):
        t0 = time.process_time()
        for _ in range(number):
            fn()
        best = min(best, (time.process_time() - t0) / number)
    return best


def measure_extraction() -> list[tuple[str, str, str]]:
    from albot2d.evaluation.run.setup import RunSpec, build_run
    from albot2d.perception import extract_surfaces
    from albot2d.sim.laser import LaserParams

    rows = []
    for beams in (181, 361):
        spec = RunSpec(max_frames=5)
        run = build_run(spec)
        if beams != 181:
            sim = type(run.simulator)(run.world, seed=0, laser=LaserParams(n_beams=beams))
        else:
            sim = run.simulator
        scan = next(iter(sim.drive(run.tour, run.profile))).scan
        compiled = _best_cpu(lambda scan=scan: extract_surfaces(scan), number=200)
        numpy_path = _best_cpu(lambda scan=scan: extract_surfaces(scan, backend="numpy"), number=20)
        rows.append((
            f"line extraction, {beams}-beam scan",
            f"{compiled * 1e6:.0f} µs (numpy path {numpy_path * 1e6:.0f} µs)",
            "`extract_surfaces` on a simulated office scan, best of 5 × 200 calls",
        ))  # fmt: skip
    return rows


def measure_albot1(steps: int) -> list[tuple[str, str, str]]:
    import albot2d.mapping.albot1.mapper as albot1
    from albot2d.evaluation.run.setup import RunSpec, build_run, make_simulator
    from albot2d.perception import extract_surfaces

    run = build_run(RunSpec())
    frames = list(
        itertools.islice(make_simulator(run.world, run.spec).drive(run.tour, run.profile), steps)
    )

    def simulate() -> None:
        drive = make_simulator(run.world, run.spec).drive(run.tour, run.profile)
        sum(1 for _ in itertools.islice(drive, steps))

    sim_s = _best_cpu(simulate, rounds=3)
    params = albot1.Albot1().perception()
    views = [extract_surfaces(f.scan, params) for f in frames]

    def mapping() -> None:
        mapper = albot1.Albot1()
        for frame, view in zip(frames, views, strict=True):
            mapper.observe_perceived(frame, view)

    map_s = _best_cpu(mapping, rounds=3)

    def both() -> None:
        mapper = albot1.Albot1()
        drive = make_simulator(run.world, run.spec).drive(run.tour, run.profile)
        for frame in itertools.islice(drive, steps):
            mapper.observe(frame)

    both_s = _best_cpu(both, rounds=3)
    n = len(frames)
    how = f"the default run's first {n} views, CPU time, best of 3 after a warm-up"
    return [
        ("Albot₁ per view (extraction excluded)", f"{map_s / n * 1e6:.0f} µs", how),
        ("simulator per view (a `dataset1` step and its scan)", f"{sim_s / n * 1e6:.0f} µs", how),
        ("simulator + Albot₁ (extraction included)", f"{n / both_s:,.0f} views per CPU-second",
         how),
    ]  # fmt: skip


def measure_step(steps: int) -> list[tuple[str, str, str]]:
    from albot2d.evaluation.run.setup import RunSpec, build_run
    from albot2d.sim import VelocityCommand

    sim = build_run(RunSpec()).simulator

    command = VelocityCommand(0.3, 0.2)

    def stepping() -> None:
        sim.reset(seed=0)
        for _ in range(steps):
            sim.step(command, 0.1)

    s = _best_cpu(stepping, rounds=3)
    return [(
        "`Simulator.step` with a 181-beam scan every step (laser at 10 Hz, dt 0.1 s)",
        f"{steps / s:,.0f} steps per CPU-second",
        f"office seed 0, {steps} steps on a 0.3 m/s, 0.2 rad/s arc (stopping at walls), best of 3",
    )]  # fmt: skip


def measure_default_run() -> list[tuple[str, str, str]]:
    with tempfile.TemporaryDirectory() as tmp:
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        t0 = time.perf_counter()
        done = subprocess.run(
            [sys.executable, "-m", "albot2d", "run", "--out", str(Path(tmp) / "out")],
            capture_output=True, text=True, check=False,
        )  # fmt: skip
        wall = time.perf_counter() - t0
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if done.returncode != 0:
        raise SystemExit(f"albot2d run failed: {done.stderr.strip()}")
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    rss_mb = after.ru_maxrss / 1024
    how = "`albot2d run --out D` in a fresh process, figures included"
    return [
        ("default run, wall time", f"{wall:.1f} s (CPU {cpu:.1f} s)", how),
        ("default run, peak memory", f"{rss_mb:.0f} MB", how + " (peak RSS)"),
    ]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.report", description=__doc__)
    parser.add_argument("--out", default=str(DEFAULT_OUT), help="the page to write")
    parser.add_argument("--quick", action="store_true", help="fewer steps (a smoke test)")
    args = parser.parse_args(argv)
    from albot2d import __version__
    from albot2d.compiled import kernels

    load_before = os.getloadavg()
    started = datetime.datetime.now(datetime.UTC)
    steps = 300 if args.quick else 3000
    rows = [
        *measure_extraction(),
        *measure_albot1(steps),
        *measure_step(200 if args.quick else 5000),
    ]
    if not args.quick:
        rows += measure_default_run()
    load_after = os.getloadavg()
    lines = [
        "# Speed and memory, measured",
        "",
        "Regenerated by `python -m benchmarks.report` (this page is its output; do not edit",
        "by hand). The pytest-benchmark suites in `benchmarks/` compare paths side by side;",
        "[performance.md](performance.md) tells how these numbers were reached.",
        "",
        f"- date: {started:%Y-%m-%d %H:%M} UTC",
        f"- machine: {_cpu_model()}, {os.cpu_count()} cores, {platform.system()}",
        f"- load average (1 min) before / after: {load_before[0]:.1f} / {load_after[0]:.1f}"
        " (other processes share the cores: CPU times are the fair comparison)",
        f"- albot2d {__version__}, kernels {kernels()}, Python {platform.python_version()}, "
        f"numpy {np.__version__}",
        "",
        "| what | measured | how |",
        "|---|---|---|",
        *(f"| {what} | {value} | {how} |" for what, value, how in rows),
        "",
    ]
    Path(args.out).write_text("\n".join(lines), encoding="utf-8")
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main())
