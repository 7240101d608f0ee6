"""Parameter validation: every error names the parameter and the offending value."""

from __future__ import annotations

import dataclasses

import pytest
from hypothesis import given
from hypothesis import strategies as st

from albot2d.errors import InputError
from worldgen import generate, kind_names, make_params
from worldgen.kinds import get_kind

KINDS = kind_names()


def test_unknown_kind_lists_the_valid_kinds():
    valid = "corridors, fig6, mixed, office, open, rooms"
    with pytest.raises(InputError, match=rf"unknown world kind 'maze'; valid kinds: {valid}"):
        generate("maze", seed=0)


@pytest.mark.parametrize("kind", KINDS)
def test_misspelled_parameter_lists_valid_names(kind):
    with pytest.raises(InputError, match=r"unknown parameter\(s\) clutter_density.*valid: "):
        generate(kind, seed=0, clutter_density=0.5)


@pytest.mark.parametrize("kind", KINDS)
def test_defaults_are_valid_and_frozen(kind):
    p = make_params(kind)
    assert p.width_m >= p.min_size_m and p.height_m >= p.min_size_m
    with pytest.raises(dataclasses.FrozenInstanceError):
        p.width_m = 1.0  # type: ignore[misc]


@pytest.mark.parametrize("kind", KINDS)
@pytest.mark.parametrize("name", ["width_m", "height_m"])
def test_too_small_for_the_kind(kind, name):
    with pytest.raises(InputError, match=rf"{name} must be >= .* got 3\.0"):
        generate(kind, seed=0, **{name: 3.0})


@given(
    kind=st.sampled_from(KINDS),
    data=st.data(),
    bad=st.sampled_from([float("nan"), float("inf"), -1.0, -1e-3]),
)
def test_bad_numbers_name_the_field_and_value(kind, data, bad):
    cls = get_kind(kind).params
    floats = [f.name for f in dataclasses.fields(cls) if f.type in ("float", float)]
    name = data.draw(st.sampled_from(floats))
    with pytest.raises(InputError) as err:
        make_params(kind, **{name: bad})
    message = str(err.value)
    assert name in message and repr(bad) in message


@pytest.mark.parametrize(
    ("kind", "params", "field"),
    [
        ("rooms", {"door_width_min_m": 1.2, "door_width_max_m": 0.9}, "door_width_min_m"),
        ("rooms", {"door_width_min_m": 0.5}, "door_width_min_m"),
        ("rooms", {"room_size_min_m": 10.0, "room_size_max_m": 8.0}, "room_size_min_m"),
        ("corridors", {"corridor_width_min_m": 0.6}, "corridor_width_min_m"),
        ("corridors", {"corridor_width_min_m": 2.5, "corridor_width_max_m": 2.0}, "corridor"),
        ("office", {"open_areas": -1}, "open_areas"),
        ("office", {"open_areas": 1.5}, "open_areas"),
        ("mixed", {"regions": 5}, "regions"),
        ("open", {"hall_parts": 0}, "hall_parts"),
        ("open", {"pillar_spacing_m": 1.0}, "pillar_spacing_m"),
        ("rooms", {"dynamic_obstacles": -2}, "dynamic_obstacles"),
        ("rooms", {"dynamic_obstacles": True}, "dynamic_obstacles"),
        ("office", {"wall_thickness_m": 2.0}, "wall_thickness_m"),
        ("rooms", {"width_m": "wide"}, "width_m"),
    ],
)
def test_specific_rules(kind, params, field):
    with pytest.raises(InputError, match=field):
        make_params(kind, **params)


def test_size_override_and_params_recorded():
    world = generate("rooms", seed=1, width_m=12.0, height_m=9.5, clutter_per_10m2=0.0)
    assert world.bounds == (0.0, 0.0, 12.0, 9.5)
    assert world.params["clutter_per_10m2"] == 0.0 and not world.clutter
