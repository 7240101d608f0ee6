"""Fuzzing campaigns: many small random episodes on a backend, streamed to disk as they finish.

``run_campaign(CampaignParams(episodes=N, ...), out_dir)`` runs episodes ``0…N-1`` (see
``albot2d.evaluation.episode`` for how each is drawn from the campaign seed) on a backend
(``albot2d.evaluation.backends``) and writes into ``out_dir``:

- ``campaign.json``: the parameters (written first; ``resume`` checks they match);
- ``episodes.jsonl``: one JSON line per finished episode, in the order they finish, each
  flushed to disk before the next, so an interrupted campaign loses nothing; with
  ``resume`` the episodes already there are skipped and a truncated last line is redone;
- ``reproducers/episode-<k>.json`` for every failing episode (an invariant violated or a
  crash), written before its line: ``albot2d run --reproduce FILE`` replays it;
- ``summary.json`` (``albot2d.evaluation.campaign_summary.summarise``); ``albot2d fuzz``
  adds ``histograms.png`` (``albot2d.plots_fuzz``).
"""

from __future__ import annotations

import json
import os
import sys
import time
from collections.abc import Callable, Mapping
from dataclasses import asdict, dataclass, fields
from pathlib import Path
from typing import Any

import numpy as np

from albot2d.atomic import atomic_write_text
from albot2d.errors import InputError
from albot2d.evaluation.campaign_summary import summarise
from albot2d.evaluation.episode import EpisodeOutcome, EpisodeSpec, run_episode

__all__ = [
    "CAMPAIGN_NAME",
    "EPISODES_NAME",
    "HISTOGRAMS_NAME",
    "SUMMARY_NAME",
    "CampaignParams",
    "read_episodes",
    "reproducer_path",
    "run_campaign",
]

CAMPAIGN_NAME = "campaign.json"
EPISODES_NAME = "episodes.jsonl"
SUMMARY_NAME = "summary.json"
HISTOGRAMS_NAME = "histograms.png"
REPRODUCERS_DIR = "reproducers"
_FORMAT = "albot2d-campaign"


@dataclass(frozen=True)
class CampaignParams:
    """A campaign: how many episodes, the seed, and what each episode draws from.

    Each episode picks a kind from ``kinds``, a width and height in ``world_size_*_m`` (at
    least the kind's minimum: offices 24 m, mixed worlds 32 m) and a minimum tour length
    in ``tour_length_*_m``; it is driven with ``profile`` and the ``noise``/``laser_noise``
    presets and mapped by ``mapper`` (a built-in name or ``module:Class``).
    """

    episodes: int
    seed: int = 0
    kinds: tuple[str, ...] = ("corridors", "rooms", "open", "office", "mixed")
    profile: str = "dataset3"
    noise: str = "typical"
    laser_noise: str = "sick_lms200"
    mapper: str = "albot1"
    tour_kind: str = "loop"
    world_size_min_m: float = 15.0
    world_size_max_m: float = 30.0
    tour_length_min_m: float = 30.0
    tour_length_max_m: float = 60.0

    def __post_init__(self) -> None:
        from albot2d.evaluation.experiment import LASER_NOISE_CHOICES, TOUR_KINDS
        from albot2d.mapping.registry import resolve_mappers
        from albot2d.sim.driving import get_profile
        from albot2d.sim.odometry import noise_preset
        from worldgen.generate import KINDS

        for name in ("episodes", "seed"):
            value = getattr(self, name)
            least = 1 if name == "episodes" else 0
            if isinstance(value, bool) or not isinstance(value, int) or value < least:
                kind = "positive" if name == "episodes" else "non-negative"
                raise InputError(f"{name} must be a {kind} integer, got {value!r}")
        kinds = tuple(dict.fromkeys(self.kinds))
        if not kinds:
            raise InputError("give at least one world kind")
        for kind in kinds:
            if kind not in KINDS:
                raise InputError(f"unknown world kind {kind!r}; valid kinds: {', '.join(KINDS)}")
        object.__setattr__(self, "kinds", kinds)
        get_profile(self.profile)
        noise_preset(self.noise)
        if self.laser_noise not in LASER_NOISE_CHOICES:
            raise InputError(f"unknown laser noise {self.laser_noise!r}; "
                             f"valid: {', '.join(LASER_NOISE_CHOICES)}")
        if self.tour_kind not in TOUR_KINDS:
            raise InputError(f"unknown tour kind {self.tour_kind!r}; "
                             f"valid: {', '.join(TOUR_KINDS)}")
        resolve_mappers([self.mapper])
        for low, high in (("world_size_min_m", "world_size_max_m"),
                          ("tour_length_min_m", "tour_length_max_m")):
            a, b = getattr(self, low), getattr(self, high)
            for name, value in ((low, a), (high, b)):
                if isinstance(value, bool) or not isinstance(value, int | float) or not value > 0:
                    raise InputError(f"{name} must be a positive number, got {value!r}")
            if a > b:
                raise InputError(f"{low} ({a}) is larger than {high} ({b})")

    def to_dict(self) -> dict[str, Any]:
        out = asdict(self)
        out["kinds"] = list(self.kinds)
        return out

    @classmethod
    def from_dict(cls, values: Mapping[str, Any], where: str = "campaign") -> CampaignParams:
        known = {f.name for f in fields(cls)}
        unknown = sorted(set(values) - known)
        if unknown:
            raise InputError(f"{where}: unknown campaign parameter(s) {', '.join(unknown)}")
        data = dict(values)
        if "kinds" in data:
            data["kinds"] = tuple(data["kinds"])
        try:
            return cls(**data)
        except TypeError as exc:
            raise InputError(f"{where}: {exc}") from None

    def identity(self) -> dict[str, Any]:
        """Everything but the episode count: what a resumed campaign must share."""
        out = self.to_dict()
        del out["episodes"]
        return out


