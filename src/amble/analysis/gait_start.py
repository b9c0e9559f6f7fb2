"""Starting trajectories of a gait optimisation: a passive step, or standing still."""

from __future__ import annotations

from typing import Any

import numpy as np

from ..backend.casadi_export import StepFunctions
from ..errors import ConvergenceError, ParameterError, StateError
from ..modelling.hybrid import HybridSystem
from ..simulation.simulate import simulate
from .poincare import default_guess

#: step time (s) of a standing or interpolated start unless one is given
STAND_STEP_TIME = 0.5
#: the kinds of starting trajectory (besides a state)
GUESSES = ("passive", "stand", "interpolate")
#: passive steps walked from the system's guess before the step that starts an optimisation
SETTLE_STEPS = 30


def initial_guess(system: HybridSystem, fns: StepFunctions | list[StepFunctions], params: dict[str, float],
                  guess: Any, N: int, step_time: float | None, posture: Any = None, steps: int = 1
                  ) -> list[tuple[np.ndarray, float]]:
    """Per step of the period (``steps`` of them), the states at the ``2N + 1`` collocation points
    and the step time (s) to start from.

    A walked start (passive or from a state) walks ``steps`` steps, one guess each; a standing
    or interpolated one is the same for every step.

    ``guess`` ``None``: ``"stand"`` for a model under feedback (virtual constraints or a control
    law: a step of it is its controller's, not a passive one, and its inputs are unknowns of the
    optimisation), else ``"passive"``; ``"passive"``: the passive walk from the system's fixed-point guess (or
    default start) settled over a few steps (:func:`~amble.analysis.poincare.default_guess`: a
    stable passive gait where there is one), then one step; a state: one passive step from it;
    ``"stand"``: the posture of the system's guess (or of the given state), held still with zero
    velocities; ``"interpolate"``: from that posture to its relabelled one at constant rates. A
    passive step that does not end in a footfall falls back to ``"interpolate"``. ``step_time``
    (s) is the duration of the last two; ``posture`` (the ``n`` coordinates, rad or m) replaces the
    guess's posture in them.

    ``fns``: the step's exported functions, or one per step of the period (a walker whose stance
    feet are modes): a standing or interpolated start then takes the same numbers in every mode,
    coordinate by coordinate — the stance leg's joints in the stance leg's places — which is the
    same posture for a walker whose modes list their legs in the same order.
    """
    fnss = list(fns) if isinstance(fns, (list, tuple)) else [fns] * steps
    fns = fnss[0]
    K, n = 2 * N + 1, fns.n
    if isinstance(guess, str) and guess not in GUESSES:
        raise ParameterError(f"guess must be one of {', '.join(GUESSES)} or a state, got {guess!r}")
    kind = guess if isinstance(guess, str) else (default_guess_kind(system) if guess is None else "state")
    if kind != "state":
        start = system.fixed_point_guess
        if start is None:
            start = system.default_start.get(system.mode_names[0])
        if start is None:
            raise StateError(f"system {system.name!r} has no fixed-point guess or start: give guess=<state>")
        x0 = np.asarray(start, float)
        if kind == "passive" and len(x0) == 2 * n:
            try:
                x0 = np.asarray(default_guess(system, params, steps=SETTLE_STEPS), float)
            except ConvergenceError:
                pass  # walking does not settle: start from the guess itself
    else:
        x0 = np.asarray(guess, float)
    if x0.shape != (2 * n,) or not np.all(np.isfinite(x0)):
        raise StateError(f"guess must be {2 * n} finite numbers ({', '.join(fns.state_names)}), got {x0.tolist()}")
    T = step_time or STAND_STEP_TIME
    if kind in ("passive", "state"):
        walked = _passive_steps(system, x0, params, step_time, steps)
        if walked is not None:
            out = []
            for t, x in walked:
                tau = np.linspace(t[0], t[-1], K)
                out.append((np.column_stack([np.interp(tau, t, x[:, i]) for i in range(2 * n)]),
                            float(t[-1] - t[0])))
            return out
    q0 = x0[:n]
    if posture is not None:
        if kind not in ("stand", "interpolate"):
            raise ParameterError("a posture is the start of guess='stand' or 'interpolate' only")
        q0 = np.asarray(posture, float)
        if q0.shape != (n,) or not np.all(np.isfinite(q0)):
            raise StateError(f"posture must be {n} finite numbers ({', '.join(fns.state_names[:n])}), "
                             f"got {np.asarray(posture).tolist()}")
    if kind == "stand":
        return [(np.tile(np.concatenate([q0, np.zeros(n)]), (K, 1)), T)] * steps
    # the relabelling of a footfall swaps legs, so (as an involution) it maps the first posture to the last
    s = np.linspace(0.0, 1.0, K)[:, None]
    out = []
    for f in fnss[:steps]:
        P = np.array([params[k] for k in f.param_names])
        qN = np.asarray(f.relabel(q0, np.zeros(n + f.dims), P), float).ravel()[:n]
        out.append((np.hstack([(1 - s) * q0 + s * qN, np.tile((qN - q0) / T, (K, 1))]), T))
    return out


def default_guess_kind(system: HybridSystem) -> str:
    """``"stand"`` for a system whose first mode has a feedback law (virtual constraints or a
    control law of its inputs), else ``"passive"``."""
    m = system.symbolic().modes[system.mode_names[0]]  # the feedback law is declared, symbolic
    law = getattr(m, "control_law", None)
    controlled = getattr(m, "virtual", None) is not None or (law is not None and any(e != 0 for e in law))
    return "stand" if controlled else "passive"


def _passive_steps(system: HybridSystem, x0: np.ndarray, params: dict[str, float], step_time: float | None,
                   steps: int = 1) -> list[tuple[np.ndarray, np.ndarray]] | None:
    """Times and states of ``steps`` passive steps from ``x0``, each from its post-impact state up
    to its footfall (pre-impact), or None."""
    limit = 4 * step_time if step_time else None
    tr = simulate(system, x0, params=params, steps=steps, sample_dt=1e-3, max_step_time=limit)
    ev = tr.step_events
    if tr.status != "completed" or len(ev) < steps:
        return None
    out, t_start, x_start = [], tr.t[0], tr.x[0]
    for e in ev[:steps]:
        keep = (tr.t > t_start) & (tr.t < e.t)
        out.append((np.concatenate([[t_start], tr.t[keep], [e.t]]), np.vstack([x_start, tr.x[keep], e.x_pre])))
        t_start, x_start = e.t, e.x_post
    return out


def start_vector(fns: StepFunctions, x: np.ndarray, T: float, N: int, P: np.ndarray, warm: Any = None
                  ) -> np.ndarray:
    """Unknowns from a guessed trajectory ``x`` (``(2N + 1) × 2n``): accelerations by differences,
    inputs zero, the impact's unknowns from the guessed pre-impact state; from a coarser solution
    ``warm``, its accelerations, inputs and impulse interpolated."""
    n, nu, d, K = fns.n, fns.nu, fns.dims, 2 * N + 1
    tau = np.linspace(0.0, T, K)
    a = np.gradient(x[:, n:], tau, axis=0) if K > 2 else np.zeros((K, n))
    u = np.zeros((K, nu))
    qe, lam = np.concatenate([x[-1, n:], np.zeros(d)]), np.zeros(d)
    if warm is not None:
        a = np.column_stack([np.interp(tau, warm.times, warm.accelerations[:, i]) for i in range(n)])
        u = warm.input(tau) if nu else u
        qe, lam = warm.extended_velocity, warm.impulse
    return np.concatenate([x.ravel(), a.ravel(), u.ravel(), [T], qe, lam])
