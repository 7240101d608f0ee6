"""Checks: invariants a run must hold, used by the tests and by every fuzzing episode.

- ``invariants``: the mapper's invariants (route connected, bounded heading error, the
  local-map rule, zero-noise localisation) and the recorders that feed them;
- ``deletion``: algorithm #5's deletion invariant, recomputed from the rule's definition
  (``deletion_numba``: its optional compiled prefilter);
- ``simulator``: the simulator's own invariants (the robot keeps clear of obstacles,
  laser hits lie on them), measured with ``hit_geometry``, geometry independent of the
  simulator's ray caster (``simulator_numba``: its compiled query);
Every check raises ``albot2d.errors.InvariantError``.

May import: everything below evaluation. Nothing here may import the run pipeline: a
check must not share code with what it checks beyond the plain geometry.
"""

from albot2d.errors import InvariantError
from albot2d.evaluation.checks.invariants import INVARIANTS, InvariantParams

__all__ = ["INVARIANTS", "InvariantError", "InvariantParams"]
