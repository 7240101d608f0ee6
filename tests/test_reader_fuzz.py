"""Property-based fuzzing of the readers: mutated world files, CARMEN logs and relations
files either read or raise ``InputError``, never anything else.

Hypothesis mutates valid inputs (``tests/bad_inputs.py``) byte by byte and field by field,
with the values that break readers (NaN, infinities, 1e308, huge integers, deep nesting,
wrong types). A world that is accepted must also build its raycast grid and pymunk space;
a log that is accepted must also go through the time-order rule. The ``ci`` profile tries
25 inputs per test; ``HYPOTHESIS_PROFILE=fuzz python -m pytest tests/test_reader_fuzz.py``
tries 5000.
"""

from __future__ import annotations

import json
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
    data = bytearray(text.encode())
    for _ in range(draw(st.integers(1, 8))):
        at = draw(st.integers(0, len(data)))
        op = draw(st.sampled_from(["replace", "insert", "delete", "truncate"]))
        chunk = draw(st.binary(min_size=1, max_size=4) | _TOKENS.map(str.encode))
        if op == "replace":
            data[at : at + len(chunk)] = chunk
        elif op == "insert":
            data[at:at] = chunk
        elif op == "delete":
            del data[at : at + len(chunk)]
        else:
            del data[at:]
    return bytes(data)


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
