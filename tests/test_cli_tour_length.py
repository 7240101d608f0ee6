"""``--tour-length 100`` plans a tour of 100-130 m (the tour the run drives);
``--min-tour-length`` keeps the older meaning, at least that long."""

from __future__ import annotations

import pytest

from albot2d.cli import build_parser
from albot2d.cli.common import spec_from_args
from albot2d.evaluation.run.setup import build_world, plan_run_tour


def _tour(*options: str):
    args = build_parser().parse_args(["run", *options, "--out", "unused"])
    spec = spec_from_args(args)
    return spec, plan_run_tour(spec, build_world(spec))[1]


@pytest.mark.parametrize("length", ["100", "40"])
def test_tour_length_is_the_length(length):
    spec, tour = _tour("--tour-length", length)
    assert not spec.tour_length_is_minimum
    assert float(length) <= tour.length_m <= 1.3 * float(length)


def test_the_default_tour_is_100_to_130_m():
    _, tour = _tour()
    assert 100.0 <= tour.length_m <= 130.0


def test_min_tour_length_is_a_minimum():
    spec, tour = _tour("--min-tour-length", "100")
    assert spec.tour_length_is_minimum and tour.length_m >= 100.0
    assert tour.length_m > 130.0  # office seed 0: the far-apart places make it 279 m
