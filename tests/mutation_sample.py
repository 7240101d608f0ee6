"""The sample of mutants ``docs/mutation.md`` measures, and its score.

``sample``: per module, ``--per-module`` mutant names drawn without replacement
(``random.Random(seed)``) from those mutmut generated (``mutants/**/*.meta``, made by
``mutmut run``), plus (unless ``--without-named``) the named mutants the issue asks to be
killed. Prints the names, one per line, for ``mutmut run NAMES``::

    S="--without-named --per-module 40 --seed 1130"
    S="$S --exclude-sample 1128:15 --exclude-sample 1129:40"
    mutmut run --max-children 1 $(python -m tests.mutation_sample $S)
    python -m tests.mutation_sample $S --report

(the measurement of docs/mutation.md: seed 1130, leaving out the two samples drawn and
read before it).

``--report``: instead of the names, the score of that sample from mutmut's recorded exit
codes: per module killed / non-equivalent and the Wilson 95 % interval. A timeout counts
as killed (the tests noticed), "no tests" and "survived" as not killed, and the mutants
listed in ``EQUIVALENT`` (reviewed by hand, reasons in docs/mutation.md) are left out.
"""

from __future__ import annotations

import argparse
import json
import math
import random
import sys
from pathlib import Path

__all__ = ["EQUIVALENT", "NAMED", "main", "sample", "score", "wilson"]

# The planted bugs of the audit that mutmut also makes: line extraction's min_points
# off by one (``>=`` → ``>``) where runs are dropped and where split pieces are.
NAMED = (
    "albot2d.perception.extraction.x_extract_surfaces__mutmut_71",
    "albot2d.perception.extraction.x__split__mutmut_27",
)

# Mutants reviewed and found equivalent (no input tells them from the original); the
# reason of each is in docs/mutation.md. Left out of the denominator.
EQUIVALENT: frozenset[str] = frozenset(
    {
        "albot2d.evaluation.metrics.alignment.x_evo_absolute_pose_error__mutmut_32",
        "albot2d.evaluation.metrics.alignment.x_in_world_frame__mutmut_9",
        "albot2d.evaluation.metrics.alignment.x_absolute_pose_error__mutmut_9",
        "albot2d.evaluation.metrics.map_quality.x_map_quality__mutmut_48",
        "albot2d.evaluation.metrics.map_quality.x__touches__mutmut_37",
        "albot2d.evaluation.metrics.map_quality.x__touches__mutmut_90",
        "albot2d.evaluation.metrics.rpe.x_relation_errors__mutmut_27",
        "albot2d.evaluation.metrics.rpe.x_relative_pose_error__mutmut_27",
        "albot2d.evaluation.metrics.rpe.x__lookup__mutmut_47",
        "albot2d.evaluation.metrics.rpe.x_relation_errors__mutmut_23",
        "albot2d.evaluation.metrics.rpe.x_relation_errors__mutmut_36",
        "albot2d.evaluation.metrics.rpe.x__lookup__mutmut_27",
        "albot2d.evaluation.metrics.rpe.x__lookup__mutmut_11",
        "albot2d.mapping.albot1.deletion.x_quick_touching_mask__mutmut_43",
        "albot2d.perception.extraction.x__split__mutmut_42",
        "albot2d.perception.extraction.x__merge__mutmut_1",
        "albot2d.perception.extraction.x__split__mutmut_36",
        "albot2d.perception.tracking.x__directions__mutmut_1",
        "albot2d.perception.tracking.x__endpoint_distances__mutmut_77",
        "albot2d.sim.odometry.xǁOdometryǁ_normal_pair__mutmut_3",
        "albot2d.evaluation.metrics.alignment.x__pose_array__mutmut_4",
        "albot2d.evaluation.metrics.alignment.x_evo_pose_errors__mutmut_116",
        "albot2d.evaluation.metrics.alignment.x_evo_pose_errors__mutmut_37",
        "albot2d.evaluation.metrics.alignment.x_evo_absolute_pose_error__mutmut_36",
        "albot2d.evaluation.metrics.alignment.x_evo_absolute_pose_error__mutmut_40",
        "albot2d.evaluation.metrics.alignment.x_evo_absolute_pose_error__mutmut_42",
        "albot2d.evaluation.metrics.alignment.x_evo_absolute_pose_error__mutmut_97",
        "albot2d.evaluation.metrics.map_quality.x_nearest_segment_distance__mutmut_37",
        "albot2d.evaluation.metrics.map_quality.x__bounded_distances__mutmut_85",
        "albot2d.evaluation.metrics.map_quality.x__bounded_distances__mutmut_96",
        "albot2d.evaluation.metrics.map_quality.x__bounded_distances__mutmut_101",
        "albot2d.evaluation.metrics.map_quality.x__near_points__mutmut_38",
        "albot2d.evaluation.metrics.map_quality.x__touches__mutmut_67",
        "albot2d.evaluation.metrics.rpe.x__lookup__mutmut_31",
        "albot2d.evaluation.metrics.rpe.x_relation_errors__mutmut_15",
        "albot2d.evaluation.metrics.rpe.x_relation_errors__mutmut_17",
        "albot2d.mapping.albot1.triangulation.x_triangulate__mutmut_16",
        "albot2d.mapping.albot1.triangulation.x_triangulate__mutmut_75",
        "albot2d.mapping.albot1.triangulation.x_triangulate__mutmut_77",
        "albot2d.perception.extraction.x_extract_surfaces__mutmut_103",
        "albot2d.perception.extraction.x__grow__mutmut_33",
        "albot2d.perception.tracking.x__directions__mutmut_2",
        "albot2d.perception.tracking.x_match_surfaces__mutmut_153",
        "albot2d.perception.tracking.x__endpoint_distances__mutmut_28",
        "albot2d.perception.tracking.x__endpoint_distances__mutmut_79",
        "albot2d.perception.tracking.x__readonly_ids__mutmut_8",
        "albot2d.sim.odometry.xǁOdometryǁinduce__mutmut_18",
        "albot2d.sim.odometry.x_heading_variance_rad2__mutmut_12",
    }
)

