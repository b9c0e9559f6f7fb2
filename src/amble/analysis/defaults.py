"""Default settings of the analyses, defined once and read by the API and the command line.

Integrator tolerances (relative and absolute alike):

- :data:`FIXED_POINT_TOL` — fixed-point searches and fixed-point sweeps (branches and maps): the
  multipliers come from finite differences of the return map and need tight integration;
- :data:`BIFURCATION_TOL` — bifurcation diagrams and Poincaré iterates;
- :data:`BASIN_TOL` — basins of attraction (only the outcome category of a cell matters).
"""

from __future__ import annotations

#: rtol = atol of fixed-point searches and fixed-point sweeps.
FIXED_POINT_TOL = 1e-12
#: Largest residual ``|P(x) − x|∞`` of a fixed point that a search returns. Tighter than the
#: accuracy promised (1e-10): the error of the fixed point is about ``|(A − I)⁻¹|`` times the
#: residual, and that factor is 2–15 for the library's gaits (multipliers away from 1); Newton
#: converges quadratically, so the last iteration usually lands at 1e-14 anyway.
RESIDUAL_TOL = 1e-12
#: rtol = atol of bifurcation diagrams and Poincaré iterates.
BIFURCATION_TOL = 1e-10
#: rtol = atol of basins of attraction.
BASIN_TOL = 1e-8
#: Footfalls walked from each initial state of a basin, at most.
BASIN_STEPS = 60

#: The tolerance of each sweep kind, by its command-line name.
SWEEP_TOL = {"fixed-point": FIXED_POINT_TOL, "continuation": FIXED_POINT_TOL, "bifurcation": BIFURCATION_TOL,
             "basin": BASIN_TOL}

#: MuJoCo's step (s) and the time constant of its soft foot contact (s) in a replay
#: (:mod:`amble.analysis.mujoco_replay`): a stiff contact, integrated with 25 steps per time constant.
MUJOCO_TIMESTEP, MUJOCO_CONTACT_TIME = 2e-4, 5e-3

__all__ = ["BASIN_STEPS", "BASIN_TOL", "BIFURCATION_TOL", "FIXED_POINT_TOL", "MUJOCO_CONTACT_TIME", "MUJOCO_TIMESTEP",
           "RESIDUAL_TOL", "SWEEP_TOL"]
