"""DIR/index.html of ``albot2d experiments``: one self-contained page a researcher opens.

For each experiment: the paper's claim in one sentence, a table of the paper's numbers
beside ours (mean ± sd over seeds), one row per measured thing and one named column per
quantity (the raw keys stay in experiments.json), the figures (PNG files beside the
page) with captions that say what is drawn and from which seeds, the verdict computed
from the numbers and the rule it was computed by. A ``--quick`` run is marked a smoke run
in a banner and beside every verdict. Plain HTML and inline CSS, no script and nothing
fetched from elsewhere.
"""

from __future__ import annotations

import html
import math
from collections.abc import Mapping
from typing import Any

__all__ = ["PAGE_NAME", "flatten_numbers", "render_page"]

PAGE_NAME = "index.html"
_VERDICT_CLASS = {"reproduced": "ok", "partly": "partly", "not reproduced": "no"}
_CSS = """
body { font-family: system-ui, sans-serif; max-width: 72rem; margin: 2rem auto; padding: 0 1rem;
       color: #222; }
h1 { font-size: 1.5rem; } h2 { font-size: 1.2rem; margin-top: 2.5rem; }
table { border-collapse: collapse; margin: .8rem 0; font-size: .85rem; }
th, td { border: 1px solid #ccc; padding: .25rem .5rem; text-align: left; }
th { background: #f3f3f3; }
td.num { text-align: right; font-variant-numeric: tabular-nums; }
.verdict { font-weight: bold; padding: .15rem .5rem; border-radius: .3rem; }
.ok { background: #d6f5d6; } .partly { background: #fff0c2; } .no { background: #f8d0d0; }
figure { margin: 1rem 0; } figure img { max-width: 100%; border: 1px solid #ddd; }
figcaption { font-size: .85rem; color: #555; }
.rule { font-size: .85rem; color: #555; }
.smoke { background: #fff3cd; border: 2px solid #e0a800; padding: .6rem 1rem;
         border-radius: .4rem; font-size: 1rem; }
.smoke-tag { font-size: .8rem; color: #8a6d00; font-weight: bold; margin-left: .4rem; }
.numbers td.who { color: #555; font-size: .8rem; }
.table-wrap { overflow-x: auto; max-width: 100%; }
"""
SMOKE_RUN = "smoke run"
# figure kinds drawn from every seed; the others are drawn from the figure seed only
_ALL_SEED_PLOTS = ("bars", "homing")


def _fmt(value: Any) -> str:
    if value is None:
        return "–"
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if not math.isfinite(value):
            return "–"
        return f"{value:.3g}" if abs(value) < 1000 else f"{value:.0f}"
    return str(value)


def _is_stat(value: Any) -> bool:
    return isinstance(value, Mapping) and "mean" in value and "per_seed" in value


def flatten_numbers(tree: Any, prefix: str = "") -> dict[str, str]:
    """Dotted path → formatted value for every number in ``tree`` (mean ± sd for a
    statistic over seeds); lists and per-seed tables are left out."""
    out: dict[str, str] = {}
    if _is_stat(tree):
        mean, sd = tree["mean"], tree["sd"]
        out[prefix] = _fmt(mean) if not sd else f"{_fmt(mean)} ± {_fmt(sd)}"
        return out
    if isinstance(tree, Mapping):
        for key, value in tree.items():
            out |= flatten_numbers(value, f"{prefix}.{key}" if prefix else str(key))
        return out
    if isinstance(tree, bool | int | float) or tree is None:
        out[prefix] = _fmt(tree)
    elif isinstance(tree, str) and prefix:
        out[prefix] = tree
    return out


_UNITS = (("_m", " (m)"), ("_deg", " (°)"), ("_s", " (s)"), ("_mps", " (m/s)"))


def human(key: str) -> str:
    """A raw key as a reader's name: ``map_accuracy_p95_m`` → ``map accuracy p95 (m)``."""
    for suffix, unit in _UNITS:
        if key.endswith(suffix) and len(key) > len(suffix):
            return key[: -len(suffix)].replace("_", " ") + unit
    return key.replace("_", " ")


