"""Invariant checks of an Albot1 run, shared by the unit, property and fuzzing tests.

The checks live in the package (``albot2d.evaluation.checks.invariants``) so that the fuzzing
campaign runs exactly the same ones; this module keeps the tests' import path.
"""

from __future__ import annotations

from albot2d.evaluation.checks.invariants import (
    UpdateRecorder,
    check_local_map_rule,
    check_update_deleted_facing_overlap,
)

__all__ = ["UpdateRecorder", "check_local_map_rule", "check_update_deleted_facing_overlap"]
