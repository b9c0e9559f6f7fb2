"""The stages of a gait optimisation (which solves, in which order, from which start) and the
gluing of a multi-step period into one result."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..backend.casadi_export import StepFunctions
from .gait_result import Gait


def period_gait(gaits: list[Gait], modes: list[str] | None = None) -> Gait:
    """The gait of a multi-step period: the first step's fields, the period's speed, every step
    (and the mode of each)."""
    T = sum(g.step_time for g in gaits)
    L = sum(g.step_length for g in gaits)
    return replace(gaits[0], speed=L / T, steps=list(gaits), modes=modes, bezier=_period_bezier(gaits))


def _period_bezier(gaits: list[Gait]) -> dict | None:
    """The first step's virtual constraints, with the controller parameters of every step where
    the steps name them apart (each stance mode its own coefficients) or agree on them: the
    values that run the whole period in ``simulate``."""
    first = gaits[0].bezier
    if not first or "params" not in first or not all(g.bezier and "params" in g.bezier for g in gaits):
        return first
    merged: dict[str, float] = {}
    for g in gaits:
        for k, v in g.bezier["params"].items():
            if k in merged and abs(merged[k] - v) > 1e-9 * max(1.0, abs(v)):
                return first  # one mode's coefficients differ from step to step: no single controller
            merged[k] = v
    return {**first, "params": merged}


def solve_stages(fns: StepFunctions, x_guess: np.ndarray, P: np.ndarray, levels: list[int], hzd: bool
            ) -> list[tuple[int, bool, bool, bool]]:
    """The solves of an optimisation, in order: ``(intervals, virtual constraints, feasibility
    only, refinement of the previous solve)``.

    A start without motion (standing still: every velocity zero, the phase not advancing) is a
    degenerate point of the problem: the impact's impulse, the old stance foot's lift-off and the
    footfall's enabling condition all sit on their bounds (each is linear in the velocities), the
    phase of the virtual constraints spans nothing, and the objective's Lagrangian pulls the
    first iterations towards small inputs rather than towards a step. From there IPOPT wanders
    (RABBIT at 0.8 m/s: the iteration limit, or a gait with its torso below the hip). A first
    solve of the constraints alone (no objective, no virtual constraints, the step time held at
    the guess's: free, it collapses to its lower bound) finds a step in a few iterations (RABBIT:
    12); the optimisation, with its virtual constraints, then starts from it. A moving start
    of an HZD gait is optimised without its virtual constraints first (see the code).
    """
    n = fns.n
    theta = [float(fns.phase(x_guess[i, :n], P)) for i in (0, -1)]
    still = not np.any(np.abs(x_guess[:, n:]) > 1e-12) or (hzd and not abs(theta[1] - theta[0]) > 1e-9)
    first = [(levels[0], False, True, False)] if still else []
    if hzd and not still:
        # a moving start off the zero-dynamics surface (an interpolated stride, a passive step):
        # with the virtual constraints from the start, a 3D biped of nine coordinates runs into
        # the iteration limit with its outputs off by 1e4 (their phase s = (θ − θ⁺)/(θ⁻ − θ⁺)
        # is singular wherever the iterates shrink the phase's span); the gait optimised
        # without them advances its phase, and the virtual constraints are fitted from there
        # (58 + 16 iterations; RABBIT from an interpolated stride: 25 in all instead of 9)
        first = [(levels[0], False, False, False)]
    return [*first, (levels[0], hzd, False, False), *((N, hzd, False, True) for N in levels[1:])]
