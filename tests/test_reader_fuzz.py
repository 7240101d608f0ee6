"""Property-based fuzzing of the readers: mutated world files, CARMEN logs and relations
files either read or raise ``InputError``, never anything else.

Also the gzip layer (bit flips, cut and spliced members, trailing garbage) and a
campaign's files (``episodes.jsonl`` records and ``campaign.json``, read back on
``--resume``). Hypothesis mutates valid inputs (``tests/bad_inputs.py``) byte by byte and
field by field, with the values that break readers (NaN, infinities, 1e308, huge integers,
deep nesting, wrong types). A world that is accepted must also build its raycast grid and
pymunk space; a log that is accepted must also go through the time-order rule. The ``ci``
profile tries 25 inputs per test;
``HYPOTHESIS_PROFILE=fuzz python -m pytest tests/test_reader_fuzz.py`` tries 5000.
"""

from __future__ import annotations

import copy
import gzip
import json
import zlib
from pathlib import Path
from typing import Any

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from albot2d.errors import InputError
from albot2d.logs.anomalies import ordered_frames
from albot2d.logs.log_frames import read_frames
from albot2d.logs.relations import read_relations
from albot2d.sim.raycast_grid import SegmentGrid
from albot2d.validation import COORDINATE_LIMIT_M
from tests import bad_inputs as bi
from tests.log_strategies import frame_sequences
from tests.strategies import corrupted
from worldgen.io import load
from worldgen.space import build_space

_NASTY_NUMBERS = st.sampled_from(
    [0, -1, 1e308, -1e308, 1e-308, 10**30, 10**400, float("nan"), float("inf"), 1e7, 0.5]
)
_JSON_VALUES = st.recursive(
    st.none() | st.booleans() | _NASTY_NUMBERS | st.floats() | st.integers() | st.text(max_size=5),
    lambda inner: st.lists(inner, max_size=4) | st.dictionaries(st.text(max_size=4), inner),
    max_leaves=12,
)
_TOKENS = st.sampled_from(
    ["nan", "inf", "-inf", "-1", "0", "1e308", "-1e308", "1e-320", "9" * 30, "abc", "", "#",
     "FLASER", "PARAM", "ODOM", "ROBOTLASER1", "1.5", "181", "999999"]
)  # fmt: skip


def _paths(value: Any, prefix: tuple[Any, ...] = ()) -> list[tuple[Any, ...]]:
    """Every path to a value inside a JSON document (object keys and list indices)."""
    out = [prefix]
    if isinstance(value, dict):
        for key, item in value.items():
            out += _paths(item, (*prefix, key))
    elif isinstance(value, list):
        for index, item in enumerate(value[:6]):  # a few items of each list are enough
            out += _paths(item, (*prefix, index))
    return out


def _replace_at(doc: Any, path: tuple[Any, ...], value: Any) -> Any:
    if not path:
        return value
    parent = doc
    for key in path[:-1]:
        parent = parent[key]
    parent[path[-1]] = value
    return doc


def _check_world_file(path: Path) -> None:
    try:
        world = load(path)
    except InputError:
        return
    SegmentGrid(world.obstacle_segments)
    build_space(world)


@st.composite
def _mutated_world_docs(draw: st.DrawFn) -> str:
    doc = bi.world_doc()
    if draw(st.booleans()):
        doc["dynamic_obstacles"] = [bi.person(doc)]
    for _ in range(draw(st.integers(1, 3))):
        paths = _paths(doc)
        path = draw(st.sampled_from(paths))
        doc = _replace_at(doc, path, draw(_JSON_VALUES))
    return json.dumps(doc)


@st.composite
def _mutated_bytes(draw: st.DrawFn, text: str) -> bytes:
    chunks = st.binary(min_size=1, max_size=4) | _TOKENS.map(str.encode)
    return draw(corrupted(text.encode(), edits=(1, 8), chunks=chunks, flips=False))


@given(_mutated_world_docs())
def test_world_field_mutations_raise_only_input_error(tmp_path_factory, text: str) -> None:
    path = tmp_path_factory.mktemp("w") / "w.json"
    path.write_text(text)
    _check_world_file(path)


@given(st.data())
def test_world_byte_mutations_raise_only_input_error(tmp_path_factory, data) -> None:
    path = tmp_path_factory.mktemp("w") / "w.json"
    path.write_bytes(data.draw(_mutated_bytes(bi.world_text())))
    _check_world_file(path)


