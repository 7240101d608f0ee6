"""Fuzzing campaigns: many small random episodes on a backend, streamed to disk as they finish.

``run_campaign(CampaignParams(episodes=N, ...), out_dir)`` runs episodes ``0…N-1`` (see
``albot2d.evaluation.fuzz.episode`` for how each is drawn from the campaign seed) on a backend
(``albot2d.evaluation.fuzz.backends``) and writes into ``out_dir``:

- ``campaign.lock`` while it runs (``albot2d.evaluation.fuzz.lock``): a second
  campaign on the same folder is refused, a lock left by a killed one is taken over;
- ``campaign.json``: the parameters (written first; ``resume`` refuses a folder without
  one written by albot2d, or with other parameters; a new campaign refuses a folder
  that holds one);
- ``episodes.jsonl``: one JSON line per finished episode, in the order they finish, each
  flushed to disk before the next, so an interrupted campaign loses nothing; with
  ``resume`` the episodes already there are skipped and a damaged tail (a last line cut
  off by a killed writer) is dropped and redone; any other damage (a broken line, an
  episode twice, an episode of another seed) is refused, naming the line;
- ``reproducers/episode-<k>.json`` for every failing episode (an invariant violated or a
  crash), written before its line: ``albot2d run --reproduce FILE`` replays it;
- ``summary.json`` (``albot2d.evaluation.fuzz.summary.summarise``); ``albot2d fuzz``
  adds ``histograms.png`` (``albot2d.viz.campaign``).

Ctrl-C (or SIGTERM): the first stops handing out episodes and lets the running ones finish
and be written down, the second stops at once (the backend's workers are terminated); either way
:class:`CampaignInterrupted` is raised and ``episodes.jsonl`` holds only whole lines.
"""

from __future__ import annotations

import contextlib
import gc
import json
import os
import signal
import sys
import threading
import time
from collections.abc import Callable, Iterator, Mapping
from dataclasses import asdict, dataclass, fields
from pathlib import Path
from types import FrameType
from typing import TYPE_CHECKING, NoReturn

import numpy as np

from albot2d.atomic import atomic_write_text
from albot2d.errors import InputError
from albot2d.evaluation.fuzz.episode import crash_outcome, run_episode
from albot2d.evaluation.fuzz.files import check_campaign_values
from albot2d.evaluation.fuzz.lock import CampaignLock
from albot2d.evaluation.fuzz.record import (
    EpisodeError,
    EpisodeOutcome,
    EpisodeRecord,
    EpisodeSpec,
    Json,
    JsonObject,
)
from albot2d.evaluation.fuzz.stream import EpisodeLog, read_episodes, scan_episodes
from albot2d.evaluation.fuzz.summary import CampaignSummary, summarise
from albot2d.inputfiles import read_json_file
from albot2d.limits import MAX_CAMPAIGN_EPISODES, MAX_TOUR_LENGTH_M
from albot2d.validation import check_at_most
from worldgen.params import MAX_WORLD_SIZE_M

if TYPE_CHECKING:
    from tqdm import tqdm

    from albot2d.evaluation.fuzz.backends import Backend

