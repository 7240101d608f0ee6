"""Fuzzing campaigns: episode seeding, determinism across workers and backends (local pool,
dask), the jsonl stream and --resume, reproducers, crashes and dead workers, user plugins."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

from albot2d.cli import main
from albot2d.errors import InputError
from albot2d.evaluation.fuzz.backends import DaskBackend, LocalBackend
from albot2d.evaluation.fuzz.campaign import (
    EPISODES_NAME,
    CampaignParams,
    read_episodes,
    reproducer_path,
    run_campaign,
)
from albot2d.evaluation.fuzz.episode import EpisodeSpec, episode_seed, run_episode
from albot2d.evaluation.fuzz.record import CheckMetrics, CheckOutcome, EpisodeRecord
from albot2d.evaluation.fuzz.reproducer import replay_reproducer
from albot2d.evaluation.fuzz.summary import COMPARED_METRICS, format_summary, summarise
from tests.campaign_helpers import SMALL
from worldgen.generate import generate
from worldgen.kinds import get_kind

ROOT = Path(__file__).resolve().parents[1]

PLUGINS = '''
import os

import numpy as np

from albot2d.geometry import Pose
from albot2d.mapping import MapperCounts, MapSnapshot
from albot2d.mapping.baselines import NaiveIntegration
from albot2d.mapping.albot1.route_map import RouteMap


class Tiny:
    """A user's mapper from scratch: dead reckoning, no map."""

    name = "tiny"

    def __init__(self):
        self.poses = []

    def observe(self, frame):
        last = Pose.from_array(self.poses[-1]) if self.poses else Pose()
        self.poses.append((last @ frame.odom_increment).as_array())

    def pose(self):
        return Pose.from_array(self.poses[-1]) if self.poses else Pose()

    def global_map(self, at_update=None):
        return MapSnapshot(np.zeros((0, 4)), np.zeros(0, dtype=np.int64))

    def trajectory(self):
        return np.array(self.poses).reshape(-1, 3)

    def counts(self):
        return MapperCounts(len(self.poses), 0, 0, 0)

    def timings_ms(self):
        return {}


class BrokenRoute(NaiveIntegration):
    """View-based (the ViewBasedMapper protocol), but its second local map has no pose in
    the first."""

    def __init__(self):
        super().__init__()
        self.route = RouteMap()
        self.update_log = []

    def route_map(self):
        return self.route

    def observe(self, frame):
        super().observe(frame)
        if len(self.route) < 2:
            self.route.append(frame.index, None, self.pose(), "start")


class Crashing(Tiny):
    def observe(self, frame):
        if frame.index == 3:
            raise RuntimeError("plugin bug at frame 3")
        super().observe(frame)


class Exact(Tiny):
    """A user's mapper that knows the true pose (it holds every invariant)."""

    def observe(self, frame):
        self.poses.append(frame.true_pose.as_array())


class Dying(Exact):
    """Kills its worker process in the episodes whose start x has an even millimetre."""

    def observe(self, frame):
        if frame.index == 0:
            self.dies = round(frame.true_pose.x * 1000) % 2 == 0
        if frame.index == 2 and self.dies:
            os._exit(3)
        super().observe(frame)
