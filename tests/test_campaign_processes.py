"""Campaigns as real processes: ``kill -9`` at random moments then ``--resume``, pool workers
that must not outlive the campaign, Ctrl-C once and twice, two campaigns on one folder.

Every campaign here is an ``albot2d fuzz`` subprocess with two pool workers on tiny
corridor worlds (``dataset3``: a view per metre; ``tests/fuzz_processes.py`` starts
them), so an episode takes a fraction of a second and each test a few seconds. The random
kill moments come from a seeded generator whose seed a failure prints;
``ALBOT2D_KILL_SEED=SEED`` replays that sequence.
"""

from __future__ import annotations

import contextlib
import os
import random
import signal
import subprocess
import time
from pathlib import Path

import pytest

from albot2d.errors import InputError
from albot2d.evaluation.fuzz.campaign import (
    CAMPAIGN_NAME,
    EPISODES_NAME,
    CampaignParams,
    read_episodes,
    run_campaign,
)
from albot2d.evaluation.fuzz.lock import LOCK_NAME
from tests.fuzz_processes import (  # noqa: F401  (the fixture is used by name)
    EPISODES,
    MARKER,
    _no_campaign_left_running,
    assert_whole_lines,
    output,
    start_fuzz,
    wait_for,
    wait_for_first_episode,
)

psutil = pytest.importorskip("psutil")

TINY = {
    "kinds": ("corridors",),
    "world_size_min_m": 12.0,
    "world_size_max_m": 14.0,
    "tour_length_min_m": 8.0,
    "tour_length_max_m": 12.0,
}
# How long the workers of a killed campaign may live on (they poll every 0.25 s).
ORPHAN_GRACE_S = 5.0
# How long a campaign may take to stop after a second Ctrl-C.
SECOND_INTERRUPT_GRACE_S = 10.0


def family_of(out: Path) -> list:  # type: ignore[type-arg]
    """Every running process of the campaigns started on ``out`` (by their environment)."""
    found = []
    for p in psutil.process_iter():
        try:
            if p.pid != os.getpid() and p.environ().get(MARKER) == str(out):
                found.append(p)
        except psutil.Error:  # gone, or not ours to read
            pass
    return found


def descendants(pid: int) -> list:  # type: ignore[type-arg]
    try:
        return psutil.Process(pid).children(recursive=True)
    except psutil.NoSuchProcess:
        return []


def alive(processes: list) -> list:  # type: ignore[type-arg]
    """Those still running (a zombie waiting for init to reap it has exited)."""
    out = []
    for p in processes:
        try:
            if p.status() != psutil.STATUS_ZOMBIE:
                out.append(p)
        except psutil.NoSuchProcess:
            pass
    return out


def episodes_written(out: Path) -> int:
    path = out / EPISODES_NAME
    return len(read_episodes(path)[0]) if path.exists() else 0


def comparable(records: list[dict]) -> list[dict]:
    return [
        {k: v for k, v in r.items() if k != "timings"}
        for r in sorted(records, key=lambda r: r["episode"])
    ]


@pytest.fixture(scope="module")
def reference(tmp_path_factory: pytest.TempPathFactory) -> list[dict]:
    """The same campaign uninterrupted, in this process."""
    out = tmp_path_factory.mktemp("uninterrupted")
    run_campaign(CampaignParams(episodes=EPISODES, seed=21, **TINY), out)
    return assert_whole_lines(out / EPISODES_NAME)


