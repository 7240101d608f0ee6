"""The sample of mutants ``docs/mutation.md`` measures: per module, ``--per-module`` mutant
names drawn without replacement (``random.Random(seed)``) from those mutmut generated
(``mutants/**/*.meta``, made by ``mutmut run``), plus the named mutants the issue asks to
be killed. Prints the names, one per line, for ``mutmut run NAMES``::

    mutmut run --max-children 1 $(python -m tests.mutation_sample --per-module 12 --seed 28)
"""

from __future__ import annotations

import argparse
import json
import random
import sys
from pathlib import Path

__all__ = ["NAMED", "main", "sample"]

# The planted bugs of the audit that mutmut also makes: line extraction's min_points
# off by one (``>=`` → ``>``) where runs are dropped and where split pieces are.
NAMED = (
    "albot2d.perception.extraction.x_extract_surfaces__mutmut_71",
    "albot2d.perception.extraction.x__split__mutmut_27",
)


def sample(root: Path, per_module: int, seed: int, skip: tuple[str, ...] = ()) -> list[str]:
    """``per_module`` mutant names of each mutated module (sorted, then drawn), skipping
    modules whose path contains any of ``skip``."""
    rng = random.Random(seed)
    names: list[str] = []
    for meta in sorted(root.glob("**/*.py.meta")):
        if any(s in str(meta) for s in skip):
            continue
        keys = sorted(json.loads(meta.read_text(encoding="utf-8"))["exit_code_by_key"])
        names += rng.sample(keys, min(per_module, len(keys)))
    return names + [n for n in NAMED if n not in names]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m tests.mutation_sample", description=__doc__)
    parser.add_argument("--per-module", type=int, default=12)
    parser.add_argument("--seed", type=int, default=28)
    parser.add_argument("--root", type=Path, default=Path("mutants"))
    parser.add_argument("--skip", action="append", default=[], help="module path part to leave out")
    args = parser.parse_args(argv)
    print("\n".join(sample(args.root, args.per_module, args.seed, tuple(args.skip))))
    return 0


if __name__ == "__main__":
    sys.exit(main())
