"""The limits on input: one module, the table in docs/limits.md generated from it, the same
constants wherever a limit is enforced, and plugins that fail cleanly in-process."""

from __future__ import annotations

import os
import sys
import textwrap
from pathlib import Path

import pytest

from albot2d import limits
from albot2d.errors import InputError
from albot2d.inputfiles import binary_lines, read_limited
from albot2d.mapping.registry import mapper_factory
from albot2d.plugins import PLUGINS_ENV, plugin_locations

ROOT = Path(__file__).resolve().parents[1]


def test_docs_limits_md_is_generated_from_the_module() -> None:
    """Regenerate with ``python -m albot2d.limits --write docs/limits.md``."""
    assert (ROOT / "docs" / "limits.md").read_text() == limits.limits_markdown()


def test_every_limit_is_in_the_table_and_used_where_it_is_enforced() -> None:
    from albot2d import validation
    from albot2d.evaluation.fuzz import backends, campaign
    from albot2d.logs import carmen
    from worldgen import io, params, world_checks

    names = {limit.name for limit in limits.LIMITS}
    assert names == {n for n in limits.__all__ if n.isupper() and n != "LIMITS"}
    for limit in limits.LIMITS:
        assert getattr(limits, limit.name) == limit.value
    assert validation.COORDINATE_LIMIT_M is limits.COORDINATE_LIMIT_M
    assert carmen.MAX_BEAMS is limits.MAX_BEAMS
    assert world_checks.MAX_WALLS is limits.MAX_WALLS
    assert params.MAX_WORLD_SIZE_M is limits.MAX_WORLD_SIZE_M
    assert params.MAX_DYNAMIC_OBSTACLES is limits.MAX_DYNAMIC_OBSTACLES
    assert io.MAX_WORLD_FILE_BYTES is limits.MAX_WORLD_FILE_BYTES
    assert campaign.MAX_TOUR_LENGTH_M is limits.MAX_TOUR_LENGTH_M
    assert backends.MAX_LOCAL_WORKERS is limits.MAX_LOCAL_WORKERS
    assert validation.MAX_SEEDS is limits.MAX_SEEDS  # parse_seed_list, for every --seeds


def test_bounded_reads(tmp_path: Path) -> None:
    path = tmp_path / "f"
    path.write_bytes(b"a\n" * 10)
    assert read_limited(path, 20, "file", "X") == b"a\n" * 10
    with pytest.raises(InputError, match=r"f: file larger than the limit of 19 bytes \(X\)"):
        read_limited(path, 19, "file", "X")
    with open(path, "rb") as handle:
        assert list(binary_lines(handle, "f", max_line_bytes=1)) == [b"a\n"] * 10
    with open(path, "rb") as handle, pytest.raises(InputError, match="f: more than 9 bytes"):
        list(binary_lines(handle, "f", max_total_bytes=9))
    path.write_bytes(b"ab\n")
    with open(path, "rb") as handle, pytest.raises(InputError, match="f:1: line longer"):
        list(binary_lines(handle, "f", max_line_bytes=1))


PLUGIN = """
from albot2d.mapping.baselines import NaiveIntegration

class Here(NaiveIntegration):
    name = "here"
"""


def test_a_plugin_in_the_current_folder_is_imported_by_location(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Found in the current folder without putting it on sys.path; its folder recorded for
    worker processes in ALBOT2D_PLUGINS."""
    (tmp_path / "cwd_plugin_xyz.py").write_text(textwrap.dedent(PLUGIN))
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv(PLUGINS_ENV, raising=False)
    path_before = list(sys.path)
    try:
        factory = mapper_factory("cwd_plugin_xyz:Here")
        assert factory().name == "here"
        assert sys.path == path_before
        assert plugin_locations() == {"cwd_plugin_xyz": str(tmp_path)}
        assert os.environ[PLUGINS_ENV]
    finally:
        sys.modules.pop("cwd_plugin_xyz", None)


@pytest.mark.parametrize(
    "value",
    ["{", "[1]", '{"a": 1}', '{"a b": "/x"}', '{"m": "relative/dir"}', "[" * 100_000],
)
def test_a_bad_plugins_variable_is_one_error(monkeypatch: pytest.MonkeyPatch, value: str) -> None:
    monkeypatch.setenv(PLUGINS_ENV, value)
    with pytest.raises(InputError, match=PLUGINS_ENV):
        plugin_locations()


@pytest.mark.parametrize(
    ("body", "message"),
    [
        ("raise KeyError('x')", "importing module 'bad_plugin_xyz' failed: KeyError"),
        ("import sys; sys.exit('bye')", r"SystemExit\('bye'\)"),
        ("raise ImportError('needs torch')", "cannot import module 'bad_plugin_xyz'"),
        ("x = 1/0", "ZeroDivisionError"),
    ],
)
def test_a_plugin_failing_at_import_is_one_error(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, body: str, message: str
) -> None:
    (tmp_path / "bad_plugin_xyz.py").write_text(body + "\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    try:
        with pytest.raises(InputError, match=message) as info:
            mapper_factory("bad_plugin_xyz:Mapper")
        assert "\n" not in str(info.value) and "mapper 'bad_plugin_xyz:Mapper'" in str(info.value)
    finally:
        sys.modules.pop("bad_plugin_xyz", None)


def test_map_server_maps_are_read_within_limits(tmp_path: Path) -> None:
    """A map YAML of /dev/zero, one with an alias bomb, and an image of too many pixels
    (refused from its header, before it is decoded) are each one ``InputError``."""
    pytest.importorskip("yaml")
    image_module = pytest.importorskip("PIL.Image")
    from albot2d.logs.map_server import read_map_server

    with pytest.raises(InputError, match="MAX_MAP_YAML_BYTES"):
        read_map_server("/dev/zero")
    bomb = tmp_path / "bomb.yaml"
    lines = ["a0: &a0 [x, x, x, x, x, x, x, x, x, x]"]
    lines += [f"a{k}: &a{k} [{', '.join([f'*a{k - 1}'] * 10)}]" for k in range(1, 12)]
    bomb.write_text("\n".join([*lines, "image: m.png", "resolution: 0.05", "origin: *a11"]))
    with pytest.raises(InputError, match="aliases"):
        read_map_server(bomb)
    image_module.new("L", (6000, 5000), 254).save(tmp_path / "big.png")
    big = tmp_path / "big.yaml"
    big.write_text("image: big.png\nresolution: 0.05\norigin: [0, 0, 0]\n")
    with pytest.raises(InputError, match=r"6000 x 5000 pixels.*MAX_MAP_PIXELS"):
        read_map_server(big)