@pytest.mark.slow  # several campaigns in subprocesses, killed and resumed
def test_kill_9_at_random_moments_then_resume_gives_the_uninterrupted_campaign(
    reference: list[dict],
    tmp_path: Path,
) -> None:
    seed = int(os.environ.get("ALBOT2D_KILL_SEED") or int.from_bytes(os.urandom(4), "little"))
    rng = random.Random(seed)
    out = tmp_path / "fuzz"
    kills = []
    for attempt in range(2):
        resume = ("--resume",) if (out / CAMPAIGN_NAME).exists() else ()
        proc = start_fuzz(out, *resume)
        wait_for(
            lambda p=proc: (out / LOCK_NAME).exists() or p.poll() is not None,
            60,
            "the campaign to start",
        )
        if attempt == 0:
            # While it runs, no second campaign may write the folder.
            with pytest.raises(InputError, match=f"in use by another campaign \\(pid {proc.pid}"):
                run_campaign(CampaignParams(episodes=EPISODES, seed=21, **TINY), out, resume=True)
        # A random moment of the campaign, whatever the speed of the machine: once a random
        # number of episodes are written (none, for the first kill, in a third of the
        # runs: while the workers start), then a random fraction of a second.
        done = episodes_written(out)
        if done >= EPISODES:  # a fast machine: every episode is written already
            wanted = done
        else:
            wanted = rng.randrange(done, EPISODES) if attempt or rng.random() > 1 / 3 else 0
        wait_for(
            lambda p=proc, n=wanted: episodes_written(out) >= n or p.poll() is not None,
            120,
            f"{wanted} episodes",
        )
        delay = rng.uniform(0.0, 0.5)
        time.sleep(delay)
        if proc.poll() is not None:  # finished before the kill
            break
        proc.send_signal(signal.SIGKILL)
        proc.wait(timeout=30)
        family = family_of(out)  # all that is left of it
        kills.append((wanted, round(delay, 2), len(family), episodes_written(out)))
        # Its pool workers (and the pool's resource tracker) notice and exit.
        with contextlib.suppress(psutil.Error):
            psutil.wait_procs(family, timeout=ORPHAN_GRACE_S)
        left = alive(family_of(out))
        for p in left:  # do not leave them to the rest of the suite
            p.kill()
        assert not left, (
            f"alive {ORPHAN_GRACE_S} s after kill -9 of their parent: "
            f"{[p.pid for p in left]} (rng seed {seed}, kills {kills})"
        )
    # Killed before it had written anything, it is started afresh.
    proc = start_fuzz(out, *(("--resume",) if (out / CAMPAIGN_NAME).exists() else ()))
    stdout, stderr = output(proc, 120)
    assert proc.returncode == 0, (stderr, seed, kills)
    records = assert_whole_lines(out / EPISODES_NAME)
    assert sorted(r["episode"] for r in records) == list(range(EPISODES)), (seed, kills)
    assert comparable(records) == comparable(reference), (seed, kills)
    assert f"{EPISODES} episodes: {EPISODES} ok" in stdout
    assert not (out / LOCK_NAME).exists()


def test_a_second_ctrl_c_stops_the_campaign_within_seconds(tmp_path: Path) -> None:
    out = tmp_path / "fuzz"
    # Larger worlds than the others, so that episodes are still running at the second Ctrl-C.
    proc = start_fuzz(out, "--world-size", "30", "30", "--tour-length", "80", "80", episodes=8)
    wait_for(
        lambda: (out / CAMPAIGN_NAME).exists() or proc.poll() is not None,
        60,
        "the campaign to start",
    )
    wait_for(
        lambda: len(descendants(proc.pid)) >= 3 or proc.poll() is not None,
        60,
        "the pool workers to start",
    )
    time.sleep(0.5)
    family = descendants(proc.pid)
    proc.send_signal(signal.SIGINT)
    time.sleep(0.3)
    proc.send_signal(signal.SIGINT)
    t0 = time.monotonic()
    try:
        _, stderr = output(proc, SECOND_INTERRUPT_GRACE_S)
    except subprocess.TimeoutExpired:
        proc.kill()
        for p in alive(family):
            p.kill()
        raise AssertionError("still running 10 s after the second Ctrl-C") from None
    stopped_s = time.monotonic() - t0
    assert proc.returncode == 130, stderr
    assert "Traceback" not in stderr, stderr
    assert "continue with the same options and --resume" in stderr
    with contextlib.suppress(psutil.Error):
        psutil.wait_procs(family, timeout=ORPHAN_GRACE_S)
    left = alive(family_of(out))
    for p in left:
        p.kill()
    assert not left, "workers alive after the campaign ended"
    records = assert_whole_lines(out / EPISODES_NAME)
    assert len({r["episode"] for r in records}) == len(records)
    assert stopped_s < SECOND_INTERRUPT_GRACE_S


@pytest.mark.slow  # waits for real episodes to finish after the interrupt
def test_a_first_ctrl_c_lets_the_running_episodes_finish(tmp_path: Path) -> None:
    out = tmp_path / "fuzz"
    proc = start_fuzz(out, episodes=20)
    wait_for_first_episode(proc, out, 60)
    proc.send_signal(signal.SIGINT)
    _, stderr = output(proc, 60)
    assert proc.returncode == 130, stderr
    assert "finishing the running episodes" in stderr and "Traceback" not in stderr
    records = assert_whole_lines(out / EPISODES_NAME)
    assert 1 <= len(records) < 20
    assert f"interrupted: {len(records)} of 20 episodes" in stderr
