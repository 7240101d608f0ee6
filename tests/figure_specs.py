"""Small, deterministic inputs for every figure family (shared by the visual regression
tests and the browser test): a short simulated run and plain data for each kind of
``albot2d experiments`` figure."""

from __future__ import annotations

from typing import Any

import numpy as np

RUN_FRAMES = 300


def small_run() -> Any:
    """A short default run (office seed 0, albot1 and naive), scored: deterministic."""
    from albot2d.evaluation import EvaluationParams, RunSpec, run_experiment

    spec = RunSpec(max_frames=RUN_FRAMES, mappers=("albot1", "naive"))
    return run_experiment(spec, EvaluationParams())


def fixed_step_times() -> dict[str, np.ndarray]:
    """steps.csv-like columns with fixed times (real ones are wall-clock, never equal)."""
    rng = np.random.default_rng(0)
    n = 400
    out = {
        "simulation_ms": 0.08 + 0.01 * rng.random(n),
        "extraction_ms": 0.03 + 0.005 * rng.random(n),
        "albot1.total_ms": 0.1 + 0.05 * rng.random(n),
        "naive.total_ms": 0.05 + 0.01 * rng.random(n),
        "albot1.remembered": (np.arange(n) % 9 == 0).astype(float),
    }
    out["albot1.total_ms"][::50] += 4.0  # rare slow views
    out["simulation_ms"][0] = 900.0  # start-up
    return out


def _square_walls() -> np.ndarray:
    return np.array([[0, 0, 10, 0], [10, 0, 10, 8], [10, 8, 0, 8], [0, 8, 0, 0],
                     [4, 0, 4, 5]], float)  # fmt: skip


def paper_specs() -> list[dict[str, Any]]:
    """One spec of each ``albot2d.viz.paper.PLOTS`` kind, plain data."""
    walls = _square_walls()
    path = np.array([[1.0, 1.0], [2.0, 6.0], [7.0, 6.0], [8.0, 2.0]])
    panel = {"title": "(a) Albot₁ at E5", "walls": walls, "segments": walls[:3] + 0.1,
             "deleted": walls[3:4] + 0.2, "path": path, "marks": {"S": (1.0, 1.0)}}  # fmt: skip
    rng = np.random.default_rng(1)
    xy = np.column_stack([np.linspace(1, 9, 30), np.full(30, 6.0)])
    return [
        {"file": "maps.png", "plot": "maps", "caption": "maps",
         "data": {"panels": [panel, dict(panel, title="(b) naive at E5", deleted=None)]}},
        {"file": "bars.png", "plot": "bars", "caption": "bars",
         "data": {"bars": [{"label": "dataset1", "ours": 0.4, "sd": 0.1, "paper": 0.39},
                           {"label": "dataset3", "ours": 0.7, "sd": 0.05, "paper": 0.61}],
                  "ylabel": "local maps per view"}},
        {"file": "homing.png", "plot": "homing", "caption": "homing",
         "data": {"bearing_error_deg": rng.normal(0, 3, 20).tolist(),
                  "distance_error_m": rng.normal(0, 1, 20).tolist(),
                  "direction": ["clockwise", "anticlockwise"] * 10, "bound": [7.0, 3.0]}},
        {"file": "updates.png", "plot": "updates", "caption": "updates",
         "data": {"walls": walls, "xy": xy, "flags": (np.arange(30) % 3 == 0).tolist(),
                  "regions": ["corridor"] * 15 + ["hall"] * 15}},
        {"file": "sequence.png", "plot": "sequence", "caption": "sequence",
         "data": {"walls": walls, "poses": np.array([[2, 2, 0.0], [3, 2, 0.5]]),
                  "rows": [5, 6], "methods": ["triangulation", "path_integration"],
                  "tracked": [2, 0], "views": [walls[:2] - 2, walls[1:3] - 4],
                  "maps": [walls, walls], "map_poses": [[2, 2, 0.0], [3, 2, 0.5]]}},
    ]  # fmt: skip
