"""The paper's experiments (Yeap et al.) regenerated on simulated runs, beside its numbers.

``run_experiments(names, seeds, backend=...)`` runs every (run, seed) job the named
experiments need (``runs``; each job's result a typed ``jobs.JobSummary``, plain data only
on its way back from a worker), computes each experiment (``counts``, ``table1``,
``maps_exp``: Figs. 7, 10, 11–12, 13; ``process_exp``: Figs. 14–16) with a verdict from
its numbers, and returns experiments.json's content (its shapes in ``outputs``) plus the
data of the figures (``figdata``).
"""

from albot2d.evaluation.paper.campaign import ExperimentsOutcome, plan_jobs, run_experiments
from albot2d.evaluation.paper.registry import EXPERIMENTS
from albot2d.evaluation.paper.runs import RUNS, PaperRun

__all__ = ["EXPERIMENTS", "RUNS", "ExperimentsOutcome", "PaperRun", "plan_jobs", "run_experiments"]
