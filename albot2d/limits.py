"""Every limit on input in one place: the memory and work budget each reader and command keeps.

Readers stream and count as they read (lines, bytes after decompression, scans, readings,
vertices, walls after de-duplication) and refuse an input past one of these limits with one
line naming the file and the limit, before materialising what they are about to refuse.
Modules that enforce a limit import it from here (the older names, e.g.
``albot2d.validation.COORDINATE_LIMIT_M`` or ``worldgen.world_checks.MAX_WALLS``, are the
same objects). :data:`LIMITS` describes each for people; ``python -m albot2d.limits``
prints it as the Markdown table of ``docs/limits.md`` (``--write docs/limits.md`` rewrites
that file; a test checks it is current).
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import NamedTuple

__all__ = [
    "COORDINATE_LIMIT_M",
    "LIMITS",
    "MAX_ARRAY_DIMENSIONS",
    "MAX_ARRAY_ITEMS",
    "MAX_BAG_MESSAGES",
    "MAX_BEAMS",
    "MAX_CAMPAIGN_EPISODES",
    "MAX_CLUTTER_ITEMS",
    "MAX_DYNAMIC_OBSTACLES",
    "MAX_EPISODE_RECORD_BYTES",
    "MAX_HOUSEEXPO_VERTICES",
    "MAX_JSON_DEPTH",
    "MAX_JSON_FILE_BYTES",
    "MAX_LINE_BYTES",
    "MAX_LOCAL_WORKERS",
    "MAX_LOG_READINGS",
    "MAX_LOG_SCANS",
    "MAX_MAP_PIXELS",
    "MAX_MAP_YAML_BYTES",
    "MAX_PATH_POINTS",
    "MAX_ROADMAP_NODES",
    "MAX_SEEDS",
    "MAX_TABLE_ROWS",
    "MAX_TEXT_BYTES",
    "MAX_TOTAL_WALL_LENGTH_M",
    "MAX_TOUR_LENGTH_M",
    "MAX_WALLS",
    "MAX_WORLD_FILE_BYTES",
    "MAX_WORLD_SIZE_M",
    "Limit",
    "limits_markdown",
]

MiB = 1024 * 1024

# -- every input -----------------------------------------------------------------------
#: Largest magnitude of any coordinate or size in metres an input may hold (±1000 km).
COORDINATE_LIMIT_M = 1e6
#: Arrays and objects in a JSON input may nest at most this deep (albot2d's files need ~8).
MAX_JSON_DEPTH = 64
#: A JSON input (report, reproducer, HouseExpo plan, campaign.json, run.json) at most.
MAX_JSON_FILE_BYTES = 64 * MiB
#: A world file at most (the largest generated worlds are a few MB).
MAX_WORLD_FILE_BYTES = 64 * MiB

# -- text logs (CARMEN logs, relations, truth files; plain or gzip) -----------------------
#: Bytes of a text input after decompression.
MAX_TEXT_BYTES = 512 * MiB
#: Bytes of one line (a ROBOTLASER1 line of 65,536 readings and remissions is ~1.3 MB).
MAX_LINE_BYTES = 2 * MiB
#: Most readings (or remissions) one laser line may hold (a 0.01° sweep of 360° is 36,000).
MAX_BEAMS = 65_536
#: Laser scans one log may hold (the longest public CARMEN logs have ~20,000).
MAX_LOG_SCANS = 100_000
#: Laser readings one log may hold in all (8 bytes each as float64: 320 MB).
MAX_LOG_READINGS = 40_000_000
#: Messages read from one topic of a ROS bag (odometry and /tf arrive at up to ~100 Hz).
MAX_BAG_MESSAGES = 2_000_000
#: Rows of a relations or truth file.
MAX_TABLE_ROWS = 2_000_000

#: A ROS map_server map's YAML file.
MAX_MAP_YAML_BYTES = 1 * MiB
#: Pixels of a map_server map's image (5000 x 5000; decoded as 32 bytes a pixel).
MAX_MAP_PIXELS = 25_000_000

# -- worlds and plans --------------------------------------------------------------------
#: Walls of a world (a wall that repeats another exactly is refused, whatever the count).
MAX_WALLS = 500_000
#: Length of all walls of a world together, in metres (raycasting work grows with it).
MAX_TOTAL_WALL_LENGTH_M = 500_000.0
MAX_CLUTTER_ITEMS = 100_000
MAX_ROADMAP_NODES = 200_000
#: Points of a moving obstacle's path.
MAX_PATH_POINTS = 10_000
#: Moving obstacles of a world (each is simulated in the physics engine).
MAX_DYNAMIC_OBSTACLES = 200
#: Largest width or height of a generated world, or span of a HouseExpo plan, in metres.
MAX_WORLD_SIZE_M = 500.0
#: Vertices of a HouseExpo plan (the real plans have at most a few hundred).
MAX_HOUSEEXPO_VERTICES = 5_000
#: Items of an array stored in a world file's params or features.
MAX_ARRAY_ITEMS = 10_000_000
#: Dimensions of such an array.
MAX_ARRAY_DIMENSIONS = 8

# -- commands ------------------------------------------------------------------------------
#: Episodes of a fuzz campaign (every record is held to write the summary).
MAX_CAMPAIGN_EPISODES = 100_000
#: Bytes of one line of a campaign's episodes.jsonl.
MAX_EPISODE_RECORD_BYTES = 1 * MiB
#: The longest tour an episode may drive (a 100 km tour takes hours per episode).
MAX_TOUR_LENGTH_M = 100_000.0
#: Local worker processes (more only thrash one machine; each holds ~200 MB).
MAX_LOCAL_WORKERS = 256
#: Seeds of one ``albot2d experiments`` run.
MAX_SEEDS = 10_000


class Limit(NamedTuple):
    """One documented limit: its name here, value, unit and what it bounds."""

    name: str
    value: float
    unit: str
    bounds: str


LIMITS: tuple[Limit, ...] = (
    Limit("COORDINATE_LIMIT_M", COORDINATE_LIMIT_M, "m", "any coordinate or size in any input"),
    Limit("MAX_JSON_DEPTH", MAX_JSON_DEPTH, "levels", "nesting of any JSON input"),
    Limit(
        "MAX_JSON_FILE_BYTES",
        MAX_JSON_FILE_BYTES,
        "bytes",
        "a report, reproducer, HouseExpo plan, campaign.json or run.json",
    ),
    Limit("MAX_WORLD_FILE_BYTES", MAX_WORLD_FILE_BYTES, "bytes", "a world file"),
    Limit(
        "MAX_TEXT_BYTES",
        MAX_TEXT_BYTES,
        "bytes",
        "a CARMEN log, relations or truth file after gzip decompression",
    ),
    Limit("MAX_LINE_BYTES", MAX_LINE_BYTES, "bytes", "one line of a log, relations or truth file"),
    Limit("MAX_BEAMS", MAX_BEAMS, "readings", "one laser line (readings, and remissions)"),
    Limit("MAX_LOG_SCANS", MAX_LOG_SCANS, "scans", "laser scans of one log or bag"),
    Limit("MAX_LOG_READINGS", MAX_LOG_READINGS, "readings", "laser readings of one log in all"),
    Limit("MAX_BAG_MESSAGES", MAX_BAG_MESSAGES, "messages", "one topic of a ROS bag"),
    Limit("MAX_MAP_YAML_BYTES", MAX_MAP_YAML_BYTES, "bytes", "a map_server map's YAML file"),
    Limit("MAX_MAP_PIXELS", MAX_MAP_PIXELS, "pixels", "a map_server map's image"),
    Limit("MAX_TABLE_ROWS", MAX_TABLE_ROWS, "rows", "a relations or truth file"),
    Limit("MAX_WALLS", MAX_WALLS, "walls", "a world's walls (exact repeats of a wall are refused)"),
    Limit(
        "MAX_TOTAL_WALL_LENGTH_M",
        MAX_TOTAL_WALL_LENGTH_M,
        "m",
        "the length of a world's walls together",
    ),
    Limit("MAX_CLUTTER_ITEMS", MAX_CLUTTER_ITEMS, "polygons", "a world's clutter"),
    Limit("MAX_ROADMAP_NODES", MAX_ROADMAP_NODES, "nodes", "a world's roadmap"),
    Limit("MAX_PATH_POINTS", MAX_PATH_POINTS, "points", "a moving obstacle's path"),
    Limit(
        "MAX_DYNAMIC_OBSTACLES", MAX_DYNAMIC_OBSTACLES, "obstacles", "a world's moving obstacles"
    ),
    Limit(
        "MAX_WORLD_SIZE_M",
        MAX_WORLD_SIZE_M,
        "m",
        "a generated world's width or height; a HouseExpo plan's span",
    ),
    Limit("MAX_HOUSEEXPO_VERTICES", MAX_HOUSEEXPO_VERTICES, "vertices", "a HouseExpo plan"),
    Limit("MAX_ARRAY_ITEMS", MAX_ARRAY_ITEMS, "items", "an array in a world file's params"),
    Limit("MAX_ARRAY_DIMENSIONS", MAX_ARRAY_DIMENSIONS, "dimensions", "such an array"),
    Limit("MAX_CAMPAIGN_EPISODES", MAX_CAMPAIGN_EPISODES, "episodes", "a fuzz campaign"),
    Limit(
        "MAX_EPISODE_RECORD_BYTES",
        MAX_EPISODE_RECORD_BYTES,
        "bytes",
        "one line of a campaign's episodes.jsonl",
    ),
    Limit("MAX_TOUR_LENGTH_M", MAX_TOUR_LENGTH_M, "m", "a fuzz episode's tour"),
    Limit("MAX_LOCAL_WORKERS", MAX_LOCAL_WORKERS, "processes", "--workers on one machine"),
    Limit("MAX_SEEDS", MAX_SEEDS, "seeds", "one `albot2d experiments` run"),
)


def _value(limit: Limit) -> str:
    v = limit.value
    if limit.unit == "bytes" and v >= MiB:
        return f"{v / MiB:g} MiB"
    if float(v).is_integer():
        return f"{int(v):,}"
    return f"{v:g}"


def limits_markdown() -> str:
    """``docs/limits.md``: the table of :data:`LIMITS`."""
    lines = [
        "# Limits on input",
        "",
        "<!-- generated by `python -m albot2d.limits --write docs/limits.md`; do not edit -->",
        "",
        "Every input albot2d reads (files, folders, options, environment, plugins) is",
        "untrusted. Readers stream and count as they read and refuse an input past one of",
        "these limits with one line naming the file (and line or field) and the limit, exit",
        "code 2, no traceback and nothing written; corrupt gzip data is refused the same way.",
        "The values are the constants of `albot2d.limits`.",
        "",
        "| limit | value | unit | bounds |",
        "|---|---:|---|---|",
    ]
    for limit in LIMITS:
        lines.append(f"| `{limit.name}` | {_value(limit)} | {limit.unit} | {limit.bounds} |")
    lines += [
        "",
        "Besides these, every number must be finite; world files must be drivable (a wall of",
        "positive length; the start disc in free space, clear of walls, clutter and every",
        "moving obstacle's outline; a roadmap whose nodes and edges fit the robot's disc, clear",
        "of static obstacles, reaching the start); moving obstacles have an area of at least",
        "1e-4 m², a speed of at most 5 m/s and a mass of at most 10,000 kg. A `module:Class`",
        "mapper that fails to import or to construct (any exception, `SystemExit` included) is",
        "refused in one line naming it; `MPLBACKEND` and `ALBOT2D_DATA` are checked before use.",
        "",
    ]
    return "\n".join(lines)


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m albot2d.limits", description="Print or write docs/limits.md."
    )
    parser.add_argument("--write", metavar="FILE", help="write the table to FILE")
    args = parser.parse_args(argv)
    text = limits_markdown()
    if args.write:
        Path(args.write).write_text(text, encoding="utf-8")
    else:
        sys.stdout.write(text)
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
