"""Fuzzing: campaigns of many small random episodes, their records and their summaries.

- ``record``: what an episode is and what is kept of it, as typed values (its spec,
  metrics, check outcome, record and outcome), plain JSON only across a process or a file;
- ``episode``: one episode — its seed, random world and tour, the run, the checks;
  ``episode_metrics``: the numbers a campaign keeps of it;
- ``campaign``: ``run_campaign`` — episodes on a backend, streamed to disk, resumable;
  ``stream``: the ``episodes.jsonl`` record file; ``lock``: one campaign per folder;
  ``files``: a campaign's files read back as untrusted input (``--resume``);
- ``backends``: where episodes run (a local process pool or a dask.distributed cluster);
- ``summary``: throughput, failures by invariant, metric distributions;
- ``reproducer``: a failing episode written down and run again.

May import: everything below evaluation, ``albot2d.evaluation.run``, ``.metrics`` and
``.checks``.
"""

from albot2d.evaluation.fuzz.campaign import CampaignParams, read_campaign, run_campaign
from albot2d.evaluation.fuzz.episode import run_episode
from albot2d.evaluation.fuzz.record import (
    CheckOutcome,
    EpisodeMetrics,
    EpisodeOutcome,
    EpisodeRecord,
    EpisodeSpec,
)

__all__ = [
    "CampaignParams",
    "CheckOutcome",
    "EpisodeMetrics",
    "EpisodeOutcome",
    "EpisodeRecord",
    "EpisodeSpec",
    "read_campaign",
    "run_campaign",
    "run_episode",
]
