"""Homing sensitivity: real start–stop runs, summarised per odometry preset and mapper."""

from __future__ import annotations

import pytest

from albot2d.errors import InputError
from albot2d.studies.sensitivity import (
    PAPER_FIG8,
    SensitivitySetup,
    format_table,
    homing_sensitivity,
    main,
    run_one,
)

SMALL = SensitivitySetup(
    kind="office",
    world_params={"width_m": 30.0, "height_m": 24.0},
    tour_length_m=40.0,
    mappers=("albot1", "albot1[preset=start_stop]", "naive"),
)


def test_sensitivity_counts_stops_within_the_bound():
    result = homing_sensitivity([1], ("none", "high"), SMALL)
    assert list(result["presets"]) == ["none", "high"]
    assert {(r["preset"], r["direction"]) for r in result["runs"]} == {
        (p, d) for p in ("none", "high") for d in ("forward", "reverse")
    }
    for preset, by_mapper in result["presets"].items():
        assert list(by_mapper) == list(SMALL.mappers)
        runs = [r for r in result["runs"] if r["preset"] == preset]
        for name, summary in by_mapper.items():
            stops = [s for r in runs for s in r["mappers"][name]["stops"]]
            within = [abs(b) <= 7.0 and abs(d) <= 3.0 for b, d, _ in stops]
            assert summary["all"]["stops"] == len(stops) > 0
            assert summary["all"]["within_bound"] == sum(within)
            assert summary["all"]["fraction_within_bound"] == pytest.approx(
                sum(within) / len(stops)
            )
            # Table 1 stops: the subset 17–35 m (straight line) from the start
            t1 = [w for w, s in zip(within, stops, strict=True) if 17.0 <= s[2] <= 35.0]
            assert summary["table1"]["stops"] == len(t1)
            assert summary["table1"]["within_bound"] == sum(t1)
        assert by_mapper["albot1"]["updates_by_region"]["all"]["updates"] > 0
        assert by_mapper["naive"]["updates_by_region"] == {}
    # every preset drives the same tours; only the odometry differs
    frames = {(r["preset"], r["direction"]): r["frames"] for r in result["runs"]}
    assert frames["none", "forward"] == frames["high", "forward"]
    table = format_table(result)
    assert "pioneer3dx" not in table and "none" in table and "±7°" in table
    assert "17–35 m" in table and "albot1[preset=start_stop]" in table


def test_reverse_drives_the_circuit_the_other_way_round():
    setup = SensitivitySetup(
        kind="office",
        world_params={"width_m": 30.0, "height_m": 24.0},
        tour_length_m=40.0,
        mappers=("truth",),
    )
    fwd = run_one(2, "none", setup, "forward")
    rev = run_one(2, "none", setup, "reverse")
    assert fwd["tour_m"] == pytest.approx(rev["tour_m"])
    # with the true poses homing is exact, both ways round
    for run in (fwd, rev):
        assert all(abs(b) < 1e-6 and abs(d) < 1e-6 for b, d, _ in run["mappers"]["truth"]["stops"])
    # the first stop is at a different place (different distance from the start)
    assert fwd["mappers"]["truth"]["stops"][0][2] != pytest.approx(
        rev["mappers"]["truth"]["stops"][0][2]
    )


def test_sensitivity_rejects_bad_arguments(capsys):
    with pytest.raises(InputError, match="at least one seed"):
        homing_sensitivity([], ("low",))
    with pytest.raises(InputError, match="workers"):
        homing_sensitivity([0], ("low",), workers=0)
    with pytest.raises(InputError, match="directions"):
        SensitivitySetup(directions=("sideways",))
    with pytest.raises(InputError, match="table1_range_m"):
        SensitivitySetup(table1_range_m=(35.0, 17.0))
    with pytest.raises(SystemExit) as exc:
        main(["--seeds", "1", "--presets", "nonsense", "--mappers", "naive"])
    assert exc.value.code == 2
    assert "nonsense" in capsys.readouterr().err


def test_paper_fig8_setting_drives_both_journeys_with_stops_every_4_m():
    setup = SensitivitySetup(mappers=("truth",), **PAPER_FIG8)
    result = homing_sensitivity([0], ("none",), setup)
    assert [r["direction"] for r in result["runs"]] == ["fig8_clockwise", "fig8_anticlockwise"]
    truth = result["presets"]["none"]["truth"]
    assert truth["table1"]["stops"] > 0 and truth["table1"]["fraction_within_bound"] == 1.0
    for run in result["runs"]:
        stops = run["mappers"]["truth"]["stops"]
        # a stop every 4 odometer metres: many more than the 20 m default would give
        assert len(stops) >= run["tour_m"] / 4.0 - 2
    assert "fig8_clockwise/fig8_anticlockwise" in format_table(result)
    with pytest.raises(InputError, match="stop_every_m"):
        SensitivitySetup(stop_every_m=0.0)
