"""The named experiments, in the order of the paper, and the runs each one needs."""

from __future__ import annotations

from albot2d.evaluation.paper import counts, table1
from albot2d.evaluation.paper.maps_exp import FIG7, FIG10, FIG11_12, FIG13
from albot2d.evaluation.paper.outputs import Experiment
from albot2d.evaluation.paper.process_exp import FIG14, FIG15, FIG16

__all__ = ["EXPERIMENTS", "PAPER_FIGURES", "runs_needed"]

EXPERIMENTS: dict[str, Experiment] = {
    "counts": counts,
    "table1": table1,
    "fig7": FIG7,
    "fig10": FIG10,
    "fig11_12": FIG11_12,
    "fig13": FIG13,
    "fig14": FIG14,
    "fig15": FIG15,
    "fig16": FIG16,
}


#: where in the paper each experiment's claim and figure are
PAPER_FIGURES: dict[str, str] = {
    "counts": "Experiments 1 and 3 (views → local maps), Fig. 16 (path integrations 5 vs 7)",
    "table1": "Table 1, Fig. 8",
    "fig7": "Fig. 7",
    "fig10": "Fig. 10",
    "fig11_12": "Figs. 11 and 12",
    "fig13": "Fig. 13",
    "fig14": "Fig. 14",
    "fig15": "Fig. 15",
    "fig16": "Fig. 16",
}


def runs_needed(names: list[str]) -> list[str]:
    """The runs the experiments ``names`` read, each once, in a fixed order."""
    from albot2d.evaluation.paper.runs import RUNS

    wanted = {r for n in names for r in EXPERIMENTS[n].RUNS}
    return [r for r in RUNS if r in wanted]
