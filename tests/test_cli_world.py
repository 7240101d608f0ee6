"""``albot2d world``: real command runs; bad input gives one line, exit 2 and no output file."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from albot2d.cli import main
from worldgen.io import load, world_to_json

REPO = Path(__file__).resolve().parents[1]
KIND = "rooms"
SMALL = ["--width", "16", "--height", "14"]
PLAN = {
    "id": "l-house",
    "verts": [[0, 0], [8, 0], [8, 3], [3, 3], [3, 8], [0, 8]],
    "room_category": {"Kitchen": [[0, 0, 8, 3]], "Bedroom": [[0, 3, 3, 8]]},
}


def run_cli(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str, str]:
    code = main(["world", *argv])
    captured = capsys.readouterr()
    return code, captured.out, captured.err


def assert_one_line_error(code: int, err: str, *needles: str) -> None:
    assert code == 2
    assert err.count("\n") == 1 and err.startswith("albot2d world: error: ")
    assert "Traceback" not in err
    for needle in needles:
        assert needle in err


def test_real_command_writes_world_and_png(tmp_path: Path) -> None:
    out, png = tmp_path / "w.json", tmp_path / "w.png"
    args = ["world", "--kind", KIND, "--seed", "3", *SMALL, "--out", str(out), "--png", str(png)]
    proc = subprocess.run(
        [sys.executable, "-m", "albot2d", *args], cwd=REPO, capture_output=True, text=True
    )
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.count("\n") == 1 and proc.stdout.startswith(f"{KIND} seed 3: ")
    world = load(out)
    assert (world.kind, world.seed) == (KIND, 3)
    assert f"{len(world.walls)} walls" in proc.stdout
    assert png.read_bytes()[:4] == b"\x89PNG"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["w.json", "w.png"]


def test_real_command_error_is_one_line(tmp_path: Path) -> None:
    out = tmp_path / "w.json"
    proc = subprocess.run(
        [sys.executable, "-m", "albot2d", "world", "--kind", "castle", "--out", str(out)],
        cwd=REPO, capture_output=True, text=True,
    )  # fmt: skip
    assert_one_line_error(proc.returncode, proc.stderr, "'castle'", "valid kinds:", KIND)
    assert list(tmp_path.iterdir()) == []


def test_same_arguments_give_identical_files(tmp_path: Path, capsys) -> None:
    paths = [tmp_path / "a.json", tmp_path / "b.json"]
    for path in paths:
        code, _, err = run_cli(capsys, "--kind", KIND, "--seed", "5", *SMALL, "--out", str(path))
        assert code == 0, err
    assert paths[0].read_bytes() == paths[1].read_bytes()
    world = load(paths[0])
    assert world_to_json(world) == paths[0].read_text()
    assert world.width_m <= 16.0 + 1e-9 and world.height_m <= 14.0 + 1e-9


@pytest.mark.parametrize(
    ("argv", "needles"),
    [
        (["--kind", "castle"], ["unknown world kind 'castle'", "valid kinds:", KIND]),
        (["--kind", KIND, "--width", "-5"], ["--width", "'-5'"]),
        (["--kind", KIND, "--height", "nan"], ["--height", "'nan'"]),
        (["--kind", KIND, "--width", "abc"], ["--width", "'abc'"]),
        (["--kind", KIND, "--seed", "-1"], ["--seed", "'-1'"]),
        (["--kind", KIND, "--param", "door_width_min_m=-1"], ["door_width_min_m", "-1"]),
        (["--kind", KIND, "--param", "no_such_knob=1"], ["no_such_knob"]),
        (["--kind", KIND, "--param", "oops"], ["--param expects NAME=VALUE", "'oops'"]),
        (["--kind", KIND, "--param", "=3"], ["--param expects NAME=VALUE", "'=3'"]),
        (
            ["--kind", KIND, "--param", "triangulation.min_tracked=2"],
            ["'triangulation.min_tracked'", "not a world generator parameter", "--mapper"],
        ),
        (["--kind", KIND, "--param", "width_m=20", "--width", "20"], ["not both"]),
        (["--kind", KIND, "--tour-kind", "spiral"], ["--tour-kind 'spiral'", "loop"]),
        (["--kind", KIND, "--tour-length", "nan"], ["--tour-length"]),
        ([], ["give --kind KIND or --from-houseexpo"]),
    ],
)
def test_bad_input_one_line_no_file(tmp_path: Path, capsys, argv: list[str], needles) -> None:
    out, png = tmp_path / "w.json", tmp_path / "w.png"
    code, stdout, err = run_cli(capsys, *argv, "--out", str(out), "--png", str(png))
    assert_one_line_error(code, err, *needles)
    assert stdout == ""
    assert list(tmp_path.iterdir()) == []


def test_failed_png_leaves_no_json(tmp_path: Path, capsys) -> None:
    out = tmp_path / "w.json"
    png_dir = tmp_path / "taken.png"
    png_dir.mkdir()  # the PNG cannot replace a directory, so the whole write fails
    code, _, err = run_cli(capsys, "--kind", KIND, *SMALL, "--out", str(out), "--png", str(png_dir))
    assert_one_line_error(code, err, "taken.png")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["taken.png"]
    assert list(png_dir.iterdir()) == []


def test_missing_output_dir_names_the_file(tmp_path: Path, capsys) -> None:
    out = tmp_path / "nope" / "w.json"
    code, _, err = run_cli(capsys, "--kind", KIND, *SMALL, "--out", str(out))
    assert_one_line_error(code, err, str(out))


def test_existing_output_survives_an_error(tmp_path: Path, capsys) -> None:
    out = tmp_path / "w.json"
    out.write_text("keep me")
    code, _, _ = run_cli(capsys, "--kind", "castle", "--out", str(out))
    assert code == 2 and out.read_text() == "keep me"


def test_same_path_for_json_and_png(tmp_path: Path, capsys) -> None:
    out = tmp_path / "w.json"
    code, _, err = run_cli(capsys, "--kind", KIND, "--out", str(out), "--png", str(out))
    assert_one_line_error(code, err, "same file")
    assert list(tmp_path.iterdir()) == []


def test_from_houseexpo(tmp_path: Path, capsys) -> None:
    plan = tmp_path / "plan.json"
    plan.write_text(json.dumps(PLAN))
    out = tmp_path / "w.json"
    argv = ["--from-houseexpo", str(plan), "--param", "robot_radius_m=0.3", "--no-tour"]
    code, stdout, err = run_cli(capsys, *argv, "--out", str(out))
    assert code == 0, err
    world = load(out)
    assert world.kind == "houseexpo" and world.robot_radius_m == 0.3
    assert world.params == {"source": "plan.json", "id": "l-house"}
    assert stdout.startswith("houseexpo seed -: 8.0 x 8.0 m, 6 walls, 0 clutter")


@pytest.mark.parametrize(
    ("extra", "needles"),
    [
        (["--kind", KIND], ["not both"]),
        (["--width", "10"], ["--from-houseexpo takes only", "width_m"]),
        (["--param", "robot_radius_m=abc"], ["robot_radius_m", "number of metres", "'abc'"]),
        (["--param", "clearance_margin_m=true"], ["clearance_margin_m", "True"]),
        (["--param", "robot_radius_m=-1"], ["robot_radius_m must be > 0", "-1"]),
    ],
)
def test_from_houseexpo_rejects_generator_options(tmp_path: Path, capsys, extra, needles) -> None:
    plan = tmp_path / "plan.json"
    plan.write_text(json.dumps(PLAN))
    out = tmp_path / "w.json"
    code, _, err = run_cli(capsys, "--from-houseexpo", str(plan), *extra, "--out", str(out))
    assert_one_line_error(code, err, *needles)
    assert not out.exists()


def test_bad_houseexpo_file(tmp_path: Path, capsys) -> None:
    plan = tmp_path / "plan.json"
    plan.write_text('{"id": "x", "verts": [[0, 0], [1, 0]]}')
    code, _, err = run_cli(capsys, "--from-houseexpo", str(plan), "--out", str(tmp_path / "w"))
    assert_one_line_error(code, err, str(plan), "verts needs at least 3 distinct points")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["plan.json"]
