"""Campaign folders: damaged episode streams, what --resume refuses, and the folder lock."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from albot2d.errors import InputError
from albot2d.evaluation.fuzz import lock as campaign_lock
from albot2d.evaluation.fuzz.campaign import (
    CAMPAIGN_NAME,
    EPISODES_NAME,
    CampaignParams,
    read_episodes,
    run_campaign,
)
from albot2d.evaluation.fuzz.lock import LOCK_NAME, CampaignLock
from tests import bad_inputs as bi
from tests.campaign_helpers import SMALL


def record_line(index: int, seed: int = 0, status: str = "ok") -> bytes:
    return json.dumps(bi.episode_record(index, seed=seed, status=status)).encode() + b"\n"


def test_a_damaged_line_inside_the_file_is_an_error(tmp_path: Path) -> None:
    path = tmp_path / EPISODES_NAME
    path.write_bytes(record_line(0) + b"not json\n" + record_line(2))
    with pytest.raises(InputError, match=f"{EPISODES_NAME}:2: not an episode record"):
        read_episodes(path)


def test_a_damaged_tail_is_left_out_to_be_redone(tmp_path: Path) -> None:
    path = tmp_path / EPISODES_NAME
    whole = record_line(0) + record_line(1, status="crash")
    for tail in (b'{"episode": 2, "sta', b"\x00" * 300, b"\x00" * 50 + b"\n" + b"\x00" * 9):
        path.write_bytes(whole + tail)
        records, keep = read_episodes(path)
        assert keep == len(whole)
        assert {k: r.to_json() for k, r in records.items()} == {
            0: bi.episode_record(0),
            1: bi.episode_record(1, status="crash"),
        }


def write_campaign(folder: Path, params: CampaignParams, episodes: bytes = b"") -> None:
    doc = {"format": "albot2d-campaign", "format_version": 1, "params": params.to_dict()}
    (folder / CAMPAIGN_NAME).write_text(json.dumps(doc))
    (folder / EPISODES_NAME).write_bytes(episodes)


def folder_state(folder: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir())}


def test_resume_refuses_a_folder_without_a_campaign(tmp_path: Path) -> None:
    (tmp_path / "notes.txt").write_text("mine")
    with pytest.raises(InputError, match=r"--resume: .* holds no campaign"):
        run_campaign(CampaignParams(episodes=1, **SMALL), tmp_path, resume=True)
    assert folder_state(tmp_path) == {"notes.txt": b"mine"}


@pytest.mark.parametrize(
    ("content", "message"),
    [
        (b"not json", "not a campaign file written by albot2d"),
        (b"[1, 2]", "format is not 'albot2d-campaign'"),
        (b'{"format": "albot2d-report", "format_version": 1}', "format is not 'albot2d-campaign'"),
        (b'{"format": "albot2d-campaign", "format_version": 7, "params": {}}', "format_version 7"),
        (b'{"format": "albot2d-campaign", "format_version": 1}', "no params"),
        (
            b'{"format": "albot2d-campaign", "format_version": 1, '
            b'"params": {"episodes": 1, "hue": 2}}',
            "unknown campaign parameter",
        ),
        (
            b'{"format": "albot2d-campaign", "format_version": 1, "params": {"episodes": 1, '
            b'"kinds": ["caves"]}}',
            "campaign.json: unknown world kind 'caves'",
        ),
    ],
)
def test_resume_refuses_a_damaged_campaign_file(
    tmp_path: Path, content: bytes, message: str
) -> None:
    (tmp_path / CAMPAIGN_NAME).write_bytes(content)
    before = folder_state(tmp_path)
    with pytest.raises(InputError, match=message):
        run_campaign(CampaignParams(episodes=1, **SMALL), tmp_path, resume=True)
    assert folder_state(tmp_path) == before


@pytest.mark.parametrize(
    ("episodes", "message"),
    [
        (record_line(0) + b"junk\n" + record_line(1), f"{EPISODES_NAME}:2: not an episode record"),
        (record_line(0) + b'{"episode": 1}\n', f"{EPISODES_NAME}:2: not an episode record"),
        (record_line(0) + b'{"episode": -1, "status": "ok"}\n', ":2: not an episode record"),
        (record_line(0) + record_line(1) + record_line(0), ":3: episode 0 again .first on line 1"),
        (record_line(0) + record_line(1, seed=5), ":2: episode 1 was not drawn from this campaign"),
    ],
)
def test_resume_refuses_episodes_that_are_not_this_campaigns(
    tmp_path: Path, episodes: bytes, message: str
) -> None:
    params = CampaignParams(episodes=3, **SMALL)
    write_campaign(tmp_path, params, episodes)
    before = folder_state(tmp_path)
    with pytest.raises(InputError, match=message):
        run_campaign(params, tmp_path, resume=True)
    assert folder_state(tmp_path) == before


def test_a_new_campaign_refuses_a_folder_that_holds_one(tmp_path: Path) -> None:
    params = CampaignParams(episodes=1, **SMALL)
    write_campaign(tmp_path, params)
    with pytest.raises(InputError, match=f"already holds a campaign .{CAMPAIGN_NAME}"):
        run_campaign(params, tmp_path)


def test_a_locked_folder_is_refused_and_a_stale_lock_taken_over(tmp_path: Path) -> None:
    params = CampaignParams(episodes=1, **SMALL)
    write_campaign(tmp_path, params)
    with CampaignLock(tmp_path):
        assert (tmp_path / LOCK_NAME).read_text() == f"{os.getpid()}\n"
        with pytest.raises(InputError, match=f"in use by another campaign .pid {os.getpid()}"):
            run_campaign(params, tmp_path, resume=True)
    assert not (tmp_path / LOCK_NAME).exists()
    # A lock left by a campaign that was killed: its pid runs no more, no one holds it.
    (tmp_path / LOCK_NAME).write_text(f"{dead_pid()}\n")
    with CampaignLock(tmp_path):
        assert (tmp_path / LOCK_NAME).read_text() == f"{os.getpid()}\n"


def dead_pid() -> int:
    """The pid of a process that has ended."""
    done = subprocess.run(
        [sys.executable, "-c", "import os; print(os.getpid())"],
        capture_output=True,
        text=True,
        check=True,
    )
    return int(done.stdout)


def test_without_fcntl_the_lock_is_a_pid_file(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Where there is no fcntl (Windows): O_EXCL creation, a dead pid's file is stale."""
    monkeypatch.setattr(campaign_lock, "fcntl", None)
    (tmp_path / LOCK_NAME).write_text(f"{dead_pid()}\n")
    with CampaignLock(tmp_path):
        assert (tmp_path / LOCK_NAME).read_text() == f"{os.getpid()}\n"
        with pytest.raises(InputError, match=f"in use by another campaign .pid {os.getpid()}"):
            CampaignLock(tmp_path).acquire()
    assert not (tmp_path / LOCK_NAME).exists()
