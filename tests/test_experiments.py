"""The paper's experiments: each computation on hand-built job summaries with known answers."""

from __future__ import annotations

import pytest

from albot2d.errors import InputError
from albot2d.evaluation.paper import counts, plan_jobs, table1
from albot2d.evaluation.paper.jobs import JobSummary, MarkCounts, PathIntegrationCauses
from albot2d.evaluation.paper.process_exp import FIG15, FIG16, method_sequences, room_exit_rows
from albot2d.evaluation.paper.stats import over_seeds, verdict_of
from albot2d.validation import parse_seed_list as parse_seeds
from tests import paper_jobs as pj


def _counts_job(views: int, maps: int, pi: int, marks: tuple[str, ...]) -> JobSummary:
    c = MarkCounts(views, maps, pi)
    return pj.job(end_counts=pj.counts(views, maps, pi),
                  marks={m: pj.mark(mapper_counts={"albot1": c}) for m in marks})  # fmt: skip


def test_counts_ratio_and_path_integration_checks():
    # dataset 1 at E5: 800 -> 300 (0.375 vs the paper's 0.386: within 25 %)
    jobs = {
        "fig6_dataset1": [_counts_job(800, 300, 4, ("E5", "E7")),
                          _counts_job(800, 320, 6, ("E5", "E7"))],
        "fig6_dataset2": [_counts_job(800, 330, 9, ("E7",)), _counts_job(800, 330, 5, ("E7",))],
        "fig6_dataset3": [_counts_job(200, 120, 3, ()), _counts_job(200, 130, 3, ())],
        "fig6_start_stop": [_counts_job(70, 60, 9, ()), _counts_job(70, 60, 9, ())],
        "fig11_open": [_counts_job(150, 140, 3, ()), _counts_job(150, 140, 3, ())],
    }  # fmt: skip
    r = counts.compute(jobs, [0, 1])
    d1 = r["ours"]["dataset1"]
    assert d1["views"]["mean"] == 800 and d1["local_maps"]["per_seed"] == {"0": 300, "1": 320}
    assert d1["local_maps_per_view"]["mean"] == pytest.approx(310 / 800)
    assert d1["ratio_within_25pct"] and r["ours"]["dataset3"]["ratio_within_25pct"]
    # 140/150 = 0.93 against 103/153 = 0.67: outside ±25 %
    assert not r["ours"]["non_corridor"]["ratio_within_25pct"]
    # dataset 2 needs more path integrations on seed 0 only: half the seeds, not most
    assert r["ours"]["path_integrations_more_with_dataset2_share"] == 0.5
    assert r["paper"]["dataset1"] == {"views": 795, "local_maps": 307,
                                      "local_maps_per_view": 307 / 795,
                                      "path_integrations": 5}  # fmt: skip
    assert r["verdict"] == "partly"


def test_table1_counts_only_stops_17_to_35_m_from_s():
    _stop = pj.homing_stop
    acw = pj.job(homing=[
        _stop(10.0, 30.0, 9.0),  # too near: not a Table 1 stop
        _stop(20.0, 6.9, -2.9),  # within
        _stop(34.0, -7.5, 0.0),  # bearing out of bound
    ])  # fmt: skip
    cw = pj.job(homing=[_stop(17.0, 0.0, 3.1), _stop(30.0, 1.0, 1.0), _stop(40.0, 50.0, 50.0)])
    r = table1.compute({"fig8_anticlockwise": [acw], "fig8_clockwise": [cw]}, [0])
    ours = r["ours"]
    assert ours["n_stops"] == 4
    assert [s["within_bound"] for s in ours["stops"]] == [True, False, False, True]
    assert ours["fraction_within_bound"] == 0.5
    assert ours["bearing_error_abs_max_deg"] == pytest.approx(7.5)  # via radians
    assert r["paper"]["fraction_within_bound"] == 1.0 and len(r["paper"]["rows"]) == 4
    assert r["verdict"] == "partly"


def _fig16_job(p95_albot1: float, p95_naive: float, pi: int) -> JobSummary:
    return pj.job(
        quality_at={"E7": pj.quality(albot1=p95_albot1, naive=p95_naive)},
        marks={"E7": pj.mark(mapper_counts={"albot1": MarkCounts(0, 0, pi)})},
    )