_KILLED = {1, 3, 36, 24, -24, 152, 255, 37}
_NOT_KILLED = {0, 5, 33}


def _metas(root: Path, skip: tuple[str, ...]) -> list[Path]:
    return [m for m in sorted(root.glob("**/*.py.meta")) if not any(s in str(m) for s in skip)]


def _module(meta: Path, root: Path) -> str:
    return str(meta.relative_to(root)).removesuffix(".py.meta").replace("/", ".")


def sample(
    root: Path,
    per_module: int,
    seed: int,
    skip: tuple[str, ...] = (),
    named: bool = True,
    exclude: frozenset[str] = frozenset(),
) -> list[str]:
    """``per_module`` mutant names of each mutated module (sorted, then drawn), skipping
    modules whose path contains any of ``skip`` and the mutants in ``exclude`` (those of
    earlier samples, whose survivors were looked at); the named mutants appended if
    ``named``."""
    rng = random.Random(seed)
    names: list[str] = []
    for meta in _metas(root, skip):
        keys = sorted(json.loads(meta.read_text(encoding="utf-8"))["exit_code_by_key"])
        keys = [k for k in keys if k not in exclude]
        names += rng.sample(keys, min(per_module, len(keys)))
    return names + [n for n in NAMED if named and n not in names]


def wilson(killed: int, n: int, z: float = 1.959964) -> tuple[float, float]:
    """The Wilson score interval (95 % by default) of a proportion ``killed / n``."""
    if n == 0:
        return (0.0, 1.0)
    p = killed / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return (max(0.0, centre - half), min(1.0, centre + half))


def score(root: Path, names: list[str]) -> list[tuple[str, int, int, int, list[str]]]:
    """Per module (and ``all`` last): (module, killed, non-equivalent, equivalent,
    names not killed or not run) of the sampled ``names``."""
    codes: dict[str, int | None] = {}
    module_of: dict[str, str] = {}
    for meta in sorted(root.glob("**/*.py.meta")):
        for key, code in json.loads(meta.read_text(encoding="utf-8"))["exit_code_by_key"].items():
            codes[key] = code
            module_of[key] = _module(meta, root)
    rows: dict[str, list] = {}
    for name in names:
        row = rows.setdefault(module_of[name], [0, 0, 0, []])
        if name in EQUIVALENT:
            row[2] += 1
            continue
        row[1] += 1
        code = codes[name]
        if code in _KILLED:
            row[0] += 1
        else:
            row[3].append(f"{name} ({'not run' if code is None else code})")
    out = [(m, k, n, e, s) for m, (k, n, e, s) in rows.items()]
    total = (
        "all",
        sum(r[1] for r in out),
        sum(r[2] for r in out),
        sum(r[3] for r in out),
        [x for r in out for x in r[4]],
    )
    return [*out, total]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m tests.mutation_sample", description=__doc__)
    parser.add_argument("--per-module", type=int, default=15)
    parser.add_argument("--seed", type=int, default=1128)
    parser.add_argument("--root", type=Path, default=Path("mutants"))
    parser.add_argument("--skip", action="append", default=[], help="module path part to leave out")
    parser.add_argument("--without-named", action="store_true", help="the random draw only")
    parser.add_argument("--report", action="store_true", help="score the sample, not list it")
    parser.add_argument(
        "--exclude-sample",
        action="append",
        default=[],
        metavar="SEED:PER_MODULE",
        help="leave out the mutants of that earlier random draw (repeatable)",
    )
    args = parser.parse_args(argv)
    exclude: set[str] = set()
    for spec in args.exclude_sample:
        seed_text, _, per_text = spec.partition(":")
        exclude |= set(sample(args.root, int(per_text), int(seed_text), named=False))
    names = sample(
        args.root,
        args.per_module,
        args.seed,
        tuple(args.skip),
        named=not args.without_named,
        exclude=frozenset(exclude),
    )
    if not args.report:
        print("\n".join(names))
        return 0
    print("| module | killed / non-equivalent | score | Wilson 95 % | equivalent |")
    print("|---|---|---|---|---|")
    rows = score(args.root, names)
    for module, killed, n, eq, _ in rows:
        lo, hi = wilson(killed, n)
        short = module.rsplit(".", 1)[-1]
        print(
            f"| {short} | {killed} / {n} | {100 * killed / max(n, 1):.1f} % "
            f"| {100 * lo:.1f}–{100 * hi:.1f} % | {eq} |"
        )
    print("\nnot killed:")
    print("\n".join(f"  {s}" for s in rows[-1][4]) or "  (none)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
