"""What a fuzzing episode is and what a campaign keeps of it, as typed values.

- :class:`EpisodeSpec`: everything one episode runs (drawn from the campaign and its index);
- :class:`EpisodeMetrics`: the numbers scored from the run (``episode_metrics``);
- :class:`CheckOutcome`: the invariants checked, those violated and the numbers the
  checks measure (the heading errors, the local maps' errors, the heading-bound ratio);
- :class:`EpisodeRecord`: one ``episodes.jsonl`` line — the spec, the outcome, the
  metrics, the run's digest and timings — and :class:`EpisodeOutcome`: the record and,
  for a failing episode, its reproducer document.

Each converts to plain JSON data (``to_json``) and back (``from_json``) only where it
crosses a process (a worker pool, dask) or a file (``episodes.jsonl``, a reproducer); the
JSON keys are the field names (unit-suffixed), in the order albot2d has always written
them. ``from_json`` reads a record already checked by ``files.check_episode_record`` (or
one albot2d wrote itself); what it still finds missing is an ``InputError``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field, fields
from typing import TYPE_CHECKING, Literal, Protocol, TypeAlias, cast

import numpy as np

from albot2d.errors import InputError

if TYPE_CHECKING:
    from albot2d.evaluation.run.setup import RunSpec

__all__ = [
    "STATUSES",
    "CheckMetrics",
    "CheckOutcome",
    "DrawParams",
    "EpisodeError",
    "EpisodeMetrics",
    "EpisodeOutcome",
    "EpisodeRecord",
    "EpisodeSpec",
    "EpisodeTimings",
    "Json",
    "JsonObject",
    "Status",
    "episode_seed",
    "finite_or_none",
]

#: A JSON value, as ``json.loads`` returns it.
Json: TypeAlias = "bool | int | float | str | list[Json] | dict[str, Json] | None"
#: A JSON object.
JsonObject: TypeAlias = "dict[str, Json]"

#: An episode's ``status``.
Status = Literal["ok", "violation", "crash"]
STATUSES: tuple[Status, ...] = ("ok", "violation", "crash")

# The largest run seed drawn for an episode (any non-negative int is a valid RunSpec seed).
_RUN_SEED_BOUND = 2**63
# Sizes and lengths are drawn on a decimetre grid so they print and replay exactly.
_DECIMETRE = 0.1


def finite_or_none(value: float | None) -> float | None:
    """``value`` as a float, ``None`` when it is missing or not finite (as JSON has it)."""
    if value is None:
        return None
    out = float(value)
    return out if math.isfinite(out) else None


def episode_seed(campaign_seed: int, index: int) -> np.random.SeedSequence:
    """Child ``index`` of the campaign seed, as ``SeedSequence(campaign_seed).spawn`` makes it."""
    return np.random.SeedSequence(campaign_seed, spawn_key=(index,))


def _decimetres(rng: np.random.Generator, low: float, high: float) -> float:
    lo, hi = math.ceil(low / _DECIMETRE - 1e-9), math.floor(high / _DECIMETRE + 1e-9)
    return round(int(rng.integers(lo, max(lo, hi) + 1)) * _DECIMETRE, 1)


class DrawParams(Protocol):
    """What drawing an episode reads of a campaign (``campaign.CampaignParams``)."""

    @property
    def seed(self) -> int: ...
    @property
    def kinds(self) -> tuple[str, ...]: ...
    @property
    def profile(self) -> str: ...
    @property
    def noise(self) -> str: ...
    @property
    def laser_noise(self) -> str: ...
    @property
    def mapper(self) -> str: ...
    @property
    def tour_kind(self) -> str: ...
    @property
    def world_size_min_m(self) -> float: ...
    @property
    def world_size_max_m(self) -> float: ...
    @property
    def tour_length_min_m(self) -> float: ...
    @property
    def tour_length_max_m(self) -> float: ...


def _object(value: object, where: str, name: str) -> Mapping[str, object]:
    if not isinstance(value, Mapping):
        raise InputError(f"{where}: {name} must be an object")
    return cast("Mapping[str, object]", value)


def _int(value: object, where: str, name: str) -> int:
    if isinstance(value, bool) or not isinstance(value, int):
        raise InputError(f"{where}: {name} must be an integer")
    return value


def _str(value: object, where: str, name: str) -> str:
    if not isinstance(value, str):
        raise InputError(f"{where}: {name} must be a string")
    return value


def _number(value: object, where: str, name: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise InputError(f"{where}: {name} must be a number")
    return value


def _number_or_none(value: object, where: str, name: str) -> float | None:
    return None if value is None else _number(value, where, name)


@dataclass(frozen=True)
class EpisodeSpec:
    """Everything one episode runs: drawn from the campaign parameters and the index."""

    index: int
    entropy: int
    kind: str
    world_params: Mapping[str, float]
    tour_length_m: float
    run_seed: int
    profile: str
    noise: str
    laser_noise: str
    tour_kind: str
    mapper: str

    @classmethod
    def draw(cls, campaign: DrawParams, index: int) -> EpisodeSpec:
        """Episode ``index`` of ``campaign`` (a ``CampaignParams``)."""
        from worldgen.kinds import get_kind

        rng = np.random.Generator(np.random.PCG64(episode_seed(campaign.seed, index)))
        kind = campaign.kinds[int(rng.integers(len(campaign.kinds)))]
        low = max(float(get_kind(kind).params.min_size_m), campaign.world_size_min_m)
        high = max(low, campaign.world_size_max_m)
        size = {"width_m": _decimetres(rng, low, high), "height_m": _decimetres(rng, low, high)}
        tour = _decimetres(rng, campaign.tour_length_min_m, campaign.tour_length_max_m)
        return cls(
            index=index, entropy=campaign.seed, kind=kind, world_params=size,
            tour_length_m=tour, run_seed=int(rng.integers(_RUN_SEED_BOUND)),
            profile=campaign.profile, noise=campaign.noise, laser_noise=campaign.laser_noise,
            tour_kind=campaign.tour_kind, mapper=campaign.mapper,
        )  # fmt: skip

    @classmethod
    def from_record(cls, record: Mapping[str, object], where: str = "record") -> EpisodeSpec:
        """The episode a record (an episodes.jsonl line, a reproducer's episode) describes."""
        for name in ("episode", "seed", "world", "tour", "run_seed"):
            if name not in record:
                raise InputError(f"{where}: not an episode record: missing {name!r}")
        seed = _object(record["seed"], where, "seed")
        world = _object(record["world"], where, "world")
        tour = _object(record["tour"], where, "tour")
        params = _object(world.get("params"), where, "world.params")
        return cls(
            index=_int(record["episode"], where, "episode"),
            entropy=_int(seed.get("entropy"), where, "seed.entropy"),
            kind=_str(world.get("kind"), where, "world.kind"),
            world_params={
                k: _number(v, where, f"world.params.{k[:40]}") for k, v in params.items()
            },
            tour_length_m=_number(tour.get("min_length_m"), where, "tour.min_length_m"),
            run_seed=_int(record["run_seed"], where, "run_seed"),
            profile=_str(record.get("profile"), where, "profile"),
            noise=_str(record.get("noise"), where, "noise"),
            laser_noise=_str(record.get("laser_noise"), where, "laser_noise"),
            tour_kind=_str(tour.get("kind"), where, "tour.kind"),
            mapper=_str(record.get("mapper"), where, "mapper"),
        )

    @property
    def spawn_key(self) -> tuple[int, ...]:
        return (self.index,)

    def run_spec(self) -> RunSpec:
        from albot2d.evaluation.run.setup import RunSpec

        return RunSpec(
            seed=self.run_seed, kind=self.kind, world_params=dict(self.world_params),
            profile=self.profile, noise=self.noise, laser_noise=self.laser_noise,
            tour_kind=self.tour_kind, tour_length_m=self.tour_length_m, mappers=(self.mapper,),
            tour_length_is_minimum=True,
        )  # fmt: skip

    def describe(self) -> JsonObject:
        """The record's header: seed, world, tour and driving parameters."""
        return {
            "episode": self.index,
            "seed": {"entropy": self.entropy, "spawn_key": list(self.spawn_key)},
            "run_seed": self.run_seed,
            "world": {"kind": self.kind, "params": dict(self.world_params)},
            "tour": {"kind": self.tour_kind, "min_length_m": self.tour_length_m},
            "profile": self.profile,
            "noise": self.noise,
            "laser_noise": self.laser_noise,
            "mapper": self.mapper,
        }


@dataclass(frozen=True, slots=True)
class EpisodeMetrics:
    """The numbers a campaign keeps of a run (``episode_metrics``): its (only) mapper's
    and raw odometry's scores. ``None``: not measurable on this run (no homing stop, no
    relation for the RPE, an empty map)."""

    frames: int
    travelled_m: float
    collided_frames: int
    local_maps: int
    triangulations: int
    path_integrations: int
    global_map_surfaces: int
    homing_stops: int
    homing_bearing_error_max_deg: float | None
    homing_distance_error_max_m: float | None
    rpe_trans_m: float | None
    rpe_rot_deg: float | None
    odometry_rpe_trans_m: float | None
    odometry_rpe_rot_deg: float | None
    end_trans_m: float | None
    end_rot_deg: float | None
    odometry_end_trans_m: float | None
    odometry_end_rot_deg: float | None
    map_accuracy_m: float | None
    map_accuracy_p95_m: float | None
    map_completeness: float | None

    _COUNTS = frozenset(
        ("frames", "collided_frames", "local_maps", "triangulations", "path_integrations",
         "global_map_surfaces", "homing_stops")
    )  # fmt: skip

    def to_json(self) -> JsonObject:
        return {f.name: getattr(self, f.name) for f in fields(self)}

    @classmethod
    def from_json(cls, metrics: Mapping[str, object], where: str) -> EpisodeMetrics:
        values: dict[str, int | float | None] = {}
        for f in fields(cls):
            if f.name not in metrics:
                raise InputError(f"{where}: no metrics {f.name}")
            value = metrics[f.name]
            if f.name in cls._COUNTS:
                values[f.name] = _int(value, where, f"metrics.{f.name}")
            elif f.name == "travelled_m":
                values[f.name] = _number(value, where, f"metrics.{f.name}")
            else:
                values[f.name] = _number_or_none(value, where, f"metrics.{f.name}")
        return cls(**values)  # type: ignore[arg-type]


#: The metrics ``CheckOutcome`` measures, in the order of the record; the first two only
#: when ``route_connected`` ran (a view-based mapper), the third only when
#: ``heading_error_bound`` ran.
_CHECK_METRICS = (
    ("local_map_position_error_max_m", "route_connected"),
    ("local_map_heading_error_max_deg", "route_connected"),
    ("heading_bound_ratio_max", "heading_error_bound"),
    ("heading_error_max_deg", None),
    ("heading_error_mean_deg", None),
    ("odometry_heading_error_max_deg", None),
    ("odometry_heading_error_mean_deg", None),
)


@dataclass(frozen=True, slots=True)
class CheckMetrics:
    """What the checks measure on the way: the mapper's and raw odometry's heading error
    (deg), each local map's pose error in its predecessor (view-based mappers) and the
    heading error's largest ratio to its bound (mappers held to one)."""

    heading_error_max_deg: float | None
    heading_error_mean_deg: float | None
    odometry_heading_error_max_deg: float | None
    odometry_heading_error_mean_deg: float | None
    local_map_position_error_max_m: float | None = None
    local_map_heading_error_max_deg: float | None = None
    heading_bound_ratio_max: float | None = None


@dataclass(frozen=True, slots=True)
class CheckOutcome:
    """The invariants checked on a run (sorted by name), the ones violated with their
    first messages (in the order found), and what the checks measured (``None`` for a
    run that crashed before they ran)."""

    checked: tuple[str, ...] = ()
    violations: Mapping[str, tuple[str, ...]] = field(default_factory=dict)
    metrics: CheckMetrics | None = None

    def metrics_json(self) -> JsonObject:
        """The checks' entries of the record's ``metrics``: a check's numbers appear when
        the check ran (``_CHECK_METRICS``)."""
        if self.metrics is None:
            return {}
        return {
            name: getattr(self.metrics, name)
            for name, check in _CHECK_METRICS
            if check is None or check in self.checked
        }

    def violations_json(self) -> JsonObject:
        return {name: list(messages) for name, messages in self.violations.items()}

    @classmethod
    def from_json(
        cls, checked: object, violations: object, metrics: Mapping[str, object], where: str
    ) -> CheckOutcome:
        if not isinstance(checked, list):
            raise InputError(f"{where}: checked must be a list")
        names = tuple(_str(name, where, "checked") for name in checked)
        found = {
            _str(name, where, "violations"): tuple(
                _str(m, where, f"violations.{name}") for m in cast("list[object]", messages)
            )
            for name, messages in _object(violations, where, "violations").items()
        }
        if not any(name in metrics for name, _ in _CHECK_METRICS):
            return cls(names, found, None)
        values = {
            name: _number_or_none(metrics.get(name), where, f"metrics.{name}")
            for name, _ in _CHECK_METRICS
        }
        return cls(names, found, CheckMetrics(**values))


@dataclass(frozen=True, slots=True)
class EpisodeError:
    """Why an episode crashed: the exception's type and message, and its traceback."""

    type: str
    message: str
    traceback: str | None = None

    @classmethod
    def of(cls, exc: BaseException) -> EpisodeError:
        import traceback

        return cls(type(exc).__name__, str(exc), "".join(traceback.format_exception(exc)))

    def to_json(self) -> JsonObject:
        out: JsonObject = {"type": self.type, "message": self.message}
        if self.traceback is not None:
            out["traceback"] = self.traceback
        return out

    @classmethod
    def from_json(cls, error: object, where: str) -> EpisodeError:
        e = _object(error, where, "error")
        tb = e.get("traceback")
        return cls(
            _str(e.get("type"), where, "error.type"),
            _str(e.get("message"), where, "error.message"),
            None if tb is None else _str(tb, where, "error.traceback"),
        )


@dataclass(frozen=True, slots=True)
class EpisodeTimings:
    """Wall-clock time of the episode (s) and per view (ms); ``None`` where unknown."""

    total_s: float | None = None
    ms_per_view: float | None = None


@dataclass(frozen=True)
class EpisodeRecord:
    """One ``episodes.jsonl`` line. ``spec`` is ``None`` only for an episode that could not
    even be drawn (then ``episode`` and ``entropy`` say which it was); ``world_sha256`` and
    ``tour_length_m`` are what the run made (``None`` for a crash); ``metrics`` is
    ``None`` for a crash."""

    episode: int
    entropy: int | None
    spec: EpisodeSpec | None
    status: Status
    checks: CheckOutcome = field(default_factory=CheckOutcome)
    error: EpisodeError | None = None
    metrics: EpisodeMetrics | None = None
    digest: str | None = None
    timings: EpisodeTimings = field(default_factory=EpisodeTimings)
    world_sha256: str | None = None
    tour_length_m: float | None = None
    spawn_key: tuple[int, ...] = ()  # the seed's spawn key as recorded; () means (episode,)

    def __post_init__(self) -> None:
        if not self.spawn_key:
            object.__setattr__(self, "spawn_key", (self.episode,))

    @property
    def failed(self) -> bool:
        return self.status != "ok"

    @property
    def checked(self) -> tuple[str, ...]:
        return self.checks.checked

    @property
    def violations(self) -> Mapping[str, tuple[str, ...]]:
        return self.checks.violations

    @property
    def kind(self) -> str | None:
        """The world kind (``None`` when the episode could not be drawn)."""
        return None if self.spec is None else self.spec.kind

    def metric(self, name: str) -> float | None:
        """A number of the record's ``metrics`` by its JSON name (``None`` if absent)."""
        value = self.metrics_json().get(name)
        return None if isinstance(value, bool) or not isinstance(value, int | float) else value

    def metrics_json(self) -> JsonObject:
        """The record's ``metrics``: the scored ones, then the checks' ones."""
        scored = {} if self.metrics is None else self.metrics.to_json()
        return scored | self.checks.metrics_json()

    def to_json(self, *, measurements: bool = True) -> JsonObject:
        """The episodes.jsonl line, as plain JSON data; without ``measurements`` (the
        ``metrics`` and ``timings``), a reproducer's ``episode``."""
        from albot2d.evaluation.run.report import plain

        if self.spec is None:
            out: JsonObject = {
                "episode": self.episode,
                "seed": {"entropy": self.entropy, "spawn_key": list(self.spawn_key)},
            }
        else:
            out = self.spec.describe()
            if self.world_sha256 is not None:
                cast("JsonObject", out["world"])["sha256"] = self.world_sha256
            if self.tour_length_m is not None:
                cast("JsonObject", out["tour"])["length_m"] = self.tour_length_m
        out |= {
            "status": self.status,
            "checked": list(self.checks.checked),
            "violations": self.checks.violations_json(),
            "error": None if self.error is None else self.error.to_json(),
        }
        if measurements:
            out["metrics"] = self.metrics_json()
        out["digest"] = self.digest
        if measurements:
            t = self.timings
            out["timings"] = {"total_s": t.total_s, "ms_per_view": t.ms_per_view}
        return cast("JsonObject", plain(out))

    @classmethod
    def from_json(cls, record: Mapping[str, object], where: str = "record") -> EpisodeRecord:
        """The record of an episodes.jsonl line or a reproducer's ``episode`` (which has no
        ``metrics`` or ``timings``)."""
        episode = _int(record.get("episode"), where, "episode")
        seed = _object(record.get("seed"), where, "seed")
        entropy = seed.get("entropy")
        key = seed.get("spawn_key")
        if not isinstance(key, list):
            raise InputError(f"{where}: seed.spawn_key must be a list")
        status = record.get("status")
        if status not in STATUSES:
            raise InputError(f"{where}: status must be one of {', '.join(STATUSES)}")
        spec = EpisodeSpec.from_record(record, where) if "world" in record else None
        world = _object(record.get("world", {}), where, "world")
        tour = _object(record.get("tour", {}), where, "tour")
        metrics = _object(record.get("metrics", {}), where, "metrics")
        error = record.get("error")
        timings = _object(record.get("timings", {}), where, "timings")
        sha = world.get("sha256")
        digest = record.get("digest")
        return cls(
            episode=episode,
            entropy=None if entropy is None else _int(entropy, where, "seed.entropy"),
            spec=spec,
            status=status,
            checks=CheckOutcome.from_json(
                record.get("checked", []), record.get("violations", {}), metrics, where
            ),
            error=None if error is None else EpisodeError.from_json(error, where),
            metrics=EpisodeMetrics.from_json(metrics, where) if "frames" in metrics else None,
            digest=None if digest is None else _str(digest, where, "digest"),
            timings=EpisodeTimings(
                _number_or_none(timings.get("total_s"), where, "timings.total_s"),
                _number_or_none(timings.get("ms_per_view"), where, "timings.ms_per_view"),
            ),
            world_sha256=None if sha is None else _str(sha, where, "world.sha256"),
            tour_length_m=_number_or_none(tour.get("length_m"), where, "tour.length_m"),
            spawn_key=tuple(_int(k, where, "seed.spawn_key") for k in key),
        )


@dataclass(frozen=True)
class EpisodeOutcome:
    """``record``: the episodes.jsonl line; ``reproducer``: the document to save (a
    report.json with a ``reproducer`` section), if failing."""

    record: EpisodeRecord
    reproducer: JsonObject | None = None

    @property
    def failed(self) -> bool:
        return self.record.failed

    def to_json(self) -> JsonObject:
        """Plain data, to cross a process boundary (``from_json`` reads it back)."""
        return {"record": self.record.to_json(), "reproducer": self.reproducer}

    @classmethod
    def from_json(cls, data: Mapping[str, object]) -> EpisodeOutcome:
        record = _object(data["record"], "outcome", "record")
        reproducer = data.get("reproducer")
        return cls(
            EpisodeRecord.from_json(record, "outcome"),
            None if reproducer is None else cast(JsonObject, reproducer),
        )