def test_fig16_ratio_of_naive_to_albot1_and_path_integrations():
    jobs = {"fig6_dataset1": [_fig16_job(0.2, 0.5, 5), _fig16_job(0.2, 0.6, 5)],
            "fig6_dataset2": [_fig16_job(0.3, 1.2, 7), _fig16_job(0.5, 1.0, 8)]}  # fmt: skip
    r = FIG16.compute(jobs, [3, 4])
    acc = r["ours"]["map_accuracy_p95_m"]
    assert acc["albot1"]["per_seed"] == {"3": 0.3, "4": 0.5}
    assert acc["naive"]["mean"] == pytest.approx(1.1)
    assert r["ours"]["naive_over_albot1_p95_dataset2"]["mean"] == pytest.approx(3.0)
    assert r["verdict"] == "reproduced"
    jobs["fig6_dataset2"][0] = _fig16_job(0.6, 1.2, 4)  # ratios 2 and 2; fewer PIs on seed 3
    assert FIG16.compute(jobs, [3, 4])["verdict"] == "not reproduced"


def test_method_sequences_finds_triangulation_then_path_integration():
    m = ["", "triangulation", "", "path_integration", "path_integration", "triangulation",
         "triangulation", "path_integration", ""]  # fmt: skip
    assert method_sequences(m) == [(1, 2), (6, 1)]
    assert method_sequences(["triangulation", "triangulation"]) == []


def test_over_seeds_and_verdicts():
    s = over_seeds([1.0, None, 3.0], [5, 6, 7])
    assert (s["mean"], s["n"], s["per_seed"]["6"]) == (2.0, 2, None)
    assert s["sd"] == pytest.approx(2**0.5)
    assert verdict_of([True, True]) == "reproduced"
    assert verdict_of([True, False]) == "partly"
    assert verdict_of([False]) == verdict_of([]) == "not reproduced"


def test_seed_ranges_and_bad_input():
    assert parse_seeds("0-3") == [0, 1, 2, 3]
    assert parse_seeds("5,1,1-2") == [1, 2, 5]
    for bad in ("x", "3-1", "-2", "1-"):
        with pytest.raises(InputError, match="--seeds"):
            parse_seeds(bad)
    with pytest.raises(InputError, match="unknown experiment 'fig99'"):
        plan_jobs(["fig99"], [0])
    assert plan_jobs(["table1"], [0, 1]) == [
        ("fig8_anticlockwise", 0), ("fig8_anticlockwise", 1),
        ("fig8_clockwise", 0), ("fig8_clockwise", 1),
    ]  # fmt: skip


def _room_update(methods: list[str], tracked: list[int]) -> pj.Updates:
    """A fig15 route along x: RD at 2 m, R at 5 m, back at RD at 8 m (true distance); a
    view every metre (two at R: the arrival, then the turn)."""
    xs = [0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 5.0, 4.0, 3.0, 2.0, 1.0, 0.0]
    assert len(methods) == len(tracked) == len(xs)
    return pj.updates([[x, 0.0] for x in xs], methods, tracked, ["corridor"] * len(xs),
                      {"S": [0.0], "RD": [2.0, 8.0], "R": [5.0], "E1": [10.0]})  # fmt: skip


def test_fig15_counts_the_methods_from_the_room_to_the_corridor():
    u = _room_update(
        ["start", "", "triangulation", "", "", "", "triangulation", "path_integration",
         "path_integration", "", "triangulation", ""],
        [0, 5, 3, 4, 4, 4, 2, 0, 0, 4, 3, 4],
    )  # fmt: skip
    # from the arrival at R (row 5) to back at RD (row 9), and two more rows
    assert room_exit_rows(u) == [5, 6, 7, 8, 9, 10, 11]
    plain = _room_update(["start"] + ["triangulation"] * 11, [0] + [3] * 11)
    jobs = {"fig15_room": [u, plain], "fig6_start_stop": [u, plain]}
    jobs = {k: [pj.job(steps=x) for x in v] for k, v in jobs.items()}
    r = FIG15.compute(jobs, [0, 1])
    exit_ = r["ours"]["room_exit"]
    assert exit_["path_integrations"]["per_seed"] == {"0": 2.0, "1": 0.0}
    assert exit_["triangulations"]["per_seed"] == {"0": 2.0, "1": 7.0}
    assert exit_["views_with_no_tracked_surface"]["per_seed"] == {"0": 2.0, "1": 0.0}
    assert exit_["share_of_seeds_triangulation_then_2plus_pi"] == 0.5
    assert r["verdict"] == "reproduced"  # half of the seeds
    jobs["fig15_room"][0] = pj.job(steps=plain)
    assert FIG15.compute(jobs, [0, 1])["verdict"] == "not reproduced"


