"""The gait sensitivity norm: how much a gait's indicators move after a one-step disturbance
(Hobbelen & Wisse 2007, *A disturbance rejection measure for limit cycle walkers: the gait
sensitivity norm*).

A disturbance ``δ`` of a parameter (the slope, the height of one step, a push) acts on one step
only: the step from the gait's post-impact state ``x*`` runs with ``p + δ e``, every later step with
``p``. To first order the post-impact states then deviate by

    ``Δx₁ = (∂P/∂p) e δ``,   ``Δxₖ₊₁ = (∂P/∂x) Δxₖ``,

and the step times by ``ΔT₀ = (∂T/∂p) e δ``, ``ΔTₖ = (∂T/∂x) Δxₖ`` (k ≥ 1), with the return
map's exact derivatives at the gait (:meth:`amble.analysis.return_map.ReturnMap.derivatives`). The
gait sensitivity norm of an indicator ``g`` is the 2-norm of its response per unit disturbance,
``sqrt(Σₖ (Δgₖ/δ)²)``: here the step time (s per unit of the parameter) and every post-impact state
coordinate, and ``state``, the norm over all of them. The sum is taken until the response has
decayed below 1e-12 of its largest term (an unstable gait has no norm: an error).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..errors import ConvergenceError, StateError
from .limit_cycle import LimitCycle
from .return_map import ReturnMap

#: steps summed at most
MAX_STEPS = 100_000


@dataclass(frozen=True)
class GaitSensitivity:
    """Gait sensitivity norms for a one-step disturbance of ``parameter`` (module docstring)."""

    parameter: str
    step_time: float
    state: float
    coordinates: dict[str, float]
    steps: int
    fixed_point: list[float]

    def to_json(self) -> dict[str, Any]:
        return {"parameter": self.parameter, "gsn_step_time": self.step_time, "gsn_state": self.state,
                "gsn_coordinates": self.coordinates, "steps": self.steps, "fixed_point": self.fixed_point}


def gait_sensitivity(cycle: LimitCycle, parameter: str) -> GaitSensitivity:
    """The gait sensitivity norms of ``cycle`` for a one-step disturbance of ``parameter``."""
    system = cycle.hybrid_system
    if system is None:
        raise StateError("the limit cycle does not carry its system: find it with find_fixed_point")
    if cycle.period != 1:
        raise StateError("the gait sensitivity norm is defined here for period-1 gaits")
    if not cycle.stable:
        raise ConvergenceError("the gait is unstable: a disturbance grows, it has no sensitivity norm")
    P = ReturnMap(system, cycle.parameters)
    names = list(P.k.meta["params"])
    if parameter not in names:
        raise StateError(f"unknown parameter {parameter!r}; parameters: {', '.join(names)}")
    j = names.index(parameter)
    _, _, s = P.derivatives(cycle.fixed_point, params=True)
    A, dT = s.dx_dx0, s.dt_dx0
    dx = s.dx_dp[:, j].copy()
    sum_x = np.zeros_like(dx)
    sum_t = float(s.dt_dp[j]) ** 2
    peak = max(float(np.max(np.abs(dx))), abs(float(s.dt_dp[j])), 1e-300)
    k = 0
    while k < MAX_STEPS:
        k += 1
        sum_x += dx**2
        sum_t += float(dT @ dx) ** 2
        dx = A @ dx
        if float(np.max(np.abs(dx))) < 1e-12 * peak:
            break
    state_names = system.state_names(P.mode)
    return GaitSensitivity(parameter=parameter, step_time=math.sqrt(sum_t), state=float(np.sqrt(sum_x.sum())),
                           coordinates={n: float(v) for n, v in zip(state_names, np.sqrt(sum_x))}, steps=k,
                           fixed_point=[float(v) for v in cycle.fixed_point])


__all__ = ["GaitSensitivity", "gait_sensitivity"]
