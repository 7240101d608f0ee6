"""The mutation score's arithmetic (``tests/mutation_sample.py``): the Wilson interval
against its closed forms at the extremes and a published value, and the draw's
reproducibility."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from tests.mutation_sample import sample, wilson

Z = 1.959964


@pytest.mark.parametrize("n", [1, 12, 300])
def test_wilson_at_the_extremes_is_closed_form(n: int) -> None:
    """0 of n: [0, z²/(n + z²)]; n of n: [n/(n + z²), 1]."""
    assert wilson(0, n) == pytest.approx((0.0, Z * Z / (n + Z * Z)), abs=1e-12)
    assert wilson(n, n) == pytest.approx((n / (n + Z * Z), 1.0), abs=1e-12)


def test_wilson_matches_a_worked_example() -> None:
    """Newcombe (1998), Statistics in Medicine 17:857, Table I, example (a): 81 of 263,
    Wilson 95 % interval 0.2553 to 0.3662."""
    lo, hi = wilson(81, 263)
    assert (round(lo, 4), round(hi, 4)) == (0.2553, 0.3662)


def test_a_draw_is_reproducible_and_leaves_out_what_it_is_told(tmp_path: Path) -> None:
    for module, count in (("a", 30), ("b", 5)):
        keys = {f"{module}.x_f__mutmut_{i}": None for i in range(1, count + 1)}
        (tmp_path / f"{module}.py.meta").write_text(json.dumps({"exit_code_by_key": keys}))
    first = sample(tmp_path, 4, seed=7, named=False)
    assert first == sample(tmp_path, 4, seed=7, named=False)
    assert len(first) == 8  # 4 of a, 4 of b
    again = sample(tmp_path, 4, seed=8, named=False, exclude=frozenset(first))
    assert not set(again) & set(first)
    assert len(again) == 5  # 4 of a; b has one mutant left
