"""A fuzzing episode's typed record and its JSON form: each gives back the other, equal.

The campaign turns records into plain data only where they leave the process (a worker's
result, an episodes.jsonl line, a reproducer) and reads them back typed; nothing may be
lost or reordered on the way.
"""

from __future__ import annotations

import json

import pytest

from albot2d.errors import InputError
from albot2d.evaluation.fuzz.campaign import CampaignParams
from albot2d.evaluation.fuzz.episode import crash_outcome, run_episode
from albot2d.evaluation.fuzz.record import (
    CheckMetrics,
    CheckOutcome,
    EpisodeError,
    EpisodeMetrics,
    EpisodeOutcome,
    EpisodeRecord,
    EpisodeSpec,
)
from tests import bad_inputs as bi
from tests.campaign_helpers import SMALL


@pytest.fixture(scope="module")
def outcome() -> EpisodeOutcome:
    """A real episode of Albot1 with zero noise (so every check runs, and some fail)."""
    params = CampaignParams(episodes=1, seed=1, noise="none", laser_noise="zero", **SMALL)
    return run_episode(EpisodeSpec.draw(params, 0))


def test_a_real_record_round_trips_through_its_json(outcome: EpisodeOutcome) -> None:
    record = outcome.record
    assert record.metrics is not None and record.checks.metrics is not None
    assert "zero_noise_localisation" in record.checked  # the zero-noise check ran too
    data = record.to_json()
    again = EpisodeRecord.from_json(json.loads(json.dumps(data)), "line")
    assert again == record
    assert again.to_json() == data
    assert json.dumps(again.to_json()) == json.dumps(data)  # the same keys in the same order
    assert list(data) == [
        "episode", "seed", "run_seed", "world", "tour", "profile", "noise", "laser_noise",
        "mapper", "status", "checked", "violations", "error", "metrics", "digest", "timings",
    ]  # fmt: skip
    assert list(data["metrics"])[:3] == ["frames", "travelled_m", "collided_frames"]
    assert "local_map_position_error_max_m" in data["metrics"]  # Albot1 has a route map


def test_an_outcome_crosses_a_process_as_plain_data(outcome: EpisodeOutcome) -> None:
    data = json.loads(json.dumps(outcome.to_json()))  # nothing but JSON types in it
    assert EpisodeOutcome.from_json(data) == outcome


def test_a_crash_record_round_trips_with_and_without_its_episode() -> None:
    params = CampaignParams(episodes=3, seed=2, **SMALL)
    error = EpisodeError("RuntimeError", "boom", "Traceback ...")
    drawn = crash_outcome(EpisodeSpec.draw(params, 2), error, elapsed_s=0.5)
    undrawn = crash_outcome(None, error, campaign=params.to_dict(), index=2)
    for out in (drawn, undrawn):
        record = out.record
        assert record.failed and record.metrics is None and record.to_json()["metrics"] == {}
        assert EpisodeRecord.from_json(record.to_json()) == record
        assert out.reproducer is not None
        episode = out.reproducer["reproducer"]["episode"]  # type: ignore[call-overload,index]
        assert episode == record.to_json(measurements=False)
    assert undrawn.record.spec is None and undrawn.record.to_json()["seed"] == {
        "entropy": 2,
        "spawn_key": [2],
    }


def test_a_record_as_written_reads_back_the_same() -> None:
    for status in ("ok", "violation", "crash"):
        data = bi.episode_record(4, seed=7, status=status)
        assert EpisodeRecord.from_json(data).to_json() == data


def test_the_checks_numbers_appear_only_when_their_check_ran() -> None:
    metrics = CheckMetrics(1.0, 0.5, 2.0, 1.0, 0.1, 0.2, 0.9)
    view_based = CheckOutcome(("heading_error_bound", "route_connected"), {}, metrics)
    other = CheckOutcome(("robot_clear_of_obstacles",), {}, metrics)
    assert list(view_based.metrics_json()) == [
        "local_map_position_error_max_m", "local_map_heading_error_max_deg",
        "heading_bound_ratio_max", "heading_error_max_deg", "heading_error_mean_deg",
        "odometry_heading_error_max_deg", "odometry_heading_error_mean_deg",
    ]  # fmt: skip
    assert list(other.metrics_json()) == list(view_based.metrics_json())[3:]


def test_a_record_missing_a_metric_is_an_input_error() -> None:
    data = bi.episode_record(0)
    del data["metrics"]["map_completeness"]
    with pytest.raises(InputError, match="line 3: no metrics map_completeness"):
        EpisodeRecord.from_json(data, "line 3")
    assert EpisodeMetrics.from_json(bi.episode_record(0)["metrics"], "x").frames == 10
