"""Readings of the paper: ``albot1[KEY=VALUE]`` for every ``Albot1Params`` field, the
``paper_literal`` preset with algorithm #4 as written, experiments under several readings,
and the zero-noise invariant's per-link bound (it holds on exact runs and catches a planted
1° triangulation error)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from albot2d.cli import main
from albot2d.errors import InputError
from albot2d.evaluation.checks import invariants as inv
from albot2d.geometry import Pose
from albot2d.mapping import Albot1, Albot1Params
from albot2d.mapping.albot1.options import albot1_params_from_spec, option_table
from albot2d.mapping.albot1.route_map import RouteMap
from albot2d.mapping.registry import mapper_factory
from albot2d.perception.surfaces import Surfaces
from albot2d.sim.laser import LaserNoise
from tests.runs import simulate
from worldgen.generate import generate


# -- albot1[KEY=VALUE] -------------------------------------------------------------------
def _other_value(opt):  # type: ignore[no-untyped-def]
    """A valid value of the option's type other than its default, as text."""
    import typing

    args = typing.get_args(opt.annotation)
    if typing.get_origin(opt.annotation) is typing.Literal:
        return next(a for a in args if a != opt.default)
    if isinstance(opt.default, bool):
        return "false" if opt.default else "true"
    if isinstance(opt.default, int):
        return str(opt.default + 1)
    if opt.default is None:
        return "0.25"
    if math.isinf(opt.default):
        return "12.5"
    return repr(opt.default * 0.5 if opt.default else 0.5)


@pytest.mark.parametrize("opt", option_table(), ids=lambda o: o.key)
def test_every_field_is_settable_by_name(opt) -> None:  # type: ignore[no-untyped-def]
    text = _other_value(opt)
    params = albot1_params_from_spec("albot1[...]", f"{opt.key}={text}")
    group = getattr(params, opt.group) if opt.group else params
    value = getattr(group, opt.field)
    assert value != opt.default
    if isinstance(value, float):
        assert value == float(text)
    else:
        assert str(value).lower() == text.lower()
    # everything else stays at the default
    default = Albot1Params()
    changed = [f.name for f in dataclasses.fields(params)
               if getattr(params, f.name) != getattr(default, f.name)]  # fmt: skip
    assert changed == [opt.group or opt.field]


def test_bare_names_presets_and_deletion_compose() -> None:
    params = mapper_factory(
        "albot1[preset=original,min_tracked=4,match_distance_m=0.3,deletion=paper,"
        "deletion.enlarge_m=0.2,triangulation.max_pi_deviation_m=none,max_endpoint_gap_m=inf]"
    )().params  # type: ignore[attr-defined]
    assert params.tracking.match_endpoint == "key" and params.min_tracked == 4
    assert params.tracking.match_distance_m == 0.3
    assert params.global_map.enlarge_m == 0.2 and params.global_map.expand == "split"
    assert params.triangulation.max_pi_deviation_m is None
    assert math.isinf(params.extraction.max_endpoint_gap_m)


@pytest.mark.parametrize(
    ("spec", "message"),
    [
        ("albot1[colour=red]", "unknown key 'colour'"),
        ("albot1[min_tracked=x]", "min_tracked must be int, got 'x'"),
        ("albot1[heading=north]", "triangulation.heading must be one of weighted"),
        ("albot1[min_length_m=-1]", "TrackingParams.min_length_m must be >= 0"),
        ("albot1[preset=literal]", "unknown Albot1 preset 'literal'"),
        ("albot1[min_tracked=3,min_tracked=4]", "min_tracked given twice"),
        ("albot1[localise_every_view=maybe]", "localise_every_view must be bool"),
        ("albot1[min_tracked]", "'min_tracked' is not key=value"),
    ],
)
def test_bad_options_name_the_spec_and_the_key(spec: str, message: str) -> None:
    with pytest.raises(InputError) as caught:
        mapper_factory(spec)
    assert str(caught.value).startswith(f"mapper {spec!r}: ") and message in str(caught.value)


def test_help_lists_every_key(capsys) -> None:  # type: ignore[no-untyped-def]
    for command in ("run", "fuzz", "replay"):
        try:
            assert main([command, "--help"]) == 0
        except SystemExit as exc:  # argparse's own exit after printing help
            assert exc.code == 0
        out = capsys.readouterr().out
        for opt in option_table():
            assert f"{opt.key}=" in out, (command, opt.key)
        assert "preset=default|paper_literal|original|start_stop" in out


def test_paper_literal_reads_the_text() -> None:
    p = Albot1Params.preset("paper_literal")
    assert math.isinf(p.triangulation.max_pi_deviation_m or 0.0)
    assert math.isinf(p.triangulation.max_pi_deviation_deg or 0.0)
    assert p.triangulation.position_endpoint == "current_real"
    # occluded only behind something nearer: a wall thinning out at a grazing angle is not
    assert p.extraction.continuation_distance_m == 0.0
    assert math.isinf(p.extraction.max_endpoint_gap_m)
    assert p.move_using_pi == "as_written" and p.min_tracked == 4
    assert Albot1Params.preset("default") == Albot1Params.preset("paper") == Albot1Params()


