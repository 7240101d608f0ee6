"""A held-out set of the same attack classes as ``tests/test_bad_budgets.py``.

Written after the fixes and not used while making them: other instances of each class
(size bombs of other shapes, other ways to repeat walls or blow up arrays, other plugin
failures, other forged campaign files, other bad environment values). Same rules: a
``python -m albot2d`` process under 3 GiB and 60 s, one line ``albot2d CMD: error: …``,
exit 2, nothing written.
"""

from __future__ import annotations

import gzip
import json
import textwrap
from pathlib import Path
from typing import Any

import pytest

from tests import bad_inputs as bi
from tests.bad_input_checks import nothing_written
from tests.hostile import (
    MIB,
    Case,
    assert_refused,
    gzip_bomb,
    replay_args,
    run_cli,
    simulate_world_args,
    write_log,
)
from tests.test_bad_campaign_files import ARGS as FUZZ_ARGS
from tests.test_bad_campaign_files import PARAMS


def sparse_plain_log(tmp: Path) -> tuple[list[str], dict[str, str]]:
    path = tmp / "zeros.clf"
    with open(path, "wb") as out:
        out.truncate(600 * MIB)
    return replay_args(path), {}


def gzip_of_600mib_comments(tmp: Path) -> tuple[list[str], dict[str, str]]:
    log = gzip_bomb(tmp / "c.clf.gz", b"# " + b"c" * (MIB - 3) + b"\n", 600)
    return replay_args(log), {}


