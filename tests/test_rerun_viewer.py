"""Rerun recordings of a run and a replay, opened with rerun's own reader; the live
viewer path connects to a running gRPC server and never starts a viewer."""

from __future__ import annotations

import json
import socket
from pathlib import Path

import numpy as np
import pytest

from albot2d.cli import main

rr = pytest.importorskip("rerun", reason="the [rerun] extra (rerun-sdk) is not installed")
RrdReader = pytest.importorskip("rerun.chunk", reason="rerun-sdk without rerun.chunk").RrdReader


def entity_rows(path: Path) -> dict[str, list]:
    """Each entity path of a recording → its chunks as pyarrow record batches."""
    out: dict[str, list] = {}
    for chunk in RrdReader(path).stream():
        out.setdefault(chunk.entity_path, []).append(chunk.to_record_batch())
    return out


def rows(batches: list) -> int:
    return sum(b.num_rows for b in batches)


def column(batches: list, name: str) -> list:
    values: list = []
    for b in batches:
        if name in b.schema.names:
            values += b.column(name).to_pylist()
    return values


@pytest.fixture(autouse=True)
def no_viewer_spawned(monkeypatch: pytest.MonkeyPatch) -> None:
    """A test never starts a GUI: spawning one fails the test."""

    def refuse(*args: object, **kwargs: object) -> None:
        raise AssertionError("a test tried to spawn a Rerun viewer")

    monkeypatch.setattr(rr, "spawn", refuse)


def test_run_recording_has_every_entity_and_one_scan_per_view(tmp_path: Path) -> None:
    out, rrd = tmp_path / "run", tmp_path / "run.rrd"
    assert main(["run", "--out", str(out), "--max-frames", "40", "--no-figures",
                 "--mapper", "albot1", "naive", "--rerun-save", str(rrd)]) == 0  # fmt: skip
    report = json.loads((out / "report.json").read_text())
    frames = report["run"]["frames"]
    entities = entity_rows(rrd)
    expected = {"/world/walls", "/world/tour", "/world/robot", "/world/true_path", "/scan",
                "/mappers/albot1/pose", "/mappers/albot1/path", "/mappers/albot1/map",
                "/mappers/albot1/view", "/mappers/albot1/tracked", "/mappers/albot1/route",
                "/mappers/albot1/route/views", "/mappers/naive/pose", "/mappers/naive/path",
                "/mappers/naive/map"}  # fmt: skip
    assert expected <= set(entities), expected - set(entities)
    assert rows(entities["/scan"]) == frames == 40
    assert sorted(column(entities["/scan"], "view")) == list(range(frames))
    assert rows(entities["/mappers/albot1/view"]) == rows(entities["/world/robot"]) == frames
    # the route map as it ends holds every local map Albot1 remembered
    local_maps = report["mappers"]["albot1"]["counts"]["local_maps"]
    views = entities["/mappers/albot1/route/views"]
    last = max(zip(column(views, "view"), column(views, "Points2D:positions"),
                   strict=True))[1]  # fmt: skip
    assert len(last) == local_maps
    # the walls are the world's, in the world frame
    from worldgen.generate import generate

    walls = np.array(column(entities["/world/walls"], "LineStrips2D:strips")[0])
    assert np.allclose(walls.reshape(-1, 4), generate("office", seed=0).obstacle_segments,
                       atol=1e-5)  # fmt: skip
    # a scan's hits lie on the walls (laser noise aside)
    import shapely

    hits = np.array(column(entities["/scan"], "Points2D:positions")[0])
    lines = shapely.linestrings(walls.reshape(-1, 2, 2).astype(np.float64))
    _, d = shapely.STRtree(lines).query_nearest(shapely.points(hits), return_distance=True)
    assert np.median(d) < 0.05


def test_replay_recording_and_a_failed_run_leaves_no_file(tmp_path: Path) -> None:
    sim = tmp_path / "sim"
    assert main(["simulate", "--out", str(sim), "--max-frames", "30", "--no-png"]) == 0
    rrd = tmp_path / "replay.rrd"
    assert main(["replay", str(sim / "log.clf"), "--out", str(tmp_path / "rep"),
                 "--no-figures", "--rerun-save", str(rrd)]) == 0  # fmt: skip
    entities = entity_rows(rrd)
    assert rows(entities["/scan"]) == 30
    assert "/world/walls" not in entities  # a log has no world
    assert {"/mappers/albot1/view", "/mappers/naive/map"} <= set(entities)
    # a run that fails leaves neither report nor recording
    bad, broken = tmp_path / "bad.rrd", tmp_path / "broken.clf"
    broken.write_text((sim / "log.clf").read_text() + "FLASER 3 1.0 1.0\n")
    assert main(["replay", str(broken), "--out", str(tmp_path / "rep2"),
                 "--rerun-save", str(bad)]) == 2  # fmt: skip
    assert not (tmp_path / "rep2").exists()
    assert not bad.exists() and not list(tmp_path.glob(".bad.rrd.*"))
    assert main(["run", "--out", str(tmp_path / "r3"), "--rerun-save",
                 str(tmp_path / "nowhere" / "x.rrd")]) == 2  # fmt: skip


def test_live_viewer_is_the_running_one(tmp_path: Path) -> None:
    """``--rerun`` connects to a viewer's gRPC server when one listens (here a real
    headless server, rerun's own), and does not start one."""
    from albot2d.viz.rerun_log import viewer_listening

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    url = f"rerun+http://127.0.0.1:{port}/proxy"
    assert not viewer_listening(url)
    server = rr.RecordingStream("albot2d-test-server")
    served = server.serve_grpc(grpc_port=port)
    try:
        assert viewer_listening(url)
        assert str(port) in served
        assert main(["run", "--out", str(tmp_path / "live"), "--max-frames", "5",
                     "--no-figures", "--mapper", "naive", "--rerun-url", url]) == 0  # fmt: skip
    finally:
        server.disconnect()
