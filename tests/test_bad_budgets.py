"""Bad inputs that attack memory and work, plugins, campaign files and the environment.

Part of the bad-input corpus (``tests/test_bad_*.py``), the second round: every case is
run as a user would, ``python -m albot2d`` in its own process, under a 3 GiB address-space
limit and a 60 s timeout (``tests/hostile.py``), and must end in one stderr line
``albot2d CMD: error: …`` naming the file (or option, variable, plugin) and the limit,
exit 2, no traceback and nothing written. Large inputs are generated at test time (a
gzip of a million log lines is ~1 MB on disk), never committed.
"""

from __future__ import annotations

import gzip
import json
import resource
import sys
import textwrap
from pathlib import Path
from typing import Any

import pytest

from tests import bad_inputs as bi
from tests.bad_input_checks import nothing_written
from tests.hostile import (
    GIB,
    MIB,
    Case,
    assert_refused,
    gzip_bomb,
    limited_run,
    replay_args,
    run_cli,
    simulate_world_args,
    write_log,
)


def million_identical_lines(tmp: Path) -> tuple[list[str], dict[str, str]]:
    # 19 beams a line keep the test quick: the scans are what the limit counts.
    line = (bi.flaser_line(1, ranges=["2.0"] * 19) + "\n").encode()
    log = gzip_bomb(tmp / "log.clf.gz", line * 1000, 1000)  # 1,000,000 lines, ~1 MB here
    assert log.stat().st_size < 4 * MIB
    return replay_args(log, "--relations", str(write_log(tmp).with_suffix(".relations"))), {}