def _split(key: str) -> tuple[str, str]:
    """A dotted key as (row, column): the last part names the column."""
    row, _, col = key.rpartition(".")
    return (row, col) if row else ("", col)


def _table(result: Mapping[str, Any], ours_label: str) -> str:
    """The paper's numbers beside ours: a row per measured thing (``dataset1``,
    ``corridor``, ...), a named column per quantity, each row twice (paper, albot2d);
    rows measuring different quantities go to separate tables, so no table is mostly
    empty cells."""
    ours = flatten_numbers(result.get("ours", {}))
    paper = flatten_numbers({k: v for k, v in result.get("paper", {}).items() if k != "rows"})
    rows: dict[str, dict[str, dict[str, str]]] = {}
    for who, values in (("paper", paper), ("albot2d", ours)):
        for key, value in values.items():
            row, col = _split(key)
            rows.setdefault(row, {}).setdefault(who, {})[col] = value
    groups: dict[tuple[str, ...], list[str]] = {}
    for row, by_who in rows.items():
        cols = tuple(dict.fromkeys(c for who in ("paper", "albot2d")
                                   for c in by_who.get(who, {})))  # fmt: skip
        groups.setdefault(cols, []).append(row)
    tables = []
    for columns, names in groups.items():
        head = "".join(f"<th>{html.escape(human(c))}</th>" for c in columns)
        body = []
        for row in names:
            by_who = rows[row]
            name = " / ".join(human(part) for part in row.split(".")) if row else "—"
            present = [w for w in ("paper", "albot2d") if w in by_who]
            for k, who in enumerate(present):
                first = (f"<td rowspan='{len(present)}'>{html.escape(name)}</td>" if k == 0
                         else "")  # fmt: skip
                cells = "".join(
                    f"<td class='num'>{html.escape(by_who[who].get(c, ''))}</td>" for c in columns
                )
                body.append(f"<tr>{first}<td class='who'>{who}</td>{cells}</tr>")
        tables.append(f"<div class='table-wrap'><table class='numbers'><tr><th></th><th></th>"
                      f"{head}</tr>{''.join(body)}</table></div>")  # fmt: skip
    note = f"<p class='rule'>albot2d: {html.escape(ours_label.removeprefix('albot2d, '))}.</p>"
    return note + "".join(tables)


def _per_seed(result: Mapping[str, Any], seeds: list[int]) -> str:
    stats: dict[str, Mapping[str, Any]] = {}

    def walk(tree: Any, prefix: str) -> None:
        if _is_stat(tree):
            stats[prefix] = tree["per_seed"]
        elif isinstance(tree, Mapping):
            for k, v in tree.items():
                walk(v, f"{prefix}.{k}" if prefix else str(k))

    walk(result.get("ours", {}), "")
    if not stats:
        return ""
    head = "".join(f"<th>{s}</th>" for s in seeds)
    rows = "".join(
        f"<tr><td>{html.escape(k)}</td>"
        + "".join(f"<td class='num'>{_fmt(v.get(str(s)))}</td>" for s in seeds) + "</tr>"
        for k, v in stats.items()
    )  # fmt: skip
    return (f"<details><summary>per seed</summary><div class='table-wrap'><table "
            f"class='per-seed'><tr><th>quantity</th>{head}</tr>{rows}</table></div>"
            "</details>")  # fmt: skip


def _paper_rows(result: Mapping[str, Any]) -> str:
    rows = result.get("paper", {}).get("rows")
    if not rows:
        return ""
    body = "".join(
        f"<tr><td>{k + 1}</td><td class='num'>{r['albot1'][0]:+.1f}° / {r['albot1'][1]:.1f} m"
        f"</td><td class='num'>{r['physical'][0]:+.1f}° / {r['physical'][1]:.1f} m</td></tr>"
        for k, r in enumerate(rows)
    )
    return ("<table class='paper-rows'><tr><th>paper's stop</th><th>Albot₁'s map</th>"
            f"<th>physical map</th></tr>{body}</table>")  # fmt: skip