@st.composite
def _mutated_log_lines(draw: st.DrawFn) -> str:
    lines = bi.carmen_lines()[:12]
    for _ in range(draw(st.integers(1, 6))):
        k = draw(st.integers(0, len(lines) - 1))
        tokens = lines[k].split(" ")
        op = draw(st.sampled_from(["token", "drop-token", "swap-lines", "dup-line"]))
        i = draw(st.integers(0, len(tokens) - 1))
        if op == "token":
            tokens[i] = draw(_TOKENS | st.floats().map(repr))
        elif op == "drop-token":
            del tokens[i]
        elif op == "swap-lines":
            j = draw(st.integers(0, len(lines) - 1))
            lines[k], lines[j] = lines[j], lines[k]
            continue
        else:
            lines.insert(k, lines[k])
            continue
        lines[k] = " ".join(tokens)
    return bi.carmen_text(lines)


def _check_log(path: Path) -> None:
    try:
        frames, anomalies = ordered_frames(read_frames(path))
    except InputError:
        return
    assert anomalies.frames_kept == len(frames) <= anomalies.frames_read
    stamps = [f.timestamp for f in frames]
    assert stamps == sorted(set(stamps))  # the time-order rule holds for every log read


@given(_mutated_log_lines())
def test_log_field_mutations_raise_only_input_error(tmp_path_factory, text: str) -> None:
    path = tmp_path_factory.mktemp("log") / "log.clf"
    path.write_text(text)
    _check_log(path)


@given(st.data())
def test_log_byte_mutations_raise_only_input_error(tmp_path_factory, data) -> None:
    path = tmp_path_factory.mktemp("log") / "log.clf"
    path.write_bytes(data.draw(_mutated_bytes(bi.carmen_text(bi.carmen_lines()[:8]))))
    _check_log(path)


@given(st.data())
def test_relations_mutations_raise_only_input_error(tmp_path_factory, data) -> None:
    path = tmp_path_factory.mktemp("rel") / "log.relations"
    path.write_bytes(data.draw(_mutated_bytes(bi.relations_text())))
    try:
        relations = read_relations(path)
    except InputError:
        return
    table = np.column_stack([relations.t1, relations.t2, relations.motion])
    assert np.isfinite(table).all() and (np.abs(relations.motion) <= COORDINATE_LIMIT_M).all()


@given(frame_sequences(max_frames=6), st.randoms(use_true_random=False), st.integers(0, 3))
def test_time_order_rule_restores_a_shuffled_log(frames, random, repeats) -> None:
    """Shuffled frames with repeated ones come back as the original log, repeats dropped."""
    shuffled = frames + [frames[random.randrange(len(frames))] for _ in range(repeats)]
    random.shuffle(shuffled)
    ordered, anomalies = ordered_frames(shuffled)
    assert anomalies.duplicate_timestamps == repeats
    assert anomalies.frames_read == len(frames) + repeats == anomalies.frames_kept + repeats
    assert [f.index for f in ordered] == list(range(len(frames)))
    for got, want in zip(ordered, frames, strict=True):
        assert got.timestamp == want.timestamp and got.scan is want.scan
        assert got.odom_pose == want.odom_pose
        assert np.allclose(got.odom_increment.as_array(), want.odom_increment.as_array())
    invalid = np.concatenate([f.scan.ranges for f in shuffled])
    assert anomalies.non_finite_ranges == int((~np.isfinite(invalid)).sum())


# ------------------------------------------------------------------ the gzip layer


