"""Studies: one-off measurements with their own command lines (``python -m
albot2d.studies.NAME``), kept out of the library's core.

- ``heading_calibration``: the heading bound's error model against Albot₁'s real link
  heading errors on fuzzing episodes;
- ``link_errors``: Albot₁'s error budget, each route-map link's error by how it was made;
- ``sensitivity``: start–stop homing against odometry noise, moves per update by region.
- ``path_integrations``: why Albot₁ integrates paths where it does on Fig. 16's route, each
  path integration with its cause and each lost tracked surface with its reason.
- ``deletion_rules``: the global map's deletion rules side by side, one run's local maps
  re-added under each at Albot₁'s and at the true poses, scored at the run's homing stops.

They use the library only through its public API and the mapper's public hooks.
May import: everything but the interfaces (CLI, viz).
"""

__all__: list[str] = []