def render_page(data: Mapping[str, Any], figures: Mapping[str, list[dict[str, Any]]]) -> str:
    """The page for experiments.json's ``data`` and the figures written beside it
    (per experiment: ``{"file", "caption"}``)."""
    seeds = list(data["seeds"])
    quick = bool(data.get("quick"))
    smoke_tag = f"<span class='smoke-tag'>({SMOKE_RUN})</span>" if quick else ""
    ours_label = (
        f"albot2d, mean ± sd over {len(seeds)} seeds"
        if len(seeds) > 1
        else f"albot2d, seed {seeds[0]}"
    )
    parts = [
        "<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'>",
        "<title>albot2d experiments: the paper's experiments regenerated</title>",
        f"<style>{_CSS}</style></head><body>",
        "<h1>The paper's experiments regenerated with albot2d</h1>",
        (f"<p class='smoke' id='smoke-banner'><strong>A {SMOKE_RUN} (--quick):</strong> "
         f"seeds {html.escape(_seed_text(seeds))}, the long runs cut short; the numbers and "
         "verdicts below only show that everything runs and are not comparable to the "
         "paper's. Run <code>albot2d experiments</code> without --quick for them.</p>"
         if quick else ""),
        "<p>Yeap et al., <em>What is a cognitive map? Unravelling its mystery using robots"
        "</em>: each claim beside the same measurement on simulated runs. "
        f"Seeds {html.escape(_seed_text(seeds))}; odometry noise "
        f"<code>{html.escape(str(data['odometry_noise']))}</code>; Albot_x: "
        f"<code>{html.escape(str(data['albot_x'] or 'not available (naive instead)'))}"
        "</code>" + ("; <strong>--quick</strong>: a smoke run, long runs cut short, "
                     "numbers not comparable to the paper's" if data.get("quick") else "")
        + ". Verdicts are computed from the numbers by the rule under each one.</p>",
        "<table class='summary'><tr><th>experiment</th><th>verdict</th></tr>",
    ]  # fmt: skip
    for name, verdict in data["verdicts"].items():
        cls = _VERDICT_CLASS.get(verdict, "")
        parts.append(
            f"<tr><td><a href='#{name}'>{name}</a></td>"
            f"<td><span class='verdict {cls}'>{html.escape(verdict)}</span>{smoke_tag}</td></tr>"
        )
    parts.append("</table>")
    for name, result in data["experiments"].items():
        cls = _VERDICT_CLASS.get(result["verdict"], "")
        parts += [
            f"<section id='{name}'><h2>{html.escape(name)}</h2>",
            f"<p class='claim'><strong>The paper:</strong> {html.escape(result['claim'])}</p>",
            f"<p>Verdict: <span class='verdict {cls}'>{html.escape(result['verdict'])}</span>"
            f"{smoke_tag}</p><p class='rule'>Rule: {html.escape(result['rule'])}.</p>",
            *(f"<p class='note'><strong>Why:</strong> {html.escape(str(n))}</p>"
              for n in result.get("notes", [])),
            _paper_rows(result), _table(result, ours_label), _per_seed(result, seeds),
        ]  # fmt: skip
        for fig in figures.get(name, []):
            scope = (
                f"All {len(seeds)} seeds." if fig.get("plot") in _ALL_SEED_PLOTS and
                len(seeds) > 1 else f"Seed {result.get('figure_seed')}."
            )  # fmt: skip
            tag = f" ({SMOKE_RUN}: runs cut short.)" if quick else ""
            parts.append(
                f"<figure><img src='{html.escape(fig['file'])}' alt='{html.escape(name)} "
                f"figure'><figcaption>{html.escape(fig['caption'])} {scope}{tag}"
                "</figcaption></figure>"
            )
        parts.append("</section>")
    parts.append("</body></html>\n")
    return "\n".join(parts)


def _seed_text(seeds: list[int]) -> str:
    if seeds == list(range(seeds[0], seeds[-1] + 1)) and len(seeds) > 2:
        return f"{seeds[0]}–{seeds[-1]}"
    return ", ".join(map(str, seeds))