def reproducer_path(out_dir: str | os.PathLike[str], index: int) -> Path:
    return Path(out_dir) / REPRODUCERS_DIR / f"episode-{index}.json"


def read_episodes(path: str | os.PathLike[str]) -> tuple[dict[int, dict[str, Any]], int]:
    """The episode records in an ``episodes.jsonl`` and the byte length of its complete part.

    A last line that was cut off (no newline, or not JSON) is left out, to be redone; a
    broken line anywhere else is an error naming the line.
    """
    p = Path(path)
    if not p.exists():
        return {}, 0
    data = p.read_bytes()
    records: dict[int, dict[str, Any]] = {}
    offset = 0
    lines = data.split(b"\n")
    for number, line in enumerate(lines, start=1):
        last = number == len(lines)
        end = offset + len(line) + (0 if last else 1)
        if not line.strip():
            offset = end
            continue
        try:
            record = json.loads(line)
            index = record["episode"]
            ok = (isinstance(record, dict) and isinstance(index, int) and not last
                  and "status" in record)
        except (ValueError, KeyError, TypeError):
            ok = False
        if not ok:
            if last or all(not rest.strip() for rest in lines[number:]):
                return records, offset
            raise InputError(f"{p}:{number}: not an episode record; the file is damaged "
                             "(move it away to start afresh)")
        records.setdefault(index, record)
        offset = end
    return records, offset


class _EpisodeLog:
    """Appends one line per episode to episodes.jsonl, on disk before the next."""

    def __init__(self, path: Path, keep_bytes: int) -> None:
        self._file = open(path, "ab")  # noqa: SIM115 (closed in close())
        self._file.truncate(keep_bytes)  # drop a line cut off by an interruption
        self._file.seek(keep_bytes)

    def write(self, record: Mapping[str, Any]) -> None:
        line = json.dumps(record, allow_nan=False, separators=(",", ":")) + "\n"
        self._file.write(line.encode("utf-8"))
        self._file.flush()
        os.fsync(self._file.fileno())

    def close(self) -> None:
        self._file.close()


def _crash_outcome(params: Mapping[str, Any], index: int, exc: BaseException) -> EpisodeOutcome:
    """A crash outside ``run_episode`` (drawing the episode, a dead worker)."""
    import traceback

    record = {"episode": index, "seed": {"entropy": params.get("seed"), "spawn_key": [index]},
              "status": "crash", "checked": [], "violations": {}, "metrics": {},
              "error": {"type": type(exc).__name__, "message": str(exc),
                        "traceback": "".join(traceback.format_exception(exc))},
              "digest": None, "timings": {}}
    return EpisodeOutcome(record, {"reproducer": {"episode": record, "campaign": dict(params)}})


# Rough relative cost per m² of world of each kind (measured with dataset3): only used to
# start the longest episodes first, so no worker idles at the end of a campaign.
_COST_PER_M2 = {"rooms": 3.0, "office": 3.0, "open": 1.6, "mixed": 1.1, "corridors": 1.0}


def _longest_first(indices: list[int], params: CampaignParams) -> list[int]:
    """Episode indices, the (probably) longest first; results do not depend on the order."""
    def cost(index: int) -> float:
        spec = EpisodeSpec.draw(params, index)
        area = float(np.prod(list(spec.world_params.values())))
        return _COST_PER_M2.get(spec.kind, 1.0) * area * spec.tour_length_m

    return sorted(indices, key=lambda k: (-cost(k), k))


