"""The ``albot2d`` command itself: --version, bare help, clean help texts, required options."""

from __future__ import annotations

import pytest

from albot2d import __version__
from albot2d.cli import build_parser, main

COMMANDS = ["world", "simulate", "run", "replay", "fuzz"]


def test_version(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["--version"]) == 0
    assert capsys.readouterr().out.strip() == f"albot2d {__version__}"


def test_bare_albot2d_prints_help(capsys: pytest.CaptureFixture[str]) -> None:
    assert main([]) == 0
    out = capsys.readouterr().out
    assert out.startswith("usage: albot2d")
    for command in COMMANDS:
        assert command in out


@pytest.mark.parametrize("command", COMMANDS)
def test_help_texts_are_plain_and_show_required_options(
    command: str, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main([command, "--help"]) == 0
    out = capsys.readouterr().out
    assert "``" not in out
    usage = " ".join(out.split("\n\n")[0].split())
    # A required option appears in the usage line without brackets.
    assert " --out " in usage + " " and "[--out" not in usage
    if command == "fuzz":
        assert "[--episodes" not in usage and "--episodes N" in usage


def test_usage_errors_are_one_line_exit_2(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["run", "--no-such-option", "--out", "x"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "unrecognized arguments: --no-such-option" in err
    assert main(["fuzz", "--out", "x"]) == 2
    assert "required: --episodes" in capsys.readouterr().err


def test_run_and_simulate_share_their_world_and_driving_options() -> None:
    parser = build_parser()
    run = vars(parser.parse_args(["run", "--out", "x"]))
    simulate = vars(parser.parse_args(["simulate", "--out", "x"]))
    shared = {
        "world",
        "kind",
        "seed",
        "width",
        "height",
        "param",
        "profile",
        "noise",
        "laser_noise",
        "tour_kind",
        "tour_length",
        "max_frames",
    }
    assert shared <= set(run) and shared <= set(simulate)
    assert {k: run[k] for k in shared} == {k: simulate[k] for k in shared}


def test_an_interrupt_inside_a_compiled_kernel_is_an_interrupt(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """SIGTERM or Ctrl-C arriving while numba's dispatcher runs Python code comes out as a
    ``SystemError`` caused by the ``KeyboardInterrupt``: still exit 130 and one line. A
    ``SystemError`` of another cause stays an error."""
    import albot2d.cli.world_cmd as world_cmd

    def interrupted_in_a_kernel(args: object) -> int:
        try:
            raise KeyboardInterrupt
        except KeyboardInterrupt as exc:
            raise SystemError("CPUDispatcher returned a result with an exception set") from exc

    monkeypatch.setattr(world_cmd, "run", interrupted_in_a_kernel)
    assert main(["world", "--kind", "rooms", "--out", "w.json"]) == 130
    assert capsys.readouterr().err == "albot2d world: interrupted\n"

    def broken(args: object) -> int:
        raise SystemError("a real bug")

    monkeypatch.setattr(world_cmd, "run", broken)
    with pytest.raises(SystemError, match="a real bug"):
        main(["world", "--kind", "rooms", "--out", "w.json"])