# -- algorithm #4 as written --------------------------------------------------------------
def _view(n: int) -> Surfaces:
    """``n`` trackable walls in front of the robot (long, seen at a wide angle, real ends),
    each at its own distance so none is recognised as another."""
    segs = [[2.0 + 1.5 * k, -1.0 - 0.2 * k, 2.0 + 1.5 * k, 1.0 + 0.2 * k] for k in range(n)]
    return Surfaces(np.array(segs, float).reshape(-1, 4), np.zeros((n, 2), bool),
                    np.tile([0, 30], (n, 1)))  # fmt: skip


def _feed(params: Albot1Params, views: list[Surfaces]) -> tuple[Albot1, inv.ViewRecorder]:
    m = Albot1(params)
    recorder = inv.ViewRecorder().attach(m)
    for k, view in enumerate(views):
        m.observe_view(k, float(k), view, Pose())
    return m, recorder


# five trackable walls; none (view 2); two, two, five again, five, five
VIEWS = [_view(5), _view(5), Surfaces.empty(), _view(2), _view(2), _view(5), _view(5), _view(5)]


def test_algorithm_4_as_written_remembers_every_view_until_one_is_full() -> None:
    m, views = _feed(Albot1Params(move_using_pi="as_written"), VIEWS)
    methods = [(lm.frame_index, lm.method) for lm in m.route]
    # view 1 (V(c-1)) triangulated, view 2 (no surface) by path integration, then every
    # view until one has > 3 trackable surfaces (view 5, line 8), also by path integration
    assert methods == [(0, "start"), (1, "triangulation"), (2, "path_integration"),
                       (3, "path_integration"), (4, "path_integration"),
                       (5, "path_integration")]  # fmt: skip
    assert [s.tracked for s in m.steps][2:6] == [0, 2, 2, 5]
    inv.check_local_map_rule(m, views.views)  # the recount follows algorithm #4 too
    restated, rviews = _feed(Albot1Params(), VIEWS)
    # restated: view 3 is tracked against view 2 (nothing to track): remembered with 0
    # tracked by path integration, view 4 tracks view 3's two walls: triangulated; view 5
    # tracks two of its walls → remembered (triangulated) and tracking resumes there
    assert [lm.method for lm in restated.route].count("path_integration") == 2
    inv.check_local_map_rule(restated, rviews.views)


def _moved(n: int, shift_m: float) -> Surfaces:
    """``_view(n)`` with every wall ``shift_m`` farther: RTSV recognises none of them from
    ``_view`` (their ends are more than 40 cm from where they were), yet all are trackable."""
    view = _view(n)
    segs = view.segments + np.array([shift_m, 0.0, shift_m, 0.0])
    return Surfaces(segs, view.occluded, view.beams)


# five walls; the same two walls moved (none tracked, two trackable), twice; five moved walls
LOST = [_view(5), _view(5), _moved(2, 0.7), _moved(2, 0.7), _moved(5, 0.7), _moved(5, 0.7)]


def test_algorithm_4_starts_only_where_no_surface_is_trackable() -> None:
    """Line 8 tests S_t after update-maps set it to the remembered view's trackable
    surfaces: a view with trackable surfaces but none tracked is placed by path integration
    and tracking resumes from it (the paper's Fig. 15: PI mode "when no trackable surfaces
    are in view"); reading S_t as RTSV's result (``on_lost_tracking``) starts PI mode."""
    m, views = _feed(Albot1Params(move_using_pi="as_written"), LOST)
    methods = [(lm.frame_index, lm.method) for lm in m.route]
    # view 2: nothing tracked → path integration; it has two trackable walls, so view 3
    # tracks them (2 < 4: remembered, triangulated); view 4 tracks view 3's two walls
    # (remembered, triangulated), view 5 keeps view 4's five
    assert methods == [(0, "start"), (1, "triangulation"), (2, "path_integration"),
                       (3, "triangulation"), (4, "triangulation")]  # fmt: skip
    inv.check_local_map_rule(m, views.views)
    lost, lviews = _feed(Albot1Params(move_using_pi="on_lost_tracking"), LOST)
    # PI mode from view 2 on: views 3 and 4 by path integration, 4 (five trackable) ends it
    assert [(lm.frame_index, lm.method) for lm in lost.route][2:] == [
        (2, "path_integration"), (3, "path_integration"), (4, "path_integration")]  # fmt: skip
    inv.check_local_map_rule(lost, lviews.views)
    # the preset reads the paper: the case above is the as-written one
    assert Albot1Params.preset("paper_literal").move_using_pi == "as_written"