'''


@pytest.fixture(scope="module")
def plugins(tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp("plugins")
    (folder / "fuzz_plugins.py").write_text(textwrap.dedent(PLUGINS))
    sys.path.insert(0, str(folder))  # spawned workers inherit sys.path
    yield folder
    sys.path.remove(str(folder))
    sys.modules.pop("fuzz_plugins", None)


def comparable(records: list[dict]) -> list[dict]:
    """Records without wall-clock timings, in episode order."""
    return [
        {k: v for k, v in r.items() if k != "timings"}
        for r in sorted(records, key=lambda r: r["episode"])
    ]


def jsonl(out: Path) -> list[dict]:
    return [json.loads(line) for line in (out / EPISODES_NAME).read_text().splitlines()]


@pytest.fixture(scope="module")
def reference(tmp_path_factory: pytest.TempPathFactory) -> tuple[CampaignParams, list[dict]]:
    """A 4-episode campaign run in this process (one worker)."""
    params = CampaignParams(episodes=4, seed=11, **SMALL)
    out = tmp_path_factory.mktemp("reference")
    summary = run_campaign(params, out)
    assert summary["episodes"] == 4 and summary["ran"] == 4
    return params, jsonl(out)


# -- seeding ----------------------------------------------------------------------------------
def test_episode_seeds_are_the_campaign_seeds_spawned_children() -> None:
    children = np.random.SeedSequence(42).spawn(6)
    for k, child in enumerate(children):
        mine = episode_seed(42, k)
        assert (mine.entropy, mine.spawn_key) == (child.entropy, child.spawn_key)
        assert np.array_equal(mine.generate_state(4), child.generate_state(4))


def test_an_episode_depends_on_the_seed_and_its_index_only() -> None:
    few = CampaignParams(episodes=3, seed=5)
    many = CampaignParams(episodes=500, seed=5)
    specs = [EpisodeSpec.draw(many, k) for k in range(40)]
    assert EpisodeSpec.draw(few, 2) == specs[2]
    assert len({s.run_seed for s in specs}) == len(specs)
    assert {s.kind for s in specs} == set(many.kinds)
    for s in specs:
        low = max(get_kind(s.kind).params.min_size_m, many.world_size_min_m)
        for size in s.world_params.values():
            assert low <= size <= max(low, many.world_size_max_m)
        assert many.tour_length_min_m <= s.tour_length_m <= many.tour_length_max_m
    assert EpisodeSpec.draw(CampaignParams(episodes=3, seed=6), 2) != specs[2]


def test_identical_seeds_give_identical_episodes() -> None:
    spec = EpisodeSpec.draw(CampaignParams(episodes=1, seed=8, **SMALL), 0)
    a, b = run_episode(spec).record, run_episode(spec).record
    assert comparable([a.to_json()]) == comparable([b.to_json()])
    assert a.digest is not None and a.status == "ok", a.violations
    other = EpisodeSpec.draw(CampaignParams(episodes=2, seed=8, **SMALL), 1)
    assert run_episode(other).record.digest != a.digest


# -- backends ---------------------------------------------------------------------------------
def test_two_local_workers_give_the_same_results(reference, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    params, expected = reference
    backend = LocalBackend(2)
    try:
        run_campaign(params, tmp_path, backend=backend)
    finally:
        backend.close()
    assert comparable(jsonl(tmp_path)) == comparable(expected)
    assert {r["status"] for r in expected} == {"ok"}


def test_a_dask_cluster_gives_the_same_results_bit_for_bit(reference, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    distributed = pytest.importorskip("dask.distributed")
    params, expected = reference
    with distributed.LocalCluster(
        n_workers=2,
        threads_per_worker=1,
        processes=False,
        protocol="tcp://",
        host="127.0.0.1",
        dashboard_address=None,
    ) as cluster:
        backend = DaskBackend(cluster.scheduler_address)
        try:
            assert backend.workers == 2
            run_campaign(params, tmp_path, backend=backend)
        finally:
            backend.close()
    assert comparable(jsonl(tmp_path)) == comparable(expected)


# -- the stream and resume --------------------------------------------------------------------
def test_resume_redoes_only_the_missing_and_the_cut_off_episodes(reference, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    params, expected = reference
    first = CampaignParams(**{**params.to_dict(), "episodes": 3, "kinds": params.kinds})
    run_campaign(first, tmp_path)
    path = tmp_path / EPISODES_NAME
    data = path.read_bytes()
    path.write_bytes(data[: data.rindex(b"\n", 0, len(data) - 1) + 40])  # cut the last line
    assert sorted(read_episodes(path)[0]) == [0, 1]
    with pytest.raises(InputError, match="already holds a campaign"):
        run_campaign(params, tmp_path)
    with pytest.raises(InputError, match=r"other parameters \(seed 11 there, 12 here\)"):
        run_campaign(
            CampaignParams(**{**params.to_dict(), "seed": 12, "kinds": params.kinds}),
            tmp_path,
            resume=True,
        )
    stale = tmp_path / ".summary.json.k1ll3d.tmp"  # an atomic write cut short by kill -9
    stale.write_text("{")
    ran: list[int] = []
    notes: list[str] = []
    summary = run_campaign(
        params,
        tmp_path,
        resume=True,
        on_episode=lambda r: ran.append(r.episode),
        on_note=notes.append,
    )
    assert sorted(ran) == [2, 3]
    assert not stale.exists()
    assert notes == [
        f"{path}: a damaged last line (39 bytes, an interrupted write) is "
        "dropped and its episode redone"
    ]
    assert summary["episodes"] == 4 and summary["ran"] == 2
    assert comparable(jsonl(tmp_path)) == comparable(expected)


# -- the summary ------------------------------------------------------------------------------
def test_ties_are_neither_wins_nor_losses() -> None:
    mine, odo = COMPARED_METRICS["heading_error_mean_deg"]
    pairs = [
        (1.0, 1.0),
        (5.575216133517828, 5.5752161335178005),
        (0.0, 1e-15),
        (0.5, 1.0),
        (2.0, 1.0),
        (1.0, 1.0 + 1e-6),
    ]
    records = [
        EpisodeRecord(
            episode=k, entropy=0, spec=None, status="ok",
            checks=CheckOutcome(metrics=CheckMetrics(a, a, b, b)),
        )
        for k, (a, b) in enumerate(pairs)
    ]  # fmt: skip
    assert (mine, odo) == ("heading_error_mean_deg", "odometry_heading_error_mean_deg")
    summary = summarise(records, {}, ran=6, wall_time_s=1.0, workers=1)
    cmp = summary["mapper_vs_odometry"]["heading_error_mean_deg"]
    assert (cmp["mapper_better"], cmp["mapper_worse"], cmp["ties"]) == (2, 1, 3)
    assert cmp["mapper_better_share"] == pytest.approx(2 / 6)
    assert cmp["tie_share"] == pytest.approx(3 / 6)
    assert "(of 6 episodes mapper better in 2, worse in 1, tied in 3)" in format_summary(summary)


# -- failures: reproducers, crashes, dead workers, plugins -------------------------------------
def test_a_violation_is_saved_as_a_reproducer_that_replays(
    plugins: Path, tmp_path: Path, capsys: pytest.CaptureFixture
) -> None:
    params = CampaignParams(episodes=2, seed=3, mapper="fuzz_plugins:BrokenRoute", **SMALL)
    summary = run_campaign(params, tmp_path / "c")
    assert summary["failures_by_invariant"] == {"route_connected": 2}
    assert summary["checked_by_invariant"]["heading_error_bound"] == 2
    record = jsonl(tmp_path / "c")[0]
    assert record["status"] == "violation"
    assert "no pose in its predecessor" in record["violations"]["route_connected"][0]
    path = reproducer_path(tmp_path / "c", record["episode"])
    doc = json.loads(path.read_text())
    assert doc["reproducer"]["world_json"]["format"] == "albot2d-world"
    assert replay_reproducer(path).record.to_json()["violations"] == record["violations"]
    done = subprocess.run(
        [sys.executable, "-m", "albot2d", "run", "--reproduce", str(path), "--no-figures",
         "--out", str(tmp_path / "again")],
        capture_output=True, text=True,
        env={**os.environ, "PYTHONPATH": os.pathsep.join([str(plugins), str(ROOT)])},
        timeout=120, check=False,
    )  # fmt: skip
    assert done.returncode == 1, done.stderr  # the failure reproduces
    assert "reproduce: run identical to" in done.stdout
    assert "reproduce: route_connected violated: local map 1 (frame 1) has no pose" in done.stdout
    assert "reproduce: the recorded failure reproduces" in done.stdout
    assert (tmp_path / "again" / "report.json").is_file()
    # The same episode with a mapper that keeps its route connected (and its heading
    # within the bound, which raw odometry would not): fixed, exit 0.
    doc["reproducer"]["episode"]["mapper"] = "truth"
    fixed = tmp_path / "fixed.json"
    fixed.write_text(json.dumps(doc))
    assert (
        main(["run", "--reproduce", str(fixed), "--no-figures", "--out", str(tmp_path / "fixed")])
        == 0
    )
    assert "the recorded failure does not reproduce: route_connected violated" in (
        capsys.readouterr().out
    )


def test_a_crashing_mapper_is_recorded_and_the_campaign_goes_on(
    plugins: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture,
) -> None:
    params = CampaignParams(episodes=3, seed=3, mapper="fuzz_plugins:Crashing", **SMALL)
    summary = run_campaign(params, tmp_path)
    assert summary["crashes"] == 3 and summary["crashes_by_type"] == {"RuntimeError": 3}
    record = jsonl(tmp_path)[0]
    assert "plugin bug at frame 3" in record["error"]["traceback"]
    assert "Traceback" in record["error"]["traceback"]
    path = reproducer_path(tmp_path, record["episode"])
    doc = json.loads(path.read_text())
    assert doc["params"]["spec"]["mappers"] == ["fuzz_plugins:Crashing"]
    capsys.readouterr()
    assert main(["run", "--reproduce", str(path), "--out", str(tmp_path / "again")]) == 1
    printed = capsys.readouterr()
    assert "reproduce: crash: RuntimeError: plugin bug at frame 3" in printed.out
    assert "reproduce: the recorded failure reproduces" in printed.out
    assert "plugin bug at frame 3" in printed.err  # the traceback
    assert not (tmp_path / "again").exists()
    # A reproducer as albot2d wrote them for dead workers before: no report, no world, only
    # the campaign and the index; the episode is drawn again.
    old = {
        "reproducer": {
            "episode": {k: record[k] for k in ("episode", "seed", "status", "error")},
            "campaign": params.to_dict(),
        }
    }
    path.write_text(json.dumps(old))
    assert main(["run", "--reproduce", str(path), "--out", str(tmp_path / "again")]) == 1
    assert "reproduce: the recorded failure reproduces" in capsys.readouterr().out


def test_a_dead_worker_fails_only_its_own_episode(
    plugins: Path, tmp_path: Path, capsys: pytest.CaptureFixture
) -> None:
    params = CampaignParams(episodes=4, seed=2, mapper="fuzz_plugins:Dying", **SMALL)
    backend = LocalBackend(2)
    try:
        run_campaign(params, tmp_path, backend=backend)
    finally:
        backend.close()
    records = {r["episode"]: r for r in jsonl(tmp_path)}
    assert sorted(records) == [0, 1, 2, 3]
    assert {r["status"] for r in records.values()} == {"ok", "crash"}  # both cases occur
    for k, r in records.items():
        spec = EpisodeSpec.draw(params, k)
        start = generate(spec.kind, seed=spec.run_seed, **spec.world_params).start
        dies = round(start.x * 1000) % 2 == 0
        assert r["status"] == ("crash" if dies else "ok"), (k, r["status"])
        if dies:
            assert r["error"]["type"] == "WorkerDiedError"
            assert r["world"]["kind"] == spec.kind and r["run_seed"] == spec.run_seed
    # Its reproducer replays: in a child process, which dies the same way.
    died = min(k for k, r in records.items() if r["status"] == "crash")
    path = reproducer_path(tmp_path, died)
    assert json.loads(path.read_text())["format"] == "albot2d-report"
    capsys.readouterr()
    assert main(["run", "--reproduce", str(path), "--out", str(tmp_path / "again")]) == 1
    assert "reproduce: the episode killed its process again (exit code 3)" in (
        capsys.readouterr().out
    )
    assert not (tmp_path / "again").exists()


def test_a_users_own_mapper_is_fuzzed_the_same_way(plugins: Path, tmp_path: Path) -> None:
    params = CampaignParams(episodes=3, seed=4, mapper="fuzz_plugins:Tiny", **SMALL)
    summary = run_campaign(params, tmp_path)
    # Dead reckoning is held to the heading bound like any mapper that reports a
    # trajectory (against the links Albot1 finds on the same frames): it may leave it,
    # and nothing else fails.
    assert summary["crashes"] == 0
    assert set(summary["failures_by_invariant"]) <= {"heading_error_bound"}
    record = jsonl(tmp_path)[0]
    assert record["mapper"] == "fuzz_plugins:Tiny"
    assert record["checked"] == [
        "heading_error_bound",
        "laser_hits_on_obstacles",
        "robot_clear_of_obstacles",
    ]
    assert record["metrics"]["heading_error_max_deg"] == pytest.approx(
        record["metrics"]["odometry_heading_error_max_deg"], abs=1e-6
    )
    # It is odometry by other arithmetic: every comparison is a tie, never a win.
    for label, cmp in summary["mapper_vs_odometry"].items():
        assert (cmp["ties"], cmp["mapper_better"], cmp["mapper_worse"]) == (3, 0, 0), label


@pytest.mark.parametrize(
    ("change", "message"),
    [
        ({"kinds": ("caves",)}, "unknown world kind 'caves'"),
        ({"mapper": "nope"}, "unknown mapper 'nope'"),
        ({"profile": "sprint"}, "unknown driving profile 'sprint'"),
        ({"episodes": 0}, "episodes must be a positive integer"),
        ({"world_size_min_m": 40.0}, "world_size_min_m .* is larger than world_size_max_m"),
    ],
)
def test_bad_campaign_parameters_are_input_errors(change: dict, message: str) -> None:
    with pytest.raises(InputError, match=message):
        CampaignParams(**{"episodes": 1, **change})


@pytest.mark.parametrize(
    ("index", "kind", "run_seed"),
    [
        (326, "office", 5094196264049440860),  # two neighbouring mixed pixels
        (126, "rooms", 8752786329543876772),  # a mixed pixel splitting a 0.205 m jump in two
    ],
)
def test_pinned_campaign_findings_now_pass(index: int, kind: str, run_seed: int) -> None:
    """Episodes that failed in 1000-episode campaigns (seed 0) and were fixed since: the
    laser-hit check took mixed pixels for hits off the walls."""
    spec = EpisodeSpec.draw(CampaignParams(episodes=1000, seed=0), index)
    assert (spec.kind, spec.run_seed) == (kind, run_seed)  # still the episode that failed
    record = run_episode(spec).record
    assert record.status == "ok", record.violations


def test_an_episode_runs_with_the_heap_frozen_and_hands_it_back() -> None:
    """Episodes run with the caller's objects out of the collector's reach (campaign
    ``_heap_frozen``), and the heap is as it was afterwards, frozen or not."""
    import gc

    from albot2d.evaluation.fuzz.campaign import _heap_frozen

    assert gc.get_freeze_count() == 0
    with _heap_frozen():
        frozen = gc.get_freeze_count()
        cycle: list[object] = []
        cycle.append(cycle)  # made inside: collected as usual
        del cycle
        assert gc.collect() >= 1
    assert frozen > 1000 and gc.get_freeze_count() == 0
    gc.freeze()  # someone else's freeze is left alone: neither thawed nor frozen again
    try:
        held = gc.get_freeze_count()
        # (a frozen object freed meanwhile, e.g. by another thread of the test process,
        # leaves the permanent generation: the count may drop by a few, never rise or
        # fall to the episode's own)
        with _heap_frozen():
            assert held - 100 <= gc.get_freeze_count() <= held
        assert held - 100 <= gc.get_freeze_count() <= held
    finally:
        gc.unfreeze()