def one_gigabyte_line(tmp: Path) -> tuple[list[str], dict[str, str]]:
    log = gzip_bomb(tmp / "log.clf.gz", b"FLASER 181 " + b"2.0 " * (MIB // 4), 1024)
    return replay_args(log), {}


def corrupt_deflate(tmp: Path) -> tuple[list[str], dict[str, str]]:
    data = bytearray(gzip.compress(bi.carmen_text().encode(), mtime=0))
    data[40:60] = b"\xff" * 20  # inside the deflate stream; the header stays valid
    log = tmp / "log.clf.gz"
    log.write_bytes(bytes(data))
    return replay_args(log), {}


def dev_zero_relations(tmp: Path) -> tuple[list[str], dict[str, str]]:
    return replay_args(write_log(tmp), "--relations", "/dev/zero"), {}


def relations_one_gigabyte_line(tmp: Path) -> tuple[list[str], dict[str, str]]:
    relations = gzip_bomb(tmp / "r.relations.gz", b"0" * MIB, 1024)
    return replay_args(write_log(tmp), "--relations", str(relations)), {}


def dev_zero_houseexpo(tmp: Path) -> tuple[list[str], dict[str, str]]:
    return ["world", "--from-houseexpo", "/dev/zero", "--out", "OUT"], {}


def dev_zero_report(tmp: Path) -> tuple[list[str], dict[str, str]]:
    return ["run", "--reproduce", "/dev/zero", "--out", "OUT"], {}


def dev_zero_world(tmp: Path) -> tuple[list[str], dict[str, str]]:
    return ["simulate", "--world", "/dev/zero", "--out", "OUT"], {}


def sparse_world(tmp: Path) -> tuple[list[str], dict[str, str]]:
    path = tmp / "w.json"
    with open(path, "wb") as out:
        out.truncate(65 * MIB)  # 65 MiB of zero bytes, none of them on disk
    return ["simulate", "--world", str(path), "--out", "OUT"], {}


def duplicated_walls(tmp: Path) -> tuple[list[str], dict[str, str]]:
    def mutate(doc: dict[str, Any]) -> None:
        doc["walls"] = doc["walls"] + doc["walls"][:1] * 400_000  # under the 500,000 cap

    return simulate_world_args(tmp, mutate), {}


def houseexpo_100k_vertices(tmp: Path) -> tuple[list[str], dict[str, str]]:
    import math

    n = 100_000
    verts = [[5 + 4 * math.cos(2 * math.pi * k / n), 5 + 4 * math.sin(2 * math.pi * k / n)]
             for k in range(n)]  # fmt: skip
    path = tmp / "he.json"
    path.write_text(json.dumps({"id": "h", "verts": verts}))
    return ["world", "--from-houseexpo", str(path), "--out", "OUT"], {}


def absurd_ndarray(tmp: Path) -> tuple[list[str], dict[str, str]]:
    def mutate(doc: dict[str, Any]) -> None:
        doc["params"]["grid"] = {
            "__type__": "ndarray", "dtype": "float64", "shape": [0, 10**12, 10**12], "data": [],
        }  # fmt: skip

    return simulate_world_args(tmp, mutate), {}


def box_on_start(tmp: Path) -> tuple[list[str], dict[str, str]]:
    def mutate(doc: dict[str, Any]) -> None:
        box = bi.box(doc)
        box["pose"] = list(doc["start"])
        doc["dynamic_obstacles"] = [box]

    return simulate_world_args(tmp, mutate), {}


def box_on_roadmap(tmp: Path) -> tuple[list[str], dict[str, str]]:
    def mutate(doc: dict[str, Any]) -> None:
        nodes, (i, j) = doc["roadmap"]["nodes"], doc["roadmap"]["edges"][-1]
        box = bi.box(doc)
        box["pose"] = [(nodes[i][0] + nodes[j][0]) / 2, (nodes[i][1] + nodes[j][1]) / 2, 0.0]
        doc["dynamic_obstacles"] = [box]

    return simulate_world_args(tmp, mutate), {}


def episodes_1e9(tmp: Path) -> tuple[list[str], dict[str, str]]:
    return ["fuzz", "--episodes", "1000000000", "--out", "OUT"], {}


def bad_mplbackend(tmp: Path) -> tuple[list[str], dict[str, str]]:
    return ["run", "--kind", "rooms", "--max-frames", "3", "--out", "OUT"], {"MPLBACKEND": "nope"}


def bad_plugins_variable(tmp: Path) -> tuple[list[str], dict[str, str]]:
    env = {"ALBOT2D_PLUGINS": "[[[" * 10}
    return ["run", "--kind", "rooms", "--max-frames", "3", "--out", "OUT"], env


def _plugin(body: str) -> Case:
    def build(tmp: Path) -> tuple[list[str], dict[str, str]]:
        (tmp / "plug.py").write_text(textwrap.dedent(body))
        argv = ["run", "--kind", "rooms", "--max-frames", "3", "--mapper", "plug:Mapper"]
        return [*argv, "--no-figures", "--out", "OUT"], {}

    return build


_MAPPER = """
from albot2d.mapping.baselines import NaiveIntegration
class Mapper(NaiveIntegration):
    def __init__(self):
        {init}
        super().__init__()
"""

# (id, case, texts the error line must hold)
CASES: list[tuple[str, Case, tuple[str, ...]]] = [
    ("log-gzip-million-lines", million_identical_lines, ("log.clf.gz:", "MAX_LOG_SCANS")),
    ("log-gzip-one-1gb-line", one_gigabyte_line, ("log.clf.gz:1:", "MAX_LINE_BYTES")),
    ("log-corrupt-deflate", corrupt_deflate, ("log.clf.gz", "corrupt or truncated gzip")),
    ("relations-dev-zero", dev_zero_relations, ("/dev/zero",)),
    ("relations-gzip-1gb-line", relations_one_gigabyte_line, ("r.relations.gz:1:", "MAX_LINE")),
    ("houseexpo-dev-zero", dev_zero_houseexpo, ("/dev/zero", "MAX_JSON_FILE_BYTES")),
    ("report-dev-zero", dev_zero_report, ("/dev/zero",)),
    ("world-dev-zero", dev_zero_world, ("/dev/zero", "no such world file")),
    ("world-65mib-of-zeros", sparse_world, ("w.json", "MAX_WORLD_FILE_BYTES")),
    ("world-400k-duplicated-walls", duplicated_walls, ("w.json", "repeats walls[0]", "400000")),
    ("houseexpo-100k-vertices", houseexpo_100k_vertices, ("he.json", "MAX_HOUSEEXPO_VERTICES")),
    ("world-ndarray-absurd-shape", absurd_ndarray, ("params.grid.shape", "MAX_ARRAY_ITEMS")),
    ("world-box-on-start", box_on_start, ("dynamic_obstacles[0]", "start disc")),
    ("world-box-on-roadmap", box_on_roadmap, ("dynamic_obstacles[0]", "blocks the roadmap")),
    ("fuzz-episodes-1e9", episodes_1e9, ("1000000000", "MAX_CAMPAIGN_EPISODES")),
    ("env-mplbackend", bad_mplbackend, ("MPLBACKEND='nope'",)),
    ("env-plugins", bad_plugins_variable, ("ALBOT2D_PLUGINS",)),
    (
        "plugin-runtime-error-at-import",
        _plugin("raise RuntimeError('no GPU here')"),
        ("plug:Mapper", "RuntimeError: no GPU here"),
    ),
    ("plugin-syntax-error", _plugin("def broken(:\n"), ("plug:Mapper", "SyntaxError")),
    (
        "plugin-sys-exit-0-at-import",
        _plugin("import sys\nsys.exit(0)"),
        ("plug:Mapper", "SystemExit(0)"),
    ),
    (
        "plugin-constructor-raises",
        _plugin(_MAPPER.format(init="raise ValueError('bad config')")),
        ("plug:Mapper", "constructing Mapper failed", "ValueError: bad config"),
    ),
    (
        "plugin-constructor-exits",
        _plugin(_MAPPER.format(init="raise SystemExit(3)")),
        ("plug:Mapper", "SystemExit(3)"),
    ),
]


@pytest.mark.parametrize(("case", "expected"), [c[1:] for c in CASES], ids=[c[0] for c in CASES])
def test_refused_in_one_line_under_3gb_and_60s(case: Case, expected, tmp_path: Path) -> None:
    argv, env = case(tmp_path)
    out = tmp_path / "out"
    argv = [str(out) if a == "OUT" else a for a in argv]
    proc = run_cli(*argv, cwd=tmp_path, env=env)
    assert_refused(proc, argv[0], *expected)
    nothing_written(out)
    if argv[0] == "fuzz":
        assert not (out / "campaign.json").exists()


_READ_1GB = """
import resource, sys
from albot2d.errors import InputError
from albot2d.logs.log_frames import read_frames
try:
    n = sum(1 for _ in read_frames(sys.argv[1]))
except InputError as exc:
    print(f"refused: {exc}")
    kib = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    print(f"peak {kib / 1024:.0f} MiB")
    sys.exit(2)
print(f"read {n} frames")
"""


def test_a_1gb_expanding_gzip_is_refused_under_a_1gb_address_space(tmp_path: Path) -> None:
    """Peak memory grows with what is kept, not with the file: 1 GiB of log lines the reader
    keeps nothing of (1 MiB lines of an unknown message type, skipped and counted), read by
    a process that may map 1 GiB in all, is refused at MAX_TEXT_BYTES (512 MiB)."""
    line = b"UNKNOWN_MESSAGE " + b"x" * (MIB - 18) + b"\n"
    log = gzip_bomb(tmp_path / "bomb.clf.gz", line, 1024)
    assert log.stat().st_size < 8 * MIB
    proc = limited_run([sys.executable, "-c", _READ_1GB, str(log)], cwd=tmp_path, address_space=GIB)
    assert proc.returncode == 2, proc.stderr[-3000:]
    refused, peak = proc.stdout.strip().splitlines()
    assert "bomb.clf.gz" in refused and "MAX_TEXT_BYTES" in refused, refused
    peak_mib = float(peak.split()[1])
    assert peak_mib < 512, peak  # far below the 1 GiB it read
    print(f"1 GiB gzip bomb: {refused}; peak RSS {peak_mib:.0f} MiB")


def test_the_address_space_limit_is_real(tmp_path: Path) -> None:
    """The harness itself: a child that allocates 4 GiB under the 3 GiB limit fails."""
    proc = limited_run([sys.executable, "-c", "b = bytearray(4 * 2**30)"], cwd=tmp_path)
    assert proc.returncode != 0 and "MemoryError" in proc.stderr
    assert resource.getrlimit(resource.RLIMIT_AS)[0] != 3 * GIB  # the test process is not limited
