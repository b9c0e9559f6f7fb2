"""Parameter gradients of a gait: how its fixed point, step time, speed and stability move with
the parameters.

At a fixed point ``P(x*, p) = x*`` of the k-step return map the implicit function theorem gives

    ``(I − ∂P/∂x) ∂x*/∂p = ∂P/∂p``,   ``∂T/∂p = (∂T/∂x) ∂x*/∂p + ∂T/∂p|ₓ``,

with ``∂P/∂x``, ``∂P/∂p``, ``∂T/∂x``, ``∂T/∂p`` exact from one run with the variational
equations (:meth:`~amble.analysis.poincare.ReturnMap.derivatives`). ``I − ∂P/∂x`` is invertible
in full state coordinates whenever no multiplier is 1: the map's derivative has the nontrivial
multipliers as eigenvalues and 0 in the directions it collapses onto the section. The speed and
the spectral radius of the multipliers depend on second derivatives of the map; they are
differentiated centrally along the branch, at fixed points re-converged from the theorem's
predictor ``x* ± ε ∂x*/∂p`` (error O(ε²), ε = 1e-5 of the parameter's scale).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..errors import ConvergenceError, StateError
from .poincare import LimitCycle, ReturnMap, find_fixed_point


@dataclass(frozen=True)
class GaitGradients:
    """Derivatives of a gait with respect to ``parameters`` (one column each).

    ``fixed_point``: ``∂x*/∂p`` (state × parameters, in the state's units per the parameter's);
    ``step_time``: ``∂T/∂p`` of the mean step time (s); ``speed``: of the mean walking speed
    (m/s, horizontal world displacement per period over its time); ``spectral_radius``: of the
    largest multiplier modulus.
    """

    parameters: list[str]
    fixed_point: np.ndarray
    step_time: np.ndarray
    speed: np.ndarray
    spectral_radius: np.ndarray

    def to_json(self) -> dict:
        return {"parameters": self.parameters, "fixed_point": self.fixed_point.tolist(),
                "step_time": self.step_time.tolist(), "speed": self.speed.tolist(),
                "spectral_radius": self.spectral_radius.tolist()}


def gait_speed(cycle: LimitCycle) -> float:
    """Mean horizontal walking speed over one period (m/s): every named point of a periodic gait
    is displaced by the same amount per period in the world frame."""
    tr = cycle.hybrid_system and cycle.trajectory(steps=cycle.period)
    world = tr.world_points() if tr is not None else {}
    if not world:
        raise StateError(f"system {cycle.system!r} has no named points: its walking speed is not defined")
    path = next(iter(world.values()))
    return float(abs(path[-1, 0] - path[0, 0]) / (cycle.step_time * cycle.period))


def gait_gradients(cycle: LimitCycle, parameters: Sequence[str] | None = None, *, relative_step: float = 1e-5
                   ) -> GaitGradients:
    """Gradients of ``cycle`` with respect to ``parameters`` (default: all the system's)."""
    system = cycle.hybrid_system
    if system is None:
        raise StateError("the limit cycle does not carry its system: find it with find_fixed_point")
    P = ReturnMap(system, cycle.parameters, period=cycle.period)
    names = list(P.k.meta["params"])
    chosen = list(parameters) if parameters is not None else names
    unknown = [n for n in chosen if n not in names]
    if unknown:
        raise StateError(f"unknown parameter(s) {', '.join(unknown)}; parameters: {', '.join(names)}")
    cols = [names.index(n) for n in chosen]
    _, _, s = P.derivatives(cycle.fixed_point, params=True)
    n = cycle.fixed_point.size
    try:
        dx = np.linalg.solve(np.eye(n) - s.dx_dx0, s.dx_dp[:, cols])
    except np.linalg.LinAlgError:
        raise ConvergenceError("a multiplier is 1 here (a fold): the gait does not depend smoothly on the "
                               "parameters") from None
    dT = (s.dt_dx0 @ dx + s.dt_dp[cols]) / cycle.period
    speed, radius = np.zeros(len(cols)), np.zeros(len(cols))
    for j, name in enumerate(chosen):
        eps = relative_step * max(1.0, abs(cycle.parameters[name]))
        ends = []
        for sign in (1.0, -1.0):
            params = {**cycle.parameters, name: cycle.parameters[name] + sign * eps}
            lc = find_fixed_point(system, cycle.fixed_point + sign * eps * dx[:, j], params=params,
                                  period=cycle.period)
            ends.append((gait_speed(lc), float(np.max(np.abs(lc.multipliers)))))
        speed[j] = (ends[0][0] - ends[1][0]) / (2 * eps)
        radius[j] = (ends[0][1] - ends[1][1]) / (2 * eps)
    return GaitGradients(parameters=chosen, fixed_point=dx, step_time=dT, speed=speed, spectral_radius=radius)
