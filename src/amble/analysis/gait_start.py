"""Starting trajectories of a gait optimisation: a passive step, or standing still."""

from __future__ import annotations

from typing import Any

import numpy as np

from ..backend.casadi_export import StepFunctions
from ..errors import ConvergenceError, ParameterError, StateError
from ..modelling.hybrid import HybridSystem
from ..simulation.simulate import simulate
from .poincare import default_guess

#: step time (s) of a standing start when neither a step time nor a speed says otherwise
STAND_STEP_TIME = 0.5
#: passive steps walked from the system's guess before the step that starts an optimisation
SETTLE_STEPS = 30


def initial_guess(system: HybridSystem, fns: StepFunctions, params: dict[str, float], guess: Any, N: int,
                  step_time: float | None, speed: float | None, step_length: float | None
                  ) -> tuple[np.ndarray, float]:
    """States at the ``2N + 1`` collocation points and the step time (s) to start from.

    ``guess`` ``None``/``"passive"``: the passive walk from the system's fixed-point guess (or
    default start) settled over a few steps (:func:`~amble.analysis.poincare.default_guess`: a
    stable passive gait where there is one), then one step; a state: one passive step from it; ``"stand"``: the first state of the
    system's guess, held still with zero velocities. A passive step that does not end in a
    footfall falls back to standing in its first state.
    """
    K, n = 2 * N + 1, fns.n
    if isinstance(guess, str) and guess not in ("passive", "stand"):
        raise ParameterError(f"guess must be 'passive', 'stand' or a state, got {guess!r}")
    if guess is None or isinstance(guess, str):
        start = system.fixed_point_guess
        if start is None:
            start = system.default_start.get(system.mode_names[0])
        if start is None:
            raise StateError(f"system {system.name!r} has no fixed-point guess or start: give guess=<state>")
        x0 = np.asarray(start, float)
        if guess != "stand" and len(x0) == 2 * n:
            try:
                x0 = np.asarray(default_guess(system, params, steps=SETTLE_STEPS), float)
            except ConvergenceError:
                pass  # walking does not settle: start from the guess itself
    else:
        x0 = np.asarray(guess, float)
    if x0.shape != (2 * n,) or not np.all(np.isfinite(x0)):
        raise StateError(f"guess must be {2 * n} finite numbers ({', '.join(fns.state_names)}), got {x0.tolist()}")
    T_stand = step_time or STAND_STEP_TIME
    if guess != "stand":
        walked = _passive_step(system, x0, params, step_time)
        if walked is not None:
            t, x = walked
            tau = np.linspace(0.0, t[-1], K)
            return np.column_stack([np.interp(tau, t, x[:, i]) for i in range(2 * n)]), float(t[-1])
    still = np.concatenate([x0[:n], np.zeros(n)])
    if step_time is None and speed is not None and step_length is not None:
        T_stand = step_length / speed
    return np.tile(still, (K, 1)), T_stand


def _passive_step(system: HybridSystem, x0: np.ndarray, params: dict[str, float], step_time: float | None
                  ) -> tuple[np.ndarray, np.ndarray] | None:
    """Times and states of one passive step from ``x0`` up to its footfall (pre-impact), or None."""
    limit = 4 * step_time if step_time else None
    tr = simulate(system, x0, params=params, steps=1, sample_dt=1e-3, max_step_time=limit)
    ev = tr.step_events
    if tr.status != "completed" or not ev:
        return None
    keep = tr.t < ev[0].t
    t = np.concatenate([tr.t[keep], [ev[0].t]])
    x = np.vstack([tr.x[keep], ev[0].x_pre])
    return t, x
