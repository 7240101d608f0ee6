"""``Simulator.reset`` / ``step``: the time-stepped interface a controller drives."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from albot2d.errors import InputError
from albot2d.geometry import Pose
from albot2d.sim import MAX_STEP_DT_S, Observation, Simulator, VelocityCommand
from albot2d.sim.laser import LaserNoise
from albot2d.sim.odometry import NOISE_PRESETS
from albot2d.sim.robot import RobotParams
from tests.test_simulator import MOVERS, room_world

ROOT = Path(__file__).resolve().parents[1]


def _run(
    sim: Simulator, seed: int | None, commands: list[tuple[float, float, float]]
) -> list[Observation]:
    out = [sim.reset(seed)]
    out += [sim.step(VelocityCommand(v, w), dt) for v, w, dt in commands]
    return out


def _key(obs: Observation) -> bytes:
    parts = [obs.time_s, *obs.true_pose.as_array(), *obs.odom_pose.as_array(), obs.collided]
    scan = obs.scan.ranges.tobytes() if obs.scan is not None else b"-"
    return np.array(parts, float).tobytes() + scan


COMMANDS = [(0.4, 0.3, 0.05)] * 40 + [(0.0, -1.0, 0.1)] * 10 + [(-0.2, 0.0, 0.25)] * 6


def noisy_sim(movers: bool = False) -> Simulator:
    return Simulator(
        room_world(MOVERS if movers else ()),
        seed=5,
        odometry=NOISE_PRESETS["pioneer3dx"],
        laser_noise=LaserNoise.sick_lms200(),
    )


@pytest.mark.parametrize("movers", [False, True])
def test_same_seed_gives_bit_identical_observations(movers: bool) -> None:
    a = [_key(o) for o in _run(noisy_sim(movers), 3, COMMANDS)]
    b = [_key(o) for o in _run(noisy_sim(movers), 3, COMMANDS)]
    assert a == b
    c = [_key(o) for o in _run(noisy_sim(movers), 4, COMMANDS)]
    assert a != c
    # reset() without a seed replays the simulator's own seed
    sim = noisy_sim(movers)
    assert [_key(o) for o in _run(sim, None, COMMANDS)] == [
        _key(o) for o in _run(sim, None, COMMANDS)
    ]


def test_observation_fields_and_clock() -> None:
    sim = noisy_sim()
    first = sim.reset()
    assert first.time_s == 0.0 and first.step_index == 0 and first.scan is not None
    assert first.true_pose == first.odom_pose == sim.world.start
    obs = sim.step(VelocityCommand(0.3, 0.0), 0.05)
    assert obs.time_s == pytest.approx(0.05) and obs.step_index == 1
    assert obs.true_pose.x == pytest.approx(sim.world.start.x + 0.015)
    assert obs.odom_twist.v_mps == pytest.approx(0.3, rel=0.2)
    assert sim.time_s == obs.time_s


def test_laser_fires_on_the_simulated_clock_not_per_call() -> None:
    """10 Hz: steps of 0.03 s get a scan in one step of about three; steps of 0.25 s
    get one per step (the latest), so scans are ~0.1 s apart in the first case."""
    sim = Simulator(room_world(), seed=1)
    sim.reset()
    times = [
        o.scan.timestamp
        for o in (sim.step(VelocityCommand(0.1, 0.0), 0.03) for _ in range(100))
        if o.scan is not None
    ]
    assert len(times) == 30  # 3.0 s at 10 Hz: firings at 0.1 ... 3.0 (0 was reset's)
    assert np.diff(times) == pytest.approx(np.full(len(times) - 1, 0.1), abs=0.031)
    sim.reset()
    assert all(sim.step(VelocityCommand(), 0.25).scan is not None for _ in range(5))
    never = Simulator(room_world(), seed=1, laser_rate_hz=None)
    assert never.reset().scan is None and never.step(VelocityCommand(), 1.0).scan is None


def test_commands_are_clamped_to_the_robot_limits() -> None:
    params = RobotParams(max_speed_m_s=0.5, max_turn_rate_deg_s=90.0)
    sim = Simulator(room_world(), seed=1, robot=params)
    sim.reset()
    obs = sim.step(VelocityCommand(2.0, 0.0), 0.5)
    assert obs.command == VelocityCommand(0.5, 0.0)
    assert obs.true_pose.x - sim.world.start.x == pytest.approx(0.25)
    obs = sim.step(VelocityCommand(-3.0, -10.0), 0.1)
    assert obs.command == VelocityCommand(-0.5, -math.pi / 2)


def test_robot_stops_at_walls_and_reports_the_collision() -> None:
    sim = Simulator(room_world(), seed=1)
    sim.reset(start=Pose(1.5, 1.5, math.pi))  # facing the wall at x = 0
    collided = []
    for _ in range(40):
        obs = sim.step(VelocityCommand(1.0, 0.2), 0.1)
        collided.append(obs.collided)
        assert obs.true_pose.x >= 0.25 - 1e-9 and obs.true_pose.y >= 0.25 - 1e-9
    assert any(collided)


def test_moving_obstacles_move_while_the_robot_stands() -> None:
    sim = noisy_sim(movers=True)
    before = sim.reset().obstacle_poses
    obs = sim.step(VelocityCommand(), 1.0)
    assert obs.true_pose == sim.world.start
    assert before is not None and obs.obstacle_poses is not None
    assert not np.allclose(before[0], obs.obstacle_poses[0])
    assert Simulator(room_world(), seed=1).reset().obstacle_poses is None


def test_zero_noise_odometry_equals_the_truth_bit_for_bit() -> None:
    sim = Simulator(room_world(), seed=1)
    for obs in _run(sim, None, COMMANDS):
        assert obs.odom_pose == obs.true_pose


@pytest.mark.parametrize(
    ("v", "w"), [(math.nan, 0.0), (0.0, math.inf), (-math.inf, 0.0), ("1", 0.0), (None, 0.0)]
)
def test_bad_commands_are_input_errors_naming_the_value(v: object, w: object) -> None:
    with pytest.raises(InputError, match=r"VelocityCommand\.(v_mps|omega_radps)"):
        VelocityCommand(v, w)  # type: ignore[arg-type]


@pytest.mark.parametrize("dt", [0.0, -0.1, math.nan, math.inf, MAX_STEP_DT_S * 2, "0.1", True])
def test_bad_dt_is_an_input_error_naming_the_value(dt: object) -> None:
    sim = Simulator(room_world(), seed=1)
    sim.reset()
    with pytest.raises(InputError, match=r"dt_s .*got " + repr(dt).replace(".", r"\.")[:4]):
        sim.step(VelocityCommand(0.1, 0.0), dt)  # type: ignore[arg-type]


def test_step_before_reset_and_bad_command_type() -> None:
    sim = Simulator(room_world(), seed=1)
    with pytest.raises(RuntimeError, match="reset"):
        sim.step(VelocityCommand(), 0.1)
    sim.reset()
    with pytest.raises(InputError, match="VelocityCommand"):
        sim.step("forward", 0.1)  # type: ignore[arg-type]
    obs = sim.step((0.2, 0.0), 0.5)  # type: ignore[arg-type]  # a (v, omega) pair works
    assert obs.command == VelocityCommand(0.2, 0.0)
    with pytest.raises(InputError, match="nan"):
        sim.step(np.array([np.nan, 0.0]), 0.1)  # type: ignore[arg-type]


def test_the_driving_yourself_snippet_is_a_short_loop_that_runs(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """docs/simulator.md "Driving albot2d yourself": a ten-line reset/step loop (the README
    copies it); it runs and the robot gets somewhere without touching a wall."""
    text = (ROOT / "docs" / "simulator.md").read_text(encoding="utf-8")
    section = text.split("## Driving albot2d yourself", 1)[1].split("\n## ", 1)[0]
    code = section.split("```python\n", 1)[1].split("```", 1)[0]
    lines = [line for line in code.splitlines() if line.strip()]
    assert len(lines) <= 10 and "sim.reset(" in code and "sim.step(" in code
    monkeypatch.chdir(tmp_path)
    namespace: dict[str, object] = {}
    exec(compile(code, "docs/simulator.md", "exec"), namespace)
    obs = namespace["obs"]
    assert isinstance(obs, Observation) and obs.time_s == pytest.approx(60.0)
    assert obs.true_pose.distance_to(namespace["sim"].world.start) > 1.0  # type: ignore[attr-defined]
    assert "60 s: true Pose(" in capsys.readouterr().out


@pytest.mark.parametrize(
    ("command", "fine", "coarse"),
    [
        (VelocityCommand(0.3, 0.0), (300, 1.0 / 30.0), (1, 10.0)),  # 3 m in 1 cm or one step
        (VelocityCommand(0.0, math.radians(30.0)), (90, 1.0 / 30.0), (1, 3.0)),  # 90° in 1°
    ],
)
def test_odometry_does_not_depend_on_the_step_length(
    command: VelocityCommand, fine: tuple[int, float], coarse: tuple[int, float]
) -> None:
    """The same motion stepped finely or in one step: the same true pose and, with the
    same seed, the same odometry pose (its error arises along the path, not per step)."""
    ends = []
    for n, dt in (fine, coarse):
        sim = Simulator(room_world(), seed=9, odometry=NOISE_PRESETS["high"])
        sim.reset(start=Pose(2.0, 4.0, 0.0))
        for _ in range(n):
            obs = sim.step(command, dt)
        ends.append(obs)
    assert ends[0].true_pose.distance_to(ends[1].true_pose) < 1e-9
    assert ends[0].odom_pose.distance_to(ends[1].odom_pose) < 1e-9
    assert abs(ends[0].odom_pose.theta - ends[1].odom_pose.theta) < 1e-9
    assert ends[0].odom_pose.distance_to(ends[0].true_pose) > 1e-3  # there is an error