__all__ = [
    "CAMPAIGN_NAME",
    "EPISODES_NAME",
    "HISTOGRAMS_NAME",
    "SUMMARY_NAME",
    "CampaignInterrupted",
    "CampaignParams",
    "read_campaign",
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
_FORMAT_VERSION = 1


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
        from albot2d.mapping.registry import resolve_mappers
        from albot2d.sim.driving import get_profile
        from albot2d.sim.laser import laser_noise_preset
        from albot2d.sim.odometry import noise_preset
        from worldgen.kinds import get_kind
        from worldgen.tours import TOUR_KINDS

        for name in ("episodes", "seed"):
            value = getattr(self, name)
            least = 1 if name == "episodes" else 0
            if isinstance(value, bool) or not isinstance(value, int) or value < least:
                kind = "positive" if name == "episodes" else "non-negative"
                raise InputError(f"{name} must be a {kind} integer, got {value!r}")
        if self.episodes > MAX_CAMPAIGN_EPISODES:
            raise InputError(
                f"episodes must be at most {MAX_CAMPAIGN_EPISODES} (MAX_CAMPAIGN_EPISODES; "
                f"run several campaigns with other seeds), got {self.episodes!r}"
            )
        kinds = tuple(dict.fromkeys(self.kinds))
        if not kinds:
            raise InputError("give at least one world kind")
        for kind in kinds:
            get_kind(kind)
        object.__setattr__(self, "kinds", kinds)
        get_profile(self.profile)
        noise_preset(self.noise)
        laser_noise_preset(self.laser_noise)
        if self.tour_kind not in TOUR_KINDS:
            raise InputError(
                f"unknown tour kind {self.tour_kind!r}; valid: {', '.join(TOUR_KINDS)}"
            )
        resolve_mappers([self.mapper])
        for low, high in (
            ("world_size_min_m", "world_size_max_m"),
            ("tour_length_min_m", "tour_length_max_m"),
        ):
            a, b = getattr(self, low), getattr(self, high)
            for name, value in ((low, a), (high, b)):
                if isinstance(value, bool) or not isinstance(value, int | float) or not value > 0:
                    raise InputError(f"{name} must be a positive number, got {value!r}")
            if a > b:
                raise InputError(f"{low} ({a}) is larger than {high} ({b})")
        # Caps on the work one episode may ask for (worlds are generated up to this size).
        check_at_most(self, "world_size_max_m", MAX_WORLD_SIZE_M, "the world generator's cap")
        check_at_most(self, "tour_length_max_m", MAX_TOUR_LENGTH_M, "a cap on the work")

    def to_dict(self) -> JsonObject:
        out: JsonObject = asdict(self)
        out["kinds"] = list(self.kinds)
        return out

    @classmethod
    def from_dict(cls, values: Mapping[str, Json], where: str = "campaign") -> CampaignParams:
        known = {f.name for f in fields(cls)}
        unknown = sorted(set(values) - known)
        if unknown:
            raise InputError(f"{where}: unknown campaign parameter(s) {', '.join(unknown)}")
        data: dict[str, object] = dict(values)
        if isinstance(data.get("kinds"), list):
            data["kinds"] = tuple(values["kinds"])  # type: ignore[arg-type]
        try:
            return cls(**data)  # type: ignore[arg-type]  # each value is checked in __post_init__
        except (TypeError, InputError) as exc:
            raise InputError(f"{where}: {exc}") from None

    def identity(self) -> JsonObject:
        """Everything but the episode count: what a resumed campaign must share."""
        out = self.to_dict()
        del out["episodes"]
        return out


def reproducer_path(out_dir: str | os.PathLike[str], index: int) -> Path:
    return Path(out_dir) / REPRODUCERS_DIR / f"episode-{index}.json"


class CampaignInterrupted(KeyboardInterrupt):
    """The campaign was stopped by Ctrl-C (SIGINT); every finished episode is on disk."""

    def __init__(self, done: int, total: int) -> None:
        super().__init__(f"interrupted after {done} of {total} episodes")
        self.done = done
        self.total = total


def _crash_outcome(params: Mapping[str, Json], index: int, exc: BaseException) -> EpisodeOutcome:
    """A crash outside ``run_episode`` (drawing the episode, a dead worker)."""
    error = EpisodeError.of(exc)
    try:
        spec = EpisodeSpec.draw(CampaignParams.from_dict(params), index)
    except Exception:  # the episode cannot even be drawn: the campaign says which it is
        spec = None
    return crash_outcome(spec, error, campaign=params, index=index)


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


def _episode_task(params: JsonObject, index: int) -> JsonObject:
    """What a worker runs: everything is rebuilt from the parameters and the index; the
    outcome goes back as plain data (``EpisodeOutcome.to_json``)."""
    try:
        with _heap_frozen():
            outcome = run_episode(EpisodeSpec.draw(CampaignParams.from_dict(params), index))
    except Exception as exc:  # still a finding, not a dead worker
        outcome = _crash_outcome(params, index, exc)
    return outcome.to_json()


@contextlib.contextmanager
def _heap_frozen() -> Iterator[None]:
    """Run the body with the objects that exist already (modules, the caller's data) out of
    the cyclic garbage collector's reach (``gc.freeze``), handed back after it
    (``gc.unfreeze``); what the body makes is collected as usual.

    An episode makes many short-lived containers, so the collector runs often, and each of
    its full collections walked the whole heap: in a test session or a notebook, ~160,000
    objects that an episode never touches (GC was 0.27 s of a 5.7 s, 20-episode campaign
    in a pytest process; 0.10 s with the heap frozen). Where something else froze the heap
    already, it is left as it is.
    """
    if gc.get_freeze_count():
        yield
        return
    gc.freeze()
    try:
        yield
    finally:
        gc.unfreeze()


def read_campaign(out_dir: str | os.PathLike[str]) -> CampaignParams:
    """The parameters in ``out_dir/campaign.json``, checked to be a campaign albot2d wrote."""
    path = Path(out_dir) / CAMPAIGN_NAME
    try:
        meta = read_json_file(path, "campaign file")
    except FileNotFoundError:
        raise InputError(f"{path.parent} holds no campaign (no {CAMPAIGN_NAME})") from None
    except InputError as exc:
        raise InputError(f"not a campaign file written by albot2d: {exc}") from None
    if not isinstance(meta, dict) or meta.get("format") != _FORMAT:
        raise InputError(
            f"{path}: not a campaign file written by albot2d (format is not {_FORMAT!r})"
        )
    if meta.get("format_version") != _FORMAT_VERSION:
        raise InputError(
            f"{path}: campaign format_version {str(meta.get('format_version'))[:40]}, "
            f"this albot2d reads {_FORMAT_VERSION}"
        )
    if not isinstance(meta.get("params"), dict):
        raise InputError(f"{path}: not a campaign file written by albot2d (no params)")
    check_campaign_values(meta["params"], str(path))
    return CampaignParams.from_dict(meta["params"], where=str(path))


def _check_folder(
    out: Path, params: CampaignParams, resume: bool
) -> tuple[dict[int, EpisodeRecord], int]:
    """The records already there and the bytes of episodes.jsonl to keep (resume), or
    none; refuses a folder that is not this campaign's (resume) or holds one (no resume)."""
    meta_path, episodes_path = out / CAMPAIGN_NAME, out / EPISODES_NAME
    if not resume:
        for path in (meta_path, episodes_path):
            if path.exists() and path.stat().st_size > 0:
                raise InputError(
                    f"{out} already holds a campaign ({path.name}); give --resume "
                    "to continue it, or another --out"
                )
        return {}, 0
    try:
        old = read_campaign(out)
    except InputError as exc:
        raise InputError(f"--resume: {exc}") from None
    if old.identity() != params.identity():
        diff = [
            f"{k} {old.identity()[k]!r} there, {v!r} here"
            for k, v in params.identity().items()
            if old.identity()[k] != v
        ]
        raise InputError(
            f"--resume: {meta_path} was written with other parameters "
            f"({'; '.join(diff)}); use the same options"
        )
    if not episodes_path.exists():
        return {}, 0
    records, keep, _ = scan_episodes(episodes_path)
    for number, record in records:
        k = record.episode
        if record.entropy != params.seed or record.spawn_key != (k,):
            raise InputError(
                f"{episodes_path}:{number}: episode {k} was not drawn from this "
                f"campaign's seed {params.seed}; the file is not this campaign's"
            )
    return {r.episode: r for _, r in records if r.episode < params.episodes}, keep


def _remove_stale_temporaries(out: Path) -> None:
    """Temporary files of atomic writes a killed campaign left behind (``.NAME.*.tmp``)."""
    for folder in (out, out / REPRODUCERS_DIR):
        for name in (CAMPAIGN_NAME, SUMMARY_NAME, "episode-*.json"):
            for path in folder.glob(f".{name}.*.tmp"):
                with contextlib.suppress(OSError):
                    path.unlink()


def _write_json(path: Path, value: Mapping[str, object]) -> None:
    atomic_write_text(path, json.dumps(value, indent=2, allow_nan=False) + "\n")


# What ``signal.signal`` takes and gives back.
_Handler = Callable[[int, FrameType | None], object] | int | signal.Handlers | None


class _Interrupts:
    """Ctrl-C during a campaign: the first stops handing out episodes (the running ones
    finish and are written down), the second stops at once; neither interrupts the
    writing of an episode, so episodes.jsonl only ever holds whole lines."""

    def __init__(self, on_note: Callable[[str], None] | None) -> None:
        self.count = 0
        self._writing = False
        self._deferred = False
        self._note = on_note
        self._previous: dict[int, _Handler] | None = None

    def __enter__(self) -> _Interrupts:
        if threading.current_thread() is threading.main_thread():
            # SIGTERM (kill, a scheduler, docker stop) is a Ctrl-C: the same clean stop.
            self._previous = {
                signum: signal.signal(signum, self._handler)
                for signum in (signal.SIGINT, signal.SIGTERM)
            }
        return self

    def __exit__(self, *exc: object) -> None:
        if self._previous is not None:
            for signum, previous in self._previous.items():
                signal.signal(signum, previous)

    def _handler(self, signum: int, frame: FrameType | None) -> None:
        self.count += 1
        if self.count == 1:
            if self._note is not None:
                self._note(
                    "interrupted: finishing the running episodes (Ctrl-C again to stop at once)"
                )
        elif self._writing:
            self._deferred = True
        else:
            raise KeyboardInterrupt

    @contextlib.contextmanager
    def writing(self) -> Iterator[None]:
        self._writing = True
        try:
            yield
        finally:
            self._writing = False
        if self._deferred:
            raise KeyboardInterrupt


def run_campaign(
    params: CampaignParams,
    out_dir: str | os.PathLike[str],
    *,
    backend: Backend | None = None,
    resume: bool = False,
    progress: bool = False,
    on_episode: Callable[[EpisodeRecord], None] | None = None,
    on_note: Callable[[str], None] | None = None,
) -> CampaignSummary:
    """Run the campaign into ``out_dir`` (created if missing) on ``backend`` (default: this
    process, one episode after another); returns the summary (also in summary.json).
    ``on_episode(record)`` is called as each episode is written down, ``on_note(line)``
    with what the user should know (a damaged line redone, an interruption).

    ``resume`` continues the campaign in ``out_dir`` (which must hold one with the same
    parameters); without it ``out_dir`` must not hold one. The folder is locked while the
    campaign runs. Ctrl-C (in the main thread) raises :class:`CampaignInterrupted`
    once the running episodes are written down, a second Ctrl-C at once.
    """
    from albot2d.evaluation.fuzz.backends import LocalBackend

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    with CampaignLock(out):
        done, keep = _check_folder(out, params, resume)
        episodes_path = out / EPISODES_NAME
        if on_note is not None and resume:
            size = episodes_path.stat().st_size if episodes_path.exists() else 0
            if size > keep:
                on_note(
                    f"{episodes_path}: a damaged last line ({size - keep} bytes, an "
                    "interrupted write) is dropped and its episode redone"
                )
        _remove_stale_temporaries(out)
        _write_json(
            out / CAMPAIGN_NAME,
            {"format": _FORMAT, "format_version": _FORMAT_VERSION, "params": params.to_dict()},
        )
        todo = _longest_first([k for k in range(params.episodes) if k not in done], params)
        own_backend = backend is None
        runner: Backend = backend or LocalBackend(1)
        try:
            wall = _run_episodes(
                params, out, runner, todo, done, keep, progress, on_episode, on_note
            )
        finally:
            if own_backend:
                runner.close()
        records = [done[k] for k in sorted(done)]
        summary = summarise(
            records, params.to_dict(), ran=len(todo), wall_time_s=wall, workers=runner.workers
        )
        _write_json(out / SUMMARY_NAME, summary)
    return summary


def _run_episodes(
    params: CampaignParams,
    out: Path,
    backend: Backend,
    todo: list[int],
    done: dict[int, EpisodeRecord],
    keep: int,
    progress: bool,
    on_episode: Callable[[EpisodeRecord], None] | None,
    on_note: Callable[[str], None] | None,
) -> float:
    """Run ``todo`` on ``backend``, writing each episode down; returns the wall time."""
    bar = _progress(params.episodes, len(done), progress)
    failures = sum(r.failed for r in done.values())
    log = EpisodeLog(out / EPISODES_NAME, keep)
    t0 = time.perf_counter()
    with _Interrupts(on_note) as interrupts:
        # After a first Ctrl-C the backend is handed no more episodes.
        queue = (k for k in todo if not interrupts.count)
        try:
            for index, result in backend.map_unordered(_episode_task, queue, params.to_dict()):
                if isinstance(result, BaseException) and not isinstance(result, Exception):
                    raise result  # an interrupt on a worker: stop, it is no finding
                outcome = (
                    _crash_outcome(params.to_dict(), index, result)
                    if isinstance(result, BaseException)
                    else EpisodeOutcome.from_json(result)
                )
                with interrupts.writing():
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
        except KeyboardInterrupt:
            _abort(backend)
            raise CampaignInterrupted(len(done), params.episodes) from None
        finally:
            log.close()
            if bar is not None:
                bar.close()
        if interrupts.count:
            raise CampaignInterrupted(len(done), params.episodes)
    return time.perf_counter() - t0


def _abort(backend: Backend) -> None:
    """Stop the backend's running tasks now (a second Ctrl-C)."""
    abort = getattr(backend, "abort", None)
    if abort is not None:
        abort()


def _progress(total: int, initial: int, enabled: bool) -> tqdm[NoReturn] | None:
    if not enabled:
        return None
    from tqdm import tqdm

    return tqdm(
        total=total,
        initial=initial,
        unit="ep",
        desc="fuzz",
        file=sys.stderr,
        dynamic_ncols=True,
        disable=None,
    )
