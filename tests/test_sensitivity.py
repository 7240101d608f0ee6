"""Homing sensitivity: real start–stop runs of Albot1, summarised per odometry preset."""

from __future__ import annotations

import pytest

from albot2d.errors import InputError
from albot2d.evaluation.sensitivity import SensitivitySetup, format_table, homing_sensitivity

SMALL = SensitivitySetup(
    kind="office", world_params={"width_m": 30.0, "height_m": 24.0}, tour_length_m=40.0
)


def test_sensitivity_counts_stops_within_the_bound():
    result = homing_sensitivity([1], ("none", "high"), SMALL)
    assert list(result["presets"]) == ["none", "high"]
    for name, summary in result["presets"].items():
        run = next(r for r in result["runs"] if r["preset"] == name)
        assert summary["stops"] == len(run["stops"]) > 0
        within = sum(abs(b) <= 7.0 and abs(d) <= 3.0 for b, d in run["stops"])
        assert summary["within_bound"] == within
        assert summary["fraction_within_bound"] == pytest.approx(within / len(run["stops"]))
        assert summary["updates_by_region"]["all"]["updates"] > 0
    # both presets drive the same tour; only the odometry differs
    frames = {r["preset"]: r["frames"] for r in result["runs"]}
    assert frames["none"] == frames["high"]
    table = format_table(result)
    assert "pioneer3dx" not in table and "none" in table and "±7°" in table


def test_sensitivity_rejects_bad_arguments():
    with pytest.raises(InputError, match="at least one seed"):
        homing_sensitivity([], ("low",))
    with pytest.raises(InputError, match="workers"):
        homing_sensitivity([0], ("low",), workers=0)
