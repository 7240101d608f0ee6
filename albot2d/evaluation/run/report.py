"""report.json: the schema's header, plain-JSON conversion, atomic writing, reading back,
and the short tables printed at the end of a run (views of ``results.RunScores``).

Top level (see the README's "report.json" section): ``format``, ``format_version``,
``albot2d_version``, ``command`` (run/replay), ``seed``, ``world``, ``profile``, ``params``,
``run`` (what was driven or read), ``odometry`` (raw odometry's ``rpe``), ``mappers`` (name →
``counts``, ``homing``, ``rpe``, ``map``, ``timing_ms``, …), ``figures`` and ``wall_time_s``.
Missing values (anything needing the truth on a real log, NaN) are ``null``.
"""

from __future__ import annotations

import json
import os
from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

from albot2d import __version__
from albot2d.atomic import atomic_write_text
from albot2d.compiled import kernels
from albot2d.errors import InputError
from albot2d.plainjson import to_plain
from albot2d.validation import parse_json

if TYPE_CHECKING:
    from albot2d.evaluation.metrics.rpe import RPEResult
    from albot2d.evaluation.run.results import RunScores

__all__ = [
    "NONDETERMINISTIC_KEYS",
    "REPORT_FORMAT",
    "REPORT_FORMAT_VERSION",
    "REPORT_NAME",
    "format_homing_table",
    "format_summary_table",
    "make_report",
    "plain",
    "read_report",
    "report_json",
    "without_timings",
    "write_report",
]

REPORT_NAME = "report.json"
REPORT_FORMAT = "albot2d-report"
REPORT_FORMAT_VERSION = 1
# Wall-clock measurements: the only fields that differ between two runs of the same report.
NONDETERMINISTIC_KEYS = ("wall_time_s", "timing_ms")


def plain(value: Any) -> Any:
    """``value`` as JSON types (``plainjson.to_plain``); NaN/inf → None (``null``)."""
    return to_plain(value, where="report", into="report.json", nan_to_none=True)


def make_report(command: str, **sections: Any) -> dict[str, Any]:
    """A report dict: the header, then ``sections`` in the given order, as plain JSON."""
    head = {
        "format": REPORT_FORMAT,
        "format_version": REPORT_FORMAT_VERSION,
        "albot2d_version": __version__,
        "kernels": kernels(),
        "command": command,
    }
    return plain(head | sections)


def report_json(report: Mapping[str, Any]) -> str:
    return json.dumps(plain(report), indent=2, allow_nan=False) + "\n"


def write_report(path: str | os.PathLike[str], report: Mapping[str, Any]) -> None:
    """Write ``report`` atomically: the file appears complete or not at all."""
    atomic_write_text(path, report_json(report))


def read_report(path: str | os.PathLike[str]) -> dict[str, Any]:
    """Read a report.json written by ``albot2d run``/``replay`` (checks its format)."""
    with open(path, encoding="utf-8", errors="replace") as handle:
        report = parse_json(handle.read(), str(path))
    if not isinstance(report, dict) or report.get("format") != REPORT_FORMAT:
        raise InputError(f"{path}: not an albot2d report (format != {REPORT_FORMAT!r})")
    version = report.get("format_version")
    if version != REPORT_FORMAT_VERSION:
        raise InputError(
            f"{path}: report format_version {version!r}, this albot2d reads {REPORT_FORMAT_VERSION}"
        )
    return report


def without_timings(value: Any) -> Any:
    """A copy of a report without its wall-clock fields (to compare two runs)."""
    if isinstance(value, dict):
        return {k: without_timings(v) for k, v in value.items() if k not in NONDETERMINISTIC_KEYS}
    if isinstance(value, list):
        return [without_timings(v) for v in value]
    return value


# -- tables ---------------------------------------------------------------------------
def _num(value: Any, fmt: str) -> str:
    return "-" if value is None else format(value, fmt)


def _pm(mean: float | None, std: float | None, fmt: str) -> str:
    return "-" if mean is None else f"{mean:{fmt}}±{std:{fmt}}"


