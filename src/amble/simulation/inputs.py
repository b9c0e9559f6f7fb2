"""Inputs of a controlled run: ``u`` per sample, joint power, work per step and cost of transport.

Inputs are evaluated from the model's closed-loop law (:attr:`amble.Equations.u`) at the
recorded states, so they are exact at every sample; the law is turned into NumPy code once per
mode. The power of input ``j`` is ``P_j = u_j ω_j`` with ``ω_j = B_jᵀ q̇`` the rate of what it
drives (W when ``u_j`` is in N·m and ``ω_j`` in rad/s). Work integrates the power over the
samples with the trapezoidal rule (exact to O(Δt²) of the sampling grid; events give a sample
on both sides of every footfall, so no interval straddles an impact).
"""

from __future__ import annotations

import weakref
from typing import Any

import numpy as np

from ..errors import AmbleError

Trajectory = Any  # a :class:`~amble.simulation.trajectory.Trajectory` (which imports this module)

_FUNCS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def _mode_functions(model: Any) -> tuple[Any, Any]:
    """NumPy functions ``(u, ω)`` of ``(t, q..., q̇..., params...)`` for one mode (cached)."""
    hit = _FUNCS.get(model)
    if hit is None:
        import sympy as sp  # SymPy only for a run with inputs: a passive run imports none

        from ..derivation.equations import derive
        from ..modelling.geometry import t as _t

        eq = derive(model)
        args = [_t, *model.q, *model.qd, *model.params]
        u = list(eq.u) if eq.u is not None else []
        w = list(eq.B.T * sp.Matrix(model.qd)) if eq.B is not None and eq.B.cols else []
        defs = list(eq.compact[0]) if eq.compact is not None else []
        # the law may be written with named intermediate quantities (HZD): evaluate them in order
        hit = (sp.lambdify(args, u, "numpy", cse=(lambda e: (defs, e)) if defs else True),
               sp.lambdify(args, w, "numpy", cse=True))
        _FUNCS[model] = hit
    return hit


def input_names(system: Any) -> list[str]:
    """Every input of every mode of a system, in declaration order."""
    names: list[str] = []
    for m in system.modes.values():
        for s in getattr(m, "inputs", []):
            if str(s) not in names:
                names.append(str(s))
    return names


def _rows(traj: Trajectory, which: int) -> dict[str, np.ndarray]:
    if traj.system is None:
        raise AmbleError("this trajectory carries no system; inputs need the model's control law")
    system = traj.system.symbolic()  # the control law is symbolic
    names = input_names(system)
    out = {n: np.full(len(traj.t), np.nan) for n in names}
    params = traj.parameters
    for mi, mname in enumerate(traj.mode_names):
        model = system.modes[mname]
        if not getattr(model, "inputs", None):
            continue
        rows = np.flatnonzero(traj.mode == mi)
        if rows.size == 0:
            continue
        nx = 2 * len(model.q)
        args = [traj.t[rows], *traj.x[rows, :nx].T, *[np.full(rows.size, params[str(p)]) for p in model.params]]
        vals = _mode_functions(model)[which](*args)
        for s, v in zip(model.inputs, vals):
            out[str(s)][rows] = np.broadcast_to(np.asarray(v, dtype=float), rows.shape)
    return out


def inputs(traj: Trajectory) -> dict[str, np.ndarray]:
    """Input name → value per sample (N·m or N; NaN in modes without that input)."""
    return _rows(traj, 0)


def rates(traj: Trajectory) -> dict[str, np.ndarray]:
    """Input name → rate ``ω_j = B_jᵀ q̇`` of what it drives per sample (rad/s or m/s)."""
    return _rows(traj, 1)


def joint_power(traj: Trajectory) -> dict[str, np.ndarray]:
    """Input name → mechanical power ``u_j ω_j`` per sample (W)."""
    u, w = inputs(traj), rates(traj)
    return {k: u[k] * w[k] for k in u}


def _segments(traj: Trajectory) -> list[tuple[int, int]]:
    """Row ranges ``[a, b]`` between footfalls (the pre row of a footfall ends one, its post row
    begins the next)."""
    bounds, i = [0], 0
    steps = {e.t for e in traj.step_events}
    for i in range(1, len(traj.t)):
        if traj.t[i] == traj.t[i - 1] and traj.t[i] in steps:
            bounds.append(i)
    bounds.append(len(traj.t))
    return [(a, b) for a, b in zip(bounds[:-1], bounds[1:]) if b - a >= 2]


def _integrate(traj: Trajectory, values: np.ndarray, a: int, b: int) -> float:
    tt, v = traj.t[a:b], np.nan_to_num(values[a:b])
    return float(np.sum(0.5 * (v[1:] + v[:-1]) * np.diff(tt)))


def work_per_step(traj: Trajectory, absolute: bool = False) -> dict[str, np.ndarray]:
    """Input name → work done in each step (J; one entry per interval between footfalls,
    including the partial ones at the start and the end). ``absolute``: ``∫|P| dt``, the work an
    actuator that cannot recover energy spends."""
    power = joint_power(traj)
    segs = _segments(traj)
    return {k: np.array([_integrate(traj, np.abs(p) if absolute else p, a, b) for a, b in segs])
            for k, p in power.items()}


def cost_of_transport(traj: Trajectory) -> float:
    """Mechanical cost of transport ``Σ_j ∫|u_j ω_j| dt / (m g d)`` over the run (dimensionless):
    ``m`` the total mass, ``g`` the magnitude of gravity, ``d`` the distance the hip moved
    forward (world frame)."""
    system = traj.system
    hip = getattr(system, "hip", None)
    if hip is None:
        raise AmbleError("cost of transport needs a walker with a hip point")
    import sympy as sp

    params = traj.parameters
    model = system.symbolic().modes[traj.mode_names[0]]  # masses and gravity are declared, symbolic
    subs = {s: params[str(s)] for s in model.params}
    mass = float(sum(model.masses.values(), sp.Integer(0)).subs(subs))
    g = float(sp.sqrt(sum((c ** 2 for c in model.gravity_vector), sp.Integer(0))).subs(subs))
    xs = traj.world_points()[hip][:, 0]
    d = float(xs[-1] - xs[0])
    if not (mass > 0 and g > 0 and d > 0):
        raise AmbleError(f"cost of transport needs positive mass, gravity and distance (got {mass:g} kg, "
                         f"{g:g} m/s², {d:g} m)")
    power = joint_power(traj)
    total = sum(_integrate(traj, np.abs(p), 0, len(traj.t)) for p in power.values())
    return total / (mass * g * d)
