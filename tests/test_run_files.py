"""Simulated run directories: write → read gives the same frames; failures leave no files."""

from __future__ import annotations

import dataclasses
import json
import math

import numpy as np
import pytest
from hypothesis import given

from albot2d.errors import InputError
from albot2d.frames import Frame, Scan, beam_angles
from albot2d.geometry import Pose
from albot2d.logs import (
    EXACT,
    LOG_PRECISION,
    RelationsOptions,
    match_timestamps,
    read_carmen,
    read_run,
    read_truth,
    write_run,
    write_truth,
)
from albot2d.logs.carmen import LaserRecord
from tests.log_strategies import frame_sequences
from tests.test_carmen import _assert_same_frames

RUN_FILES = {"log.clf", "truth.txt", "log.relations", "run.json"}


@pytest.mark.parametrize("fmt", [LOG_PRECISION, EXACT], ids=["log_precision", "exact"])
@given(frames=frame_sequences(max_frames=5))
def test_read_run_of_write_run_gives_the_same_frames(tmp_path_factory, fmt, frames):
    out = tmp_path_factory.mktemp("run") / "run"
    params = {"seed": 3, "laser": {"noise_m": np.float64(0.01)}, "size": (4, 5)}
    manifest = write_run(out, frames, params=params, float_format=fmt)
    assert {p.name for p in out.iterdir()} == RUN_FILES
    run = read_run(out)
    read_frames = list(run.frames)
    _assert_same_frames([dataclasses.replace(f, true_pose=None) for f in read_frames], frames, fmt)
    for got, want in zip(read_frames, frames, strict=True):
        assert got.true_pose == want.true_pose  # truth is written exactly in either format
        assert got.collided == want.collided
    assert run.params == {"seed": 3, "laser": {"noise_m": 0.01}, "size": [4, 5]}
    assert run.manifest == manifest == json.loads((out / "run.json").read_text())
    assert manifest["counts"] == {
        "frames": len(frames),
        "relations": len(run.relations),
        "collided_frames": sum(f.collided for f in frames),
    }
    # Relation stamps are the log's ipc_timestamps exactly, and the relations are the truth's.
    stamps = np.array([f.timestamp for f in read_frames])
    i = match_timestamps(run.relations.t1, stamps, tolerance_s=0.0)
    j = match_timestamps(run.relations.t2, stamps, tolerance_s=0.0)
    for a, b, motion in zip(i, j, run.relations.motion, strict=True):
        expected = read_frames[a].true_pose.between(read_frames[b].true_pose)
        np.testing.assert_allclose(motion, expected.as_array(), atol=1e-9)


def _frames_on_a_loop(count: int = 40) -> list[Frame]:
    """A robot circling (radius 2 m, 20 s per lap) with slightly drifting odometry."""
    angles = beam_angles(181)
    ranges = np.linspace(0.5, 40.0, 181)
    scan = Scan(ranges, angles, ranges < 30.0, 30.0, laser_pose=Pose(0.1, 0.0, 0.0))
    frames = []
    for k in range(count):
        angle = 2 * math.pi * k / 20
        truth = Pose(2 * math.cos(angle), 2 * math.sin(angle), angle + math.pi / 2)
        odom = Pose(truth.x * 1.01, truth.y, truth.theta)
        frames.append(Frame(k, 100.0 + k, scan, odom, Pose(), truth, k == 7))
    return frames


def test_run_layout_truth_and_loop_relations(tmp_path):
    frames = _frames_on_a_loop()
    # Neighbouring poses are 0.63 m apart: a 0.5 m radius accepts only exact revisits.
    options = RelationsOptions(
        long_range_every=5, long_range_min_gap_s=15.0, long_range_max_distance_m=0.5
    )
    manifest = write_run(tmp_path / "r", frames, params={}, relations_options=options)
    lines = (tmp_path / "r" / "truth.txt").read_text().splitlines()
    assert lines[0].startswith("#") and len([ln for ln in lines if ln[0] != "#"]) == 40
    t, poses = read_truth(tmp_path / "r" / "truth.txt")
    assert t.tolist() == [100.0 + k for k in range(40)]
    assert poses[3].tolist() == list(dataclasses.astuple(frames[3].true_pose))
    records = list(read_carmen(tmp_path / "r" / "log.clf"))
    lasers = [r for r in records if isinstance(r, LaserRecord)]
    assert [r.ipc_timestamp for r in lasers] == t.tolist()
    assert manifest["collided_indices"] == [7]
    assert manifest["relations_options"]["long_range_every"] == 5
    run = read_run(tmp_path / "r")
    long_range = run.relations.t2 - run.relations.t1 >= 15.0
    # Anchors 0, 5, ..., 15 come back to the same place 20 s later; 20+ have no later lap.
    assert list(zip(run.relations.t1[long_range], run.relations.t2[long_range], strict=True)) == [
        (100.0 + a, 120.0 + a) for a in (0, 5, 10, 15)
    ]
    np.testing.assert_allclose(run.relations.motion[long_range], 0.0, atol=1e-9)
    assert [f.index for f in run.frames if f.collided] == [7]


def test_failed_run_leaves_no_files(tmp_path):
    frames = _frames_on_a_loop(5)
    frames[3] = dataclasses.replace(frames[3], true_pose=None)
    with pytest.raises(InputError, match="frame 3 has no true_pose"):
        write_run(tmp_path / "new", frames, params={})
    assert not (tmp_path / "new").exists()
    existing = tmp_path / "existing"
    existing.mkdir()
    with pytest.raises(InputError, match="cannot store a object"):
        write_run(existing, _frames_on_a_loop(5), params={"bad": object()})
    assert list(existing.iterdir()) == []
    with pytest.raises(InputError, match="increase strictly"):
        write_run(existing, [*frames[:2], frames[1]], params={})
    assert list(existing.iterdir()) == []


def test_read_run_rejects_inconsistent_directories(tmp_path):
    out = tmp_path / "run"
    write_run(out, _frames_on_a_loop(6), params={})
    t, poses = read_truth(out / "truth.txt")
    write_truth(out / "truth.txt", t[:-1], poses[:-1])
    with pytest.raises(InputError, match="5 poses for 6 scans"):
        read_run(out)
    write_truth(out / "truth.txt", t + 1.0, poses)
    with pytest.raises(InputError, match=r"pose 0 has timestamp 101\.0"):
        read_run(out)
    (out / "truth.txt").write_text("1 2 3\n")
    with pytest.raises(InputError, match=r"truth\.txt:1: truth line has 3 fields"):
        read_run(out)
    (out / "run.json").write_text('{"format": "something else"}')
    with pytest.raises(InputError, match="not an albot2d run manifest"):
        read_run(out)
    (out / "run.json").write_text("{")
    with pytest.raises(InputError, match=r"run\.json: not valid JSON"):
        read_run(out)
