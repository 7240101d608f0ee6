"""Fuzzing reproducers (``reproducers/episode-K.json``): reading one back, the episode it
describes, and running that episode again with every check."""

from __future__ import annotations

import os
from collections.abc import Mapping
from typing import Any

from albot2d.errors import InputError
from albot2d.evaluation.fuzz.episode import EpisodeOutcome, EpisodeSpec, run_checked
from albot2d.evaluation.run.experiment import ExperimentResult
from albot2d.validation import parse_json

__all__ = ["read_reproducer", "replay_reproducer", "reproduce_episode", "reproducer_spec"]


def read_reproducer(path: str | os.PathLike[str]) -> dict[str, Any]:
    """A reproducer document (``reproducers/episode-K.json``), checked to hold an episode."""
    try:
        with open(path, encoding="utf-8") as handle:
            doc = parse_json(handle.read(), str(path))
        record = doc["reproducer"]["episode"]
    except (ValueError, KeyError, TypeError) as exc:
        raise InputError(f"{path}: not a fuzzing reproducer ({exc})") from None
    if not isinstance(record, dict):
        raise InputError(f"{path}: not a fuzzing reproducer (no episode record)")
    return doc


def replay_reproducer(path: str | os.PathLike[str]) -> EpisodeOutcome:
    """Run a saved reproducer's episode again, with every check (``albot2d run --reproduce``
    replays the run itself; this also says whether the invariants still fail)."""
    return reproduce_episode(read_reproducer(path), where=str(path))[0]


def reproduce_episode(
    doc: Mapping[str, Any], *, where: str = "reproducer", **hooks: Any
) -> tuple[EpisodeOutcome, ExperimentResult | None]:
    """Re-run a reproducer document's episode with its scoring parameters and every check;
    returns the new outcome and the run (``None`` when it crashed). ``hooks`` go to
    ``run_experiment`` (progress display)."""
    from albot2d.evaluation.run.experiment import evaluation_params_from_report

    spec = reproducer_spec(doc, where=where)
    params = evaluation_params_from_report(doc) if "params" in doc else None
    return run_checked(spec, params, **hooks)


def reproducer_spec(doc: Mapping[str, Any], *, where: str = "reproducer") -> EpisodeSpec:
    """The episode a reproducer document describes: from its record or, when the record
    has no world (an episode that could not even be drawn, or a dead worker's reproducer
    from an older albot2d), drawn again from the campaign's parameters and its index."""
    try:
        section = doc["reproducer"]
        record = section["episode"]
        index = record["episode"]
    except (KeyError, TypeError):
        raise InputError(f"{where}: not a fuzzing reproducer (no reproducer.episode)") from None
    if "world" in record:
        try:
            return EpisodeSpec.from_record(record)
        except InputError as exc:
            raise InputError(f"{where}: {exc}") from None
    campaign = section.get("campaign")
    if not isinstance(campaign, Mapping) or isinstance(index, bool) or not isinstance(index, int):
        raise InputError(f"{where}: not a fuzzing reproducer (no world and no campaign)")
    from albot2d.evaluation.fuzz.campaign import CampaignParams

    return EpisodeSpec.draw(CampaignParams.from_dict(campaign, where=where), index)
