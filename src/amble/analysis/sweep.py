"""Parameter sweeps on Dask: fixed-point branches and maps, bifurcation diagrams, basins of attraction.

This module gathers the public API of the sweep feature; each idea lives in its own module:

- :mod:`amble.analysis.store` — the resumable result file (append-only CSV journal, exact keys,
  atomic compaction) and :class:`SweepResult`;
- :mod:`amble.analysis.runner` — Dask clients (:func:`open_client`) and chunked execution;
- :mod:`amble.analysis.fixed_points` — fixed-point branches (continuation) and 2D maps,
  :func:`period_doubling`;
- :mod:`amble.analysis.bifurcation` — bifurcation diagrams, :func:`poincare_iterates`;
- :mod:`amble.analysis.continuation_sweep` — branches by pseudo-arclength continuation with their
  folds, flips and period-doubled branches (:mod:`amble.analysis.continuation`);
- :mod:`amble.analysis.basin` — basins of attraction, cells put on the post-impact section
  (:mod:`amble.analysis.section`);

Work is cut into chunks (consecutive parameter values, one row of a map or a basin), each one
Dask task; chunks depend only on the grid, so a result does not depend on how many processes
computed it. Every row is durable in the result file as soon as its chunk finishes; a sweep
interrupted at any moment (even killed) and run again with the same file computes only the
missing points, and its final file equals that of an uninterrupted run byte for byte. A point
whose computation fails is recorded with ``status`` ``failed`` and its reason, and the sweep
goes on.

Units: angles in rad, angular velocities in rad/s, times in s; parameters in the model's units.
"""

from __future__ import annotations

from .basin import BASIN_LABELS, BasinResult, basin
from .bifurcation import bifurcation, first_period_doubling_iterates, poincare_iterates
from .continuation_sweep import sweep_continuation
from .fixed_points import period_doubling, sweep_fixed_points, sweep_fixed_points_2d
from .runner import open_client
from .store import ResultStore, SweepResult

__all__ = ["BASIN_LABELS", "BasinResult", "ResultStore", "SweepResult", "basin", "bifurcation",
           "first_period_doubling_iterates", "open_client", "period_doubling", "poincare_iterates",
           "sweep_continuation", "sweep_fixed_points", "sweep_fixed_points_2d"]
