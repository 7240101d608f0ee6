"""Fuzzing reproducers (``reproducers/episode-K.json``): reading one back, the episode it
describes, and running that episode again with every check.

A reproducer is a report.json (the failing run, fully scored, which ``albot2d run
--reproduce`` compares the re-run with) with a ``reproducer`` section: the episode's
record without its metrics and timings, the world, and for an episode that could not even
be drawn the campaign's parameters. :class:`Reproducer` is that document read back.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import cast

from albot2d.errors import InputError
from albot2d.evaluation.fuzz.episode import EpisodeOutcome, EpisodeSpec, run_checked
from albot2d.evaluation.fuzz.record import EpisodeRecord, JsonObject
from albot2d.evaluation.run.experiment import ExperimentResult
from albot2d.frames import Frame
from albot2d.validation import parse_json

__all__ = [
    "Reproducer",
    "read_reproducer",
    "replay_reproducer",
    "reproduce_episode",
    "reproducer_spec",
]


@dataclass(frozen=True)
class Reproducer:
    """A reproducer document: ``report`` is the whole of it (a report.json, read by the
    run pipeline as such), ``episode`` its failing episode's record, ``campaign`` the
    campaign's parameters when it has them (an episode that could not be drawn)."""

    report: JsonObject
    episode: EpisodeRecord
    campaign: JsonObject | None

    @classmethod
    def from_json(cls, doc: Mapping[str, object], where: str = "reproducer") -> Reproducer:
        section = doc.get("reproducer")
        record = section.get("episode") if isinstance(section, Mapping) else None
        if not isinstance(section, Mapping) or not isinstance(record, Mapping):
            raise InputError(f"{where}: not a fuzzing reproducer (no reproducer.episode)")
        if "episode" not in record:
            raise InputError(f"{where}: not a fuzzing reproducer (no reproducer.episode)")
        episode = EpisodeRecord.from_json(record, where)
        campaign = section.get("campaign")
        return cls(
            cast(JsonObject, dict(doc)),
            episode,
            cast(JsonObject, dict(campaign)) if isinstance(campaign, Mapping) else None,
        )

    def spec(self, where: str = "reproducer") -> EpisodeSpec:
        """The episode: from its record or, when the record has no world (an episode that
        could not even be drawn, or a dead worker's reproducer from an older albot2d),
        drawn again from the campaign's parameters and its index."""
        if self.episode.spec is not None:
            return self.episode.spec
        if self.campaign is None:
            raise InputError(f"{where}: not a fuzzing reproducer (no world and no campaign)")
        from albot2d.evaluation.fuzz.campaign import CampaignParams

        params = CampaignParams.from_dict(self.campaign, where=where)
        return EpisodeSpec.draw(params, self.episode.episode)


def read_reproducer(path: str | os.PathLike[str]) -> Reproducer:
    """A reproducer document (``reproducers/episode-K.json``), checked to hold an episode."""
    try:
        with open(path, encoding="utf-8") as handle:
            doc = parse_json(handle.read(), str(path))
    except ValueError as exc:
        raise InputError(f"{path}: not a fuzzing reproducer ({exc})") from None
    if not isinstance(doc, Mapping):
        raise InputError(f"{path}: not a fuzzing reproducer (not an object)")
    return Reproducer.from_json(doc, str(path))


def replay_reproducer(path: str | os.PathLike[str]) -> EpisodeOutcome:
    """Run a saved reproducer's episode again, with every check (``albot2d run --reproduce``
    replays the run itself; this also says whether the invariants still fail)."""
    return reproduce_episode(read_reproducer(path), where=str(path))[0]


def reproduce_episode(
    reproducer: Reproducer,
    *,
    where: str = "reproducer",
    on_frame: Callable[[Frame, float], None] | None = None,
    on_stage: Callable[[str], None] | None = None,
) -> tuple[EpisodeOutcome, ExperimentResult | None]:
    """Re-run a reproducer's episode with its scoring parameters and every check; returns
    the new outcome and the run (``None`` when it crashed). ``on_frame`` and ``on_stage``
    go to ``run_experiment`` (progress display)."""
    from albot2d.evaluation.run.experiment import evaluation_params_from_report

    spec = reproducer.spec(where)
    doc = reproducer.report
    params = evaluation_params_from_report(doc) if "params" in doc else None
    return run_checked(spec, params, on_frame=on_frame, on_stage=on_stage)


def reproducer_spec(doc: Mapping[str, object], *, where: str = "reproducer") -> EpisodeSpec:
    """The episode a reproducer document describes (``Reproducer.spec``)."""
    return Reproducer.from_json(doc, where).spec(where)