def _episode_task(params: dict[str, Any], index: int) -> EpisodeOutcome:
    """What a worker runs: everything is rebuilt from the parameters and the index."""
    try:
        return run_episode(EpisodeSpec.draw(CampaignParams.from_dict(params), index))
    except Exception as exc:  # still a finding, not a dead worker
        return _crash_outcome(params, index, exc)


def _check_resume(out: Path, params: CampaignParams, resume: bool) -> dict[int, Any]:
    """The records already there (resume) or none; refuses to mix two campaigns."""
    meta_path, episodes_path = out / CAMPAIGN_NAME, out / EPISODES_NAME
    has_episodes = episodes_path.exists() and episodes_path.stat().st_size > 0
    if not resume:
        if has_episodes:
            raise InputError(f"{episodes_path} already holds a campaign; give --resume to "
                             "continue it, or another --out")
        return {}
    if meta_path.exists():
        try:
            meta = json.loads(meta_path.read_text(encoding="utf-8"))
            old = CampaignParams.from_dict(meta["params"], where=str(meta_path))
        except (ValueError, KeyError, TypeError) as exc:
            raise InputError(f"{meta_path}: not a campaign file ({exc})") from None
        if old.identity() != params.identity():
            diff = [k for k, v in params.identity().items() if old.identity()[k] != v]
            raise InputError(f"--resume: {meta_path} was written with other parameters "
                             f"({', '.join(diff)} differ); use the same options")
    elif has_episodes:
        raise InputError(f"--resume: {episodes_path} has no {CAMPAIGN_NAME} beside it")
    records, _ = read_episodes(episodes_path)
    return {k: r for k, r in records.items() if k < params.episodes}


def _write_json(path: Path, value: Any) -> None:
    atomic_write_text(path, json.dumps(value, indent=2, allow_nan=False) + "\n")


def run_campaign(
    params: CampaignParams,
    out_dir: str | os.PathLike[str],
    *,
    backend: Any = None,
    resume: bool = False,
    progress: bool = False,
    on_episode: Callable[[dict[str, Any]], None] | None = None,
) -> dict[str, Any]:
    """Run the campaign into ``out_dir`` (created if missing) on ``backend`` (default: this
    process, one episode after another); returns the summary (also in summary.json).
    ``on_episode(record)`` is called as each episode is written down."""
    from albot2d.evaluation.backends import LocalBackend

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    done = _check_resume(out, params, resume)
    _write_json(out / CAMPAIGN_NAME, {"format": _FORMAT, "format_version": 1,
                                      "params": params.to_dict()})
    episodes_path = out / EPISODES_NAME
    _, keep = read_episodes(episodes_path)
    todo = _longest_first([k for k in range(params.episodes) if k not in done], params)
    own_backend = backend is None
    backend = backend or LocalBackend(1)
    bar = _progress(params.episodes, len(done), progress)
    failures = sum(r["status"] != "ok" for r in done.values())
    log = _EpisodeLog(episodes_path, keep)
    t0 = time.perf_counter()
    try:
        for index, result in backend.map_unordered(_episode_task, todo, params.to_dict()):
            if isinstance(result, BaseException) and not isinstance(result, Exception):
                raise result  # an interrupt on a worker: stop, it is no finding
            outcome = (result if isinstance(result, EpisodeOutcome)
                       else _crash_outcome(params.to_dict(), index, result))
            if outcome.reproducer is not None:
                path = reproducer_path(out, index)
                path.parent.mkdir(exist_ok=True)
                _write_json(path, outcome.reproducer)
            log.write(outcome.record)
            done[index] = outcome.record
            failures += outcome.failed
            if on_episode is not None:
                on_episode(outcome.record)
            if bar is not None:
                bar.set_postfix_str(f"{failures} failing", refresh=False)
                bar.update(1)
    finally:
        log.close()
        if bar is not None:
            bar.close()
        if own_backend:
            backend.close()
    wall = time.perf_counter() - t0
    records = [done[k] for k in sorted(done)]
    summary = summarise(records, params.to_dict(), ran=len(todo), wall_time_s=wall,
                        workers=backend.workers)
    _write_json(out / SUMMARY_NAME, summary)
    return summary


def _progress(total: int, initial: int, enabled: bool) -> Any:
    if not enabled:
        return None
    from tqdm import tqdm

    return tqdm(total=total, initial=initial, unit="ep", desc="fuzz", file=sys.stderr,
                dynamic_ncols=True, disable=None)