def _rpe_cells(rpe: RPEResult | None) -> list[str]:
    if rpe is None:
        return ["-"] * 5
    o, short, long = rpe.overall, rpe.short, rpe.long
    return [
        _pm(o.trans_m_mean, o.trans_m_std, ".3f"),
        _pm(o.rot_deg_mean, o.rot_deg_std, ".2f"),
        _pm(short.rot_deg_mean, short.rot_deg_std, ".2f"),
        _pm(long.trans_m_mean, long.trans_m_std, ".2f"),
        _pm(long.rot_deg_mean, long.rot_deg_std, ".1f"),
    ]


def _table(header: list[str], rows: list[list[str]]) -> str:
    widths = [max(len(r[i]) for r in [header, *rows]) for i in range(len(header))]
    lines = [
        "  ".join(
            c.ljust(w) if i == 0 else c.rjust(w)
            for i, (c, w) in enumerate(zip(r, widths, strict=True))
        )
        for r in [header, *rows]
    ]
    return "\n".join(lines)


def format_summary_table(scores: RunScores) -> str:
    """Two tables of one row per mapper (and raw odometry), each under 100 columns:
    accuracy (RPE overall/short/long, APE, worst homing error) and process/map quality."""
    header = [
        "",
        "RPE m",
        "RPE deg",
        "short deg",
        "long m",
        "long deg",
        "APE m",
        "home max°",
        "max m",
    ]
    odometry = scores.odometry
    ape = None if odometry.ape is None else odometry.ape.trans_m_rmse
    rows = [["odometry", *_rpe_cells(odometry.rpe), _num(ape, ".3f"), "", ""]]
    for name, m in scores.mappers.items():
        h = m.homing_summary
        rows.append([
            name, *_rpe_cells(m.rpe), _num(None if m.ape is None else m.ape.trans_m_rmse, ".3f"),
            _num(h.bearing_abs_max_deg, ".1f"), _num(h.distance_abs_max_m, ".2f"),
        ])  # fmt: skip
    header2 = [
        "",
        "views",
        "local maps",
        "triangulated",
        "integrated",
        "surfaces",
        "map acc m",
        "p95 m",
        "complete",
    ]
    rows2 = []
    for name, m in scores.mappers.items():
        c, q = m.counts, m.map.quality
        rows2.append([
            name, str(c.views), str(c.local_maps), str(c.triangulations),
            str(c.path_integrations), _num(c.global_map_surfaces, "d"),
            _num(q.accuracy_m_mean, ".3f"), _num(q.accuracy_m_p95, ".3f"),
            _num(q.completeness, ".2f"),
        ])  # fmt: skip
    return _table(header, rows) + "\n\n" + _table(header2, rows2)


def format_homing_table(scores: RunScores) -> str:
    """Per stop: distance travelled, true bearing/distance to the start, and each mapper's
    error (bearing °/distance m) when the truth is known, else its estimate."""
    mappers = scores.mappers
    names = list(mappers)
    if not names or not mappers[names[0]].homing:
        return "homing: no stops (the run never got far enough from its start)"
    known = mappers[names[0]].homing[0].homing.bearing_true_deg is not None
    header = ["stop", "view", "odo m"] + (["true °/m"] if known else [])
    header += [f"{n[:12]} {'Δ°/Δm' if known else '°/m'}" for n in names]
    rows = []
    for k, first in enumerate(mappers[names[0]].homing):
        row = [str(k + 1), str(first.homing.view), f"{first.travelled_m:.1f}"]
        if known:
            row.append(f"{first.homing.bearing_true_deg:+.1f}/{first.homing.distance_true_m:.1f}")
        for name in names:
            e = mappers[name].homing[k].homing
            if known and e.bearing_error_deg is not None:
                row.append(f"{e.bearing_error_deg:+.1f}/{e.distance_error_m:+.1f}")
            else:
                row.append(f"{e.bearing_est_deg:+.1f}/{e.distance_est_m:.1f}")
        rows.append(row)
    title = (
        "homing: error of each mapper's bearing/distance to the start (estimates in report.json)"
        if known
        else "homing: each mapper's bearing/distance to the start"
    )
    return title + "\n" + _table(header, rows)