def truncated_gzip_relations(tmp: Path) -> tuple[list[str], dict[str, str]]:
    data = gzip.compress(bi.relations_text().encode() * 50, mtime=0)
    path = tmp / "r.relations.gz"
    path.write_bytes(data[: len(data) * 2 // 3])
    return replay_args(write_log(tmp), "--relations", str(path)), {}


def reversed_repeats(tmp: Path) -> tuple[list[str], dict[str, str]]:
    def mutate(doc: dict[str, Any]) -> None:
        x1, y1, x2, y2 = doc["walls"][3]
        doc["walls"] += [[x2, y2, x1, y1]] * 1000

    return simulate_world_args(tmp, mutate), {}


def long_walls(tmp: Path) -> tuple[list[str], dict[str, str]]:
    def mutate(doc: dict[str, Any]) -> None:
        doc["walls"] += [[0.0, 0.01 * k, 99_999.0, 0.01 * k] for k in range(6)]

    return simulate_world_args(tmp, mutate), {}


def many_dimensions(tmp: Path) -> tuple[list[str], dict[str, str]]:
    def mutate(doc: dict[str, Any]) -> None:
        doc["features"]["cube"] = {
            "__type__": "ndarray", "dtype": "int8", "shape": [1] * 40, "data": [1],
        }  # fmt: skip

    return simulate_world_args(tmp, mutate), {}


def person_on_start(tmp: Path) -> tuple[list[str], dict[str, str]]:
    def mutate(doc: dict[str, Any]) -> None:
        doc["dynamic_obstacles"] = [bi.person(doc, pose=list(doc["start"]))]

    return simulate_world_args(tmp, mutate), {}


def houseexpo_6000(tmp: Path) -> tuple[list[str], dict[str, str]]:
    verts = [[k * 0.001, (k % 2) * 0.5] for k in range(6000)]
    path = tmp / "he.json"
    path.write_text(json.dumps({"id": "zigzag", "verts": verts}))
    return ["world", "--from-houseexpo", str(path), "--out", "OUT"], {}


def _plugin(body: str) -> Case:
    def build(tmp: Path) -> tuple[list[str], dict[str, str]]:
        (tmp / "plug2.py").write_text(textwrap.dedent(body))
        argv = ["run", "--kind", "rooms", "--max-frames", "3", "--mapper", "plug2:M"]
        return [*argv, "--no-figures", "--out", "OUT"], {}

    return build


def _resume(episodes: bytes, campaign: str | None = None) -> Case:
    def build(tmp: Path) -> tuple[list[str], dict[str, str]]:
        out = tmp / "out"
        out.mkdir()
        doc = {"format": "albot2d-campaign", "format_version": 1, "params": PARAMS.to_dict()}
        (out / "campaign.json").write_text(campaign or json.dumps(doc))
        (out / "episodes.jsonl").write_bytes(episodes)
        return ["fuzz", *FUZZ_ARGS, "--resume", "--out", "KEEP"], {}

    return build


def _record(**changes: Any) -> bytes:
    return json.dumps(bi.episode_record(0) | changes).encode() + b"\n"


CASES: list[tuple[str, Case, tuple[str, ...]]] = [
    ("log-600mib-of-zero-bytes", sparse_plain_log, ("zeros.clf:1:", "MAX_LINE_BYTES")),
    ("log-gzip-600mib-of-comments", gzip_of_600mib_comments, ("c.clf.gz", "MAX_TEXT_BYTES")),
    ("relations-truncated-gzip", truncated_gzip_relations, ("r.relations.gz", "corrupt")),
    ("world-reversed-repeats", reversed_repeats, ("repeats walls[3]", "1000 walls")),
    ("world-600km-of-walls", long_walls, ("MAX_TOTAL_WALL_LENGTH_M",)),
    ("world-40-dimensions", many_dimensions, ("features.cube.shape", "MAX_ARRAY_DIMENSIONS")),
    ("world-person-on-start", person_on_start, ("dynamic_obstacles[0]", "start disc")),
    ("houseexpo-6000-vertices", houseexpo_6000, ("he.json", "MAX_HOUSEEXPO_VERTICES")),
    (
        "plugin-recursion-at-import",
        _plugin("def f():\n    return f()\nf()"),
        ("plug2:M", "RecursionError"),
    ),
    (
        "plugin-constructor-memory-error",
        _plugin(
            "from albot2d.mapping.baselines import NaiveIntegration\n"
            "class M(NaiveIntegration):\n    def __init__(self):\n        raise MemoryError"
        ),
        ("plug2:M", "constructing M failed", "MemoryError"),
    ),
    ("plugin-not-a-module-name", _plugin(""), ("plug2:M",)),
    (
        "fuzz-episodes-100001",
        lambda t: (["fuzz", "--episodes", "100001", "--out", "OUT"], {}),
        ("MAX_CAMPAIGN_EPISODES",),
    ),
    (
        "env-mplbackend-case",
        lambda t: (["world", "--kind", "rooms", "--out", "OUT"], {"MPLBACKEND": "Agg2"}),
        ("MPLBACKEND",),
    ),
    (
        "env-data-folder-missing",
        lambda t: (["replay", "nothing.clf", "--out", "OUT"], {"ALBOT2D_DATA": "/nonexistent"}),
        ("ALBOT2D_DATA", "not a folder"),
    ),
    (
        "campaign-status-crash-with-metrics-only",
        _resume(_record(status="crash")),
        ("episodes.jsonl:1:", "error.type"),
    ),
    (
        "campaign-violations-not-lists",
        _resume(_record(status="violation", violations={"route_connected": "broken"})),
        ("episodes.jsonl:1:", "violations.route_connected"),
    ),
    (
        "campaign-params-deep-in-kinds",
        _resume(
            b"",
            json.dumps(
                {
                    "format": "albot2d-campaign",
                    "format_version": 1,
                    "params": {"kinds": json.loads(bi.nested(60))},
                }
            ),
        ),
        ("campaign.json",),
    ),
]


@pytest.mark.parametrize(("case", "expected"), [c[1:] for c in CASES], ids=[c[0] for c in CASES])
def test_held_out_case_refused_in_one_line(case: Case, expected, tmp_path: Path) -> None:
    argv, env = case(tmp_path)
    out = tmp_path / "out"
    before = sorted(p.name for p in out.iterdir()) if out.exists() else None
    argv = [str(out) if a in ("OUT", "KEEP") else a for a in argv]
    proc = run_cli(*argv, cwd=tmp_path, env=env)
    assert_refused(proc, argv[0], *expected)
    if before is None:
        nothing_written(out)
    else:
        assert sorted(p.name for p in out.iterdir()) == before
