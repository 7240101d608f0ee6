"""A campaign's files read back as untrusted input: ``campaign.json`` and ``episodes.jsonl``.

``--resume`` reads what an earlier campaign left in a folder, and anyone may have edited,
truncated or forged it. Each document is checked here before the campaign uses it: its
size and depth (``albot2d.limits``), its schema (every field the campaign reads, with its
type) and its consistency (a record's ``status`` agrees with its ``violations``, ``error``
and ``metrics``: an ``ok`` record has every metric an episode reports, no violation and
no error). Every failure is one :class:`~albot2d.errors.InputError` naming the file (and
line) and the field.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import TypeVar, cast

from albot2d.errors import InputError
from albot2d.evaluation.fuzz.record import STATUSES, JsonObject

__all__ = ["OK_METRICS", "check_campaign_values", "check_episode_record"]

T = TypeVar("T")

#: Metrics every ``ok`` or ``violation`` record holds a number for (every other metric of
#: ``EpisodeMetrics`` it holds too, a number or null: ``EpisodeRecord.from_json`` says so).
OK_METRICS = ("frames", "travelled_m", "collided_frames")

_PARAM_TYPES: dict[str, tuple[type, ...]] = {
    "episodes": (int,),
    "seed": (int,),
    "kinds": (list,),
    "profile": (str,),
    "noise": (str,),
    "laser_noise": (str,),
    "mapper": (str,),
    "tour_kind": (str,),
    "world_size_min_m": (int, float),
    "world_size_max_m": (int, float),
    "tour_length_min_m": (int, float),
    "tour_length_max_m": (int, float),
}
_SHORT = 60


def _short(value: object) -> str:
    text = repr(value)
    return text if len(text) <= _SHORT else text[: _SHORT - 3] + "..."


def _kind(value: object) -> str:
    names = {dict: "an object", list: "a list", str: "a string", bool: "a boolean"}
    return names.get(type(value), "null" if value is None else "a number")


def check_campaign_values(values: object, where: str) -> JsonObject:
    """``campaign.json``'s ``params``: an object of the campaign's fields, each of its type
    (no booleans for numbers, a list of strings for ``kinds``); returns it."""
    if not isinstance(values, dict):
        raise InputError(f"{where}: params must be an object, got {_kind(values)}")
    for name, value in values.items():
        types = _PARAM_TYPES.get(name)
        if types is None:
            continue  # CampaignParams names unknown parameters itself
        if isinstance(value, bool) or not isinstance(value, types):
            raise InputError(f"{where}: params.{name} has the wrong type: {_short(value)}")
        if isinstance(value, list) and not all(isinstance(k, str) for k in value):
            raise InputError(f"{where}: params.kinds must be a list of names, got {_short(value)}")
    return cast(JsonObject, values)


def _need(record: Mapping[str, object], name: str, types: tuple[type[T], ...], where: str) -> T:
    if name not in record:
        raise InputError(f"{where}: no {name}")
    value = record[name]
    if (isinstance(value, bool) and bool not in types) or not isinstance(value, types):
        raise InputError(f"{where}: {name} must be {_types(types)}, got {_short(value)}")
    return value


def _types(types: tuple[type, ...]) -> str:
    names = {int: "an integer", float: "a number", str: "a string", dict: "an object",
             list: "a list", type(None): "null", bool: "a boolean"}  # fmt: skip
    return " or ".join(names[t] for t in types)


def _number_or_null(value: object) -> bool:
    if value is None:
        return True
    return (
        not isinstance(value, bool)
        and isinstance(value, int | float)
        and (isinstance(value, int) or math.isfinite(value))
    )


def check_episode_record(record: object, where: str) -> JsonObject:
    """One ``episodes.jsonl`` line (``where`` is ``file:line``): the fields the campaign and
    its summary read, with their types, and a status that agrees with them."""
    if not isinstance(record, dict):
        raise InputError(f"{where}: {_kind(record)}, not an object")
    index = _need(record, "episode", (int,), where)
    if index < 0:
        raise InputError(f"{where}: episode must be >= 0, got {index}")
    status = _need(record, "status", (str,), where)
    if status not in STATUSES:
        raise InputError(
            f"{where}: status must be one of {', '.join(STATUSES)}, got {_short(status)}"
        )
    seed = _need(record, "seed", (dict,), where)
    if not isinstance(seed.get("spawn_key"), list):
        raise InputError(f"{where}: seed must hold entropy and spawn_key, got {_short(seed)}")
    checked = _need(record, "checked", (list,), where)
    if not all(isinstance(name, str) for name in checked):
        raise InputError(f"{where}: checked must be a list of invariant names")
    violations = _need(record, "violations", (dict,), where)
    for name, messages in violations.items():
        if not (
            isinstance(messages, list) and messages and all(isinstance(m, str) for m in messages)
        ):
            raise InputError(f"{where}: violations.{name[:40]} must be a list of messages")
    error = _need(record, "error", (dict, type(None)), where)
    metrics = _need(record, "metrics", (dict,), where)
    for name, value in metrics.items():
        if not _number_or_null(value):
            raise InputError(
                f"{where}: metrics.{name[:40]} must be a number or null, got {_short(value)}"
            )
    if "world" in record or status != "crash":  # a crash may precede drawing the episode
        world = _need(record, "world", (dict,), where)
        if not isinstance(world.get("kind"), str) or not isinstance(world.get("params"), dict):
            raise InputError(f"{where}: world must hold a kind and params, got {_short(world)}")
        tour = _need(record, "tour", (dict,), where)
        if not isinstance(tour.get("kind"), str) or not _number_or_null(tour.get("min_length_m")):
            raise InputError(f"{where}: tour must hold a kind and min_length_m, got {_short(tour)}")
        _need(record, "run_seed", (int,), where)
        for name in ("profile", "noise", "laser_noise", "mapper"):
            _need(record, name, (str,), where)
    # The status must agree with the fields the summary counts.
    if status == "crash":
        if not (isinstance(error, dict) and isinstance(error.get("type"), str)
                and isinstance(error.get("message"), str)):  # fmt: skip
            raise InputError(f"{where}: a crash record needs error.type and error.message")
    elif error is not None:
        raise InputError(f"{where}: status {status!r} with an error: the record contradicts itself")
    if status == "violation" and not violations:
        raise InputError(f"{where}: status 'violation' with no violations")
    if status == "ok" and violations:
        raise InputError(f"{where}: status 'ok' with violations: the record contradicts itself")
    if status != "crash":
        missing = [name for name in OK_METRICS if metrics.get(name) is None]
        if missing:
            raise InputError(f"{where}: status {status!r} but no metrics {', '.join(missing)}")
    return record
