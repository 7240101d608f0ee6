"""Campaign folders as untrusted input: ``fuzz --resume`` on forged or damaged files.

Part of the bad-input corpus: a valid campaign folder (``campaign.json`` as albot2d writes
it, whole ``episodes.jsonl`` records from ``tests/bad_inputs.py``) with one thing broken;
``python -m albot2d fuzz --resume`` under the 3 GiB / 60 s limits of ``tests/hostile.py``
must refuse it in one line naming the file (and line) and leave the folder as it was.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from albot2d.evaluation.fuzz.campaign import CAMPAIGN_NAME, EPISODES_NAME, CampaignParams
from albot2d.evaluation.fuzz.lock import _read_pid
from tests import bad_inputs as bi
from tests.hostile import MIB, assert_refused, run_cli

PARAMS = CampaignParams(
    episodes=3,
    kinds=("corridors",),
    world_size_min_m=12.0,
    world_size_max_m=14.0,
    tour_length_min_m=8.0,
    tour_length_max_m=12.0,
)
ARGS = ["--episodes", "3", "--kinds", "corridors", "--world-size", "12", "14",
        "--tour-length", "8", "12", "--profile", "dataset3", "--no-figures"]  # fmt: skip


def _campaign(params: dict[str, Any] | None = None) -> dict[str, Any]:
    return {
        "format": "albot2d-campaign",
        "format_version": 1,
        "params": PARAMS.to_dict() if params is None else params,
    }


def _lines(*records: dict[str, Any]) -> bytes:
    return b"".join(json.dumps(r).encode() + b"\n" for r in records)


def _params(**changes: Any) -> dict[str, Any]:
    return PARAMS.to_dict() | changes


def _record(**changes: Any) -> dict[str, Any]:
    return bi.episode_record(1) | changes


# (id, campaign.json text, episodes.jsonl bytes, texts the error line must hold)
CASES: list[tuple[str, str | Callable[[Path], None], bytes, tuple[str, ...]]] = [
    (
        "campaign-deep-nesting",
        json.dumps(_campaign())[:-1] + ', "x": ' + bi.nested(100_000) + "}",
        b"",
        (CAMPAIGN_NAME, "nested deeper than 64"),
    ),
    (
        "campaign-params-string-for-number",
        json.dumps(_campaign(_params(world_size_min_m="12"))),
        b"",
        (CAMPAIGN_NAME, "params.world_size_min_m", "wrong type"),
    ),
    (
        "campaign-params-kinds-object",
        json.dumps(_campaign(_params(kinds={"corridors": 1}))),
        b"",
        (CAMPAIGN_NAME, "params.kinds"),
    ),
    (
        "campaign-params-episodes-bool",
        json.dumps(_campaign(_params(episodes=True))),
        b"",
        (CAMPAIGN_NAME, "params.episodes"),
    ),
    (
        "campaign-65mib",
        lambda folder: _sparse(folder / CAMPAIGN_NAME, 65 * MIB),
        b"",
        (CAMPAIGN_NAME, "MAX_JSON_FILE_BYTES"),
    ),
    (
        "record-ok-with-an-error",
        json.dumps(_campaign()),
        _lines(bi.episode_record(0), _record(error={"type": "X", "message": "y"})),
        (f"{EPISODES_NAME}:2:", "contradicts"),
    ),
    (
        "record-minimal-ok",
        json.dumps(_campaign()),
        _lines(
            bi.episode_record(0),
            {"episode": 1, "status": "ok", "seed": {"entropy": 0, "spawn_key": [1]}},
        ),
        (f"{EPISODES_NAME}:2:", "not an episode record"),
    ),
    (
        "record-ok-without-metrics",
        json.dumps(_campaign()),
        _lines(_record(metrics={})),
        (f"{EPISODES_NAME}:1:", "no metrics frames"),
    ),
    (
        "record-crash-without-error",
        json.dumps(_campaign()),
        _lines(_record(status="crash")),
        (f"{EPISODES_NAME}:1:", "error.type"),
    ),
    (
        "record-violation-without-violations",
        json.dumps(_campaign()),
        _lines(_record(status="violation")),
        (f"{EPISODES_NAME}:1:", "no violations"),
    ),
    (
        "record-metric-text",
        json.dumps(_campaign()),
        _lines(_record(metrics=bi.episode_record(1)["metrics"] | {"frames": "ten"})),
        (f"{EPISODES_NAME}:1:", "metrics.frames"),
    ),
    (
        "record-world-a-list",
        json.dumps(_campaign()),
        _lines(_record(world=[1, 2])),
        (f"{EPISODES_NAME}:1:", "world must be an object"),
    ),
    (
        "record-deep-nesting",
        json.dumps(_campaign()),
        bi.nested(100_000).encode() + b"\n",
        (f"{EPISODES_NAME}:1:", "nested deeper than 64"),
    ),
    (
        "record-4mib-line",
        json.dumps(_campaign()),
        b'{"episode": 0, "pad": "' + b"x" * (4 * MIB) + b'"}\n',
        (f"{EPISODES_NAME}:1:", "MAX_EPISODE_RECORD_BYTES"),
    ),
]


def _sparse(path: Path, size: int) -> None:
    with open(path, "wb") as out:
        out.truncate(size)


@pytest.mark.parametrize(
    ("campaign", "episodes", "expected"), [c[1:] for c in CASES], ids=[c[0] for c in CASES]
)
def test_resume_refuses_a_forged_campaign_folder(campaign, episodes, expected, tmp_path) -> None:
    out = tmp_path / "fuzz"
    out.mkdir()
    if callable(campaign):
        campaign(out)
    else:
        (out / CAMPAIGN_NAME).write_text(campaign)
    (out / EPISODES_NAME).write_bytes(episodes)
    before = {p.name: p.stat().st_size for p in out.iterdir()}
    proc = run_cli("fuzz", *ARGS, "--resume", "--out", str(out), cwd=tmp_path)
    assert_refused(proc, "fuzz", *expected)
    assert {p.name: p.stat().st_size for p in out.iterdir()} == before


@pytest.mark.parametrize(
    ("content", "pid"),
    [(b"123\n", 123), (b"9" * 5000, None), (b"-4\n", None), (b"\x00" * 100, None), (b"", None)],
)
def test_a_lock_file_is_read_as_untrusted(tmp_path: Path, content: bytes, pid) -> None:
    path = tmp_path / "campaign.lock"
    path.write_bytes(content)
    assert _read_pid(path) == pid