# -- experiments under readings -----------------------------------------------------------
def test_readings_are_checked_before_anything_runs(tmp_path, capsys) -> None:  # type: ignore[no-untyped-def]
    out = tmp_path / "never"
    argv = ["experiments", "--quick", "--only", "table1", "--out", str(out), "--readings"]
    assert main([*argv, "default", "literal"]) == 2
    assert "unknown reading 'literal'" in capsys.readouterr().err
    assert main([*argv, "default", "albot1[preset=paper]"]) == 2
    assert "runs the same mapper" in capsys.readouterr().err
    assert main([*argv, "albot1[colour=red]"]) == 2
    assert not out.exists()


def test_compute_readings_puts_each_reading_side_by_side() -> None:
    from albot2d.evaluation.paper.campaign import compute_readings
    from albot2d.viz.paper_page import render_page
    from tests import paper_jobs as pj

    def job(err: float) -> pj.JobSummary:
        return pj.job(homing=[pj.homing_stop(20.0, err, 0.0, travelled_m=20.0)])

    by_reading = {
        "default": {"fig8_anticlockwise": [job(1.0)], "fig8_clockwise": [job(2.0)]},
        "paper_literal": {"fig8_anticlockwise": [job(9.0)], "fig8_clockwise": [job(2.0)]},
    }
    out = compute_readings(["table1"], [0], by_reading, quick=True, albot_x=False)
    t1 = out.data["experiments"]["table1"]
    assert t1["reading"] == "default" and t1["verdict"] == "reproduced"
    assert t1["readings"]["paper_literal"]["ours"]["fraction_within_bound"] == 0.5
    assert out.data["verdicts_by_reading"]["table1"] == {
        "default": "reproduced", "paper_literal": "partly"}  # fmt: skip
    assert out.data["readings"]["paper_literal"] == "albot1[preset=paper_literal]"
    files = [f["file"] for f in out.figures["table1"]]
    assert files == ["table1.png", "paper_literal-table1.png"]
    page = render_page(out.data, {})
    assert "verdict: paper_literal" in page and "<td class='who'>paper_literal</td>" in page


# -- the zero-noise invariant -------------------------------------------------------------
@pytest.fixture(scope="module")
def exact_run():  # type: ignore[no-untyped-def]
    world = generate("office", seed=11, width_m=28.0, height_m=24.0)
    frames = simulate(world, 11, noise="none", laser=LaserNoise.zero(), length_m=30.0)
    m = Albot1()
    recorder = inv.LocalisationRecorder().attach(m)
    recorder.resolution_rad = float(np.diff(frames[0].scan.angles).max())
    for f in frames:
        m.observe(f)
    truth = np.array([f.true_pose.as_array() for f in frames])
    return m, recorder, truth, np.array([f.index for f in frames])


def test_zero_noise_bounds_hold_on_an_exact_run(exact_run) -> None:  # type: ignore[no-untyped-def]
    m, recorder, truth, index = exact_run
    assert m.counts().triangulations > 20
    inv.check_zero_noise_localisation(m.route, index, truth, localisations=recorder)
    bounds = inv.zero_noise_link_bounds(m.route, index, truth, recorder.pairs,
                                        recorder.resolution_rad, 0.05)  # fmt: skip
    assert len(bounds) == len(m.route) - 1
    assert all(b.heading_err_rad <= b.heading_bound_rad for b in bounds)
    # most links are bound well under 1° (the planted error below is caught there)
    assert np.median([math.degrees(b.heading_bound_rad) for b in bounds]) < 0.2


def test_a_planted_1_degree_triangulation_error_is_caught(exact_run) -> None:  # type: ignore[no-untyped-def]
    m, recorder, truth, index = exact_run
    k = next(i for i, lm in enumerate(m.route) if lm.method == "triangulation" and i > 2)
    maps = list(m.route.maps)
    maps[k] = dataclasses.replace(
        maps[k], pose_in_previous=maps[k].pose_in_previous @ Pose(0.0, 0.0, math.radians(1.0))
    )
    planted = RouteMap(maps)
    with pytest.raises(inv.InvariantError, match=rf"1 of \d+ local maps beyond their bound; "
                                                 rf"worst map {k} "):  # fmt: skip
        inv.check_zero_noise_localisation(planted, index, truth, localisations=recorder)


def test_fit_and_end_bounds_follow_beams_and_geometry() -> None:
    # a 1 m wall 2 m ahead, face on, 30 beams; the same with 6 beams; no beams at all
    s = Surfaces(np.array([[2.0, -0.5, 2.0, 0.5]] * 3), np.zeros((3, 2), bool),
                 np.array([[0, 29], [0, 5], [-1, -1]]))  # fmt: skip
    b = inv.fit_direction_bounds(s, 0.05)
    assert b[0] == pytest.approx(24 * 0.05 / 30) and b[1] == pytest.approx(24 * 0.05 / 6)
    assert math.isinf(b[2])
    g = inv.end_position_bounds(s, math.radians(1.0), 0.05)
    r = math.hypot(2.0, 0.5)
    # beam spacing r·Δφ/sin β at the end (β: between the beam and the wall) + split
    assert g[0, 0] == pytest.approx(r * math.radians(1.0) / (2.0 / r) + 0.05)