def _gzip_members(text: str, level: int, split: int) -> bytes:
    """``text`` gzipped, cut into ``split`` members (readers must read every member)."""
    data = text.encode()
    step = max(1, len(data) // split)
    return b"".join(
        gzip.compress(data[k : k + step], compresslevel=level, mtime=0)
        for k in range(0, len(data), step)
    )


@st.composite
def _mutated_gzip(draw: st.DrawFn) -> bytes:
    text = bi.carmen_text(bi.carmen_lines()[:8])
    data = _gzip_members(text, draw(st.integers(1, 9)), draw(st.integers(1, 4)))
    # keep the magic bytes: it stays a "gzip" file; trailing garbage or a stray member
    tails = [b"\x1f\x8b", b"\x00" * 8, gzip.compress(b"\n")]
    return draw(corrupted(data, edits=(0, 6), keep=2, tails=tails))


@given(_mutated_gzip())
def test_gzip_mutations_raise_only_input_error(tmp_path_factory, data: bytes) -> None:
    """Flipped bits, cut or spliced members, trailing garbage: every corrupt gzip stream is
    an ``InputError`` (never ``zlib.error``, ``EOFError``, ``BadGzipFile``), and whatever
    reads must also read the same as the plain text would."""
    folder = tmp_path_factory.mktemp("gz")
    path = folder / "log.clf.gz"
    path.write_bytes(data)
    _check_log(path)
    try:
        text = gzip.decompress(data)
    except (OSError, EOFError, zlib.error):
        return  # the reader must have refused it (checked above: only InputError)
    plain = folder / "log.clf"
    plain.write_bytes(text)
    try:
        from_gzip = [f.timestamp for f in read_frames(path)]
    except InputError:
        return
    assert from_gzip == [f.timestamp for f in read_frames(plain)]


# ------------------------------------------------------------------ campaign files

_CAMPAIGN_PARAMS = {
    "episodes": 3, "seed": 0, "kinds": ["corridors"], "profile": "dataset3", "noise": "typical",
    "laser_noise": "sick_lms200", "mapper": "albot1", "tour_kind": "loop",
    "world_size_min_m": 12.0, "world_size_max_m": 14.0, "tour_length_min_m": 8.0,
    "tour_length_max_m": 12.0,
}  # fmt: skip


@st.composite
def _mutated_records(draw: st.DrawFn) -> bytes:
    statuses = st.sampled_from(["ok", "violation", "crash"])
    records: list[Any] = [
        bi.episode_record(k, status=draw(statuses)) for k in range(draw(st.integers(1, 3)))
    ]
    for _ in range(draw(st.integers(0, 3))):
        k = draw(st.integers(0, len(records) - 1))
        path = draw(st.sampled_from(_paths(records[k])))
        records[k] = _replace_at(records[k], path, draw(_JSON_VALUES))
    lines = [json.dumps(r).encode() for r in records]
    if draw(st.booleans()):
        k = draw(st.integers(0, len(lines) - 1))
        lines[k] = draw(_mutated_bytes(lines[k].decode()))
    return b"\n".join(lines) + draw(st.sampled_from([b"\n", b"", b"\n\x00\x00", b"\n{"]))


@given(_mutated_records())
def test_episode_record_mutations_raise_only_input_error(tmp_path_factory, data: bytes) -> None:
    """Any damage to episodes.jsonl is an ``InputError`` naming a line, or the records read
    are whole: the summary is computed from them without error and agrees with itself."""
    from albot2d.evaluation.fuzz.campaign import read_episodes
    from albot2d.evaluation.fuzz.summary import summarise

    path = tmp_path_factory.mktemp("c") / "episodes.jsonl"
    path.write_bytes(data)
    try:
        records, _ = read_episodes(path)
    except InputError:
        return
    summary = summarise(list(records.values()), {}, ran=0, wall_time_s=0.0, workers=1)
    assert summary["ok"] + summary["violations"] + summary["crashes"] == summary["episodes"]
    assert all(records[k].metrics is not None for k in records if records[k].status == "ok")


@given(st.data())
def test_campaign_file_mutations_raise_only_input_error(tmp_path_factory, data) -> None:
    from albot2d.evaluation.fuzz.campaign import CampaignParams, read_campaign

    doc = {
        "format": "albot2d-campaign",
        "format_version": 1,
        "params": copy.deepcopy(_CAMPAIGN_PARAMS),
    }
    for _ in range(data.draw(st.integers(1, 3))):
        path = data.draw(st.sampled_from(_paths(doc)))
        doc = _replace_at(doc, path, data.draw(_JSON_VALUES))
    text = json.dumps(doc)
    if data.draw(st.booleans()):
        text = data.draw(_mutated_bytes(text)).decode("utf-8", errors="replace")
    folder = tmp_path_factory.mktemp("c")
    (folder / "campaign.json").write_text(text)
    try:
        params = read_campaign(folder)
    except InputError:
        return
    assert isinstance(params, CampaignParams) and params.episodes >= 1