def test_path_integration_causes_are_split_and_cut_at_the_mark():
    causes = PathIntegrationCauses(
        frames=(3, 7, 9, 20), tracked=(0, 2, 0, 0), turning=(True, False, False, True),
        regions=("corridor", "corridor", "hall", "corridor"), update_frames=(0, 3, 5, 7, 9, 20),
        update_methods=("start", "path_integration", "triangulation", "path_integration",
                        "path_integration", "path_integration"),
    )  # fmt: skip
    job = pj.job(causes=causes, marks={"E7": pj.mark(frame=10)})
    c = counts._pi_causes([job], "E7", [0])
    values = {k: v["per_seed"]["0"] for k, v in c.items()}
    assert values == {"total": 3, "no_tracked_surface": 2, "tracked_but_no_pose": 1,
                      "after_a_turn": 1, "in_corridor": 2, "in_hall": 1, "in_room": 0,
                      "runs": 2, "updates": 5}  # fmt: skip


def test_run_experiment_without_scoring_drives_the_same_run():
    import numpy as np

    from albot2d.evaluation.run.experiment import RunSpec, run_experiment

    spec = RunSpec(kind="fig6", seed=1, route="fig15", profile="start_stop", noise="pioneer3dx",
                   mappers=("albot1", "naive"), max_frames=8)  # fmt: skip
    full, light = run_experiment(spec), run_experiment(spec, score=False)
    assert np.array_equal(full.trace.true_poses, light.trace.true_poses)
    assert np.array_equal(full.trace.odom_poses, light.trace.odom_poses)
    assert light.report["mappers"] == {}
    assert all(v is None for v in light.report["odometry"].values())  # nothing scored
    assert light.report["run"]["relations"] is None and full.report["run"]["relations"] > 0
    assert light.report["run"]["frames"] == full.report["run"]["frames"] == 8
    counts = full.report["mappers"]["albot1"]["counts"]
    assert light.trace.mappers["albot1"].counts().local_maps == counts["local_maps"]


def _same_plain(a: object, b: object) -> bool:
    import numpy as np

    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        return (
            isinstance(a, np.ndarray)
            and isinstance(b, np.ndarray)
            and a.dtype == b.dtype
            and np.array_equal(a, b)
        )
    if isinstance(a, dict) and isinstance(b, dict):
        return list(a) == list(b) and all(_same_plain(a[k], b[k]) for k in a)
    if isinstance(a, list) and isinstance(b, list):
        return len(a) == len(b) and all(_same_plain(x, y) for x, y in zip(a, b, strict=True))
    return type(a) is type(b) and a == b


def test_a_job_summary_crosses_a_process_whole():
    """A job's typed summary, to plain data (what a worker sends back) and back: every
    number, array (dtype too) and key order the same, and it pickles as plain data."""
    import pickle

    from albot2d.evaluation.paper.runs import run_job_readings

    out = run_job_readings("fig6_dataset1", 0, quick=True, albot_x=False, keep_figures=True,
                           readings=("default", "paper_literal"))  # fmt: skip
    for reading, summary in out.items():
        assert summary.figures is not None and summary.figures.snaps  # the figure seed's
        assert summary.reading == reading and summary.others  # naive beside Albot1
        plain = summary.to_plain()
        again = JobSummary.from_plain(pickle.loads(pickle.dumps(plain)))
        assert _same_plain(again.to_plain(), plain)
        assert again.albot1 == summary.albot1 and again.marks == summary.marks
        assert again.map_quality_at_marks == summary.map_quality_at_marks
