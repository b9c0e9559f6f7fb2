"""The result of a gait optimisation: the collocated step, its constraint report and HZD outputs."""

from __future__ import annotations

import json
from dataclasses import dataclass
from math import comb
from pathlib import Path
from typing import Any

import numpy as np
import sympy as sp

from ..backend.casadi_export import StepFunctions
from ..errors import ModelError, OutputError
from .collocation import hermite

#: an inequality whose slack is below this (in its own unit) is reported as active (binding)
ACTIVE_TOL = 1e-6


@dataclass
class Gait:
    """One periodic step found by :func:`~amble.analysis.gait_optimisation.optimize_gait`.

    ``fixed_point``: the post-impact state (``state_names`` order) — the first point of the step,
    and a start for :func:`~amble.analysis.poincare.find_fixed_point`; ``times`` (s), ``states``,
    ``accelerations``, ``inputs``: the ``2N + 1`` collocation points (mesh points and interval
    midpoints); ``pre_impact_state`` is the last of them; ``impulse``: the impact impulse on the
    new stance foot (N·s, world frame); ``constraints``: per kind, ``count``, ``max_violation``
    (≥ 0, in the constraint's unit), ``min_slack`` and ``active`` (inequalities within
    ``ACTIVE_TOL`` of a bound); ``bezier``: HZD virtual constraints fitted to the gait (or None);
    ``solver``: status, iterations, wall time (s), nodes.
    """

    system: str
    state_names: list[str]
    input_names: list[str]
    params: dict[str, float]
    objective_name: str
    objective: float
    fixed_point: np.ndarray
    step_time: float
    step_length: float
    speed: float
    times: np.ndarray
    states: np.ndarray
    accelerations: np.ndarray
    inputs: np.ndarray
    pre_impact_state: np.ndarray
    impulse: np.ndarray
    constraints: dict[str, dict[str, Any]]
    solver: dict[str, Any]
    bezier: dict[str, Any] | None = None
    #: the post-impact velocity of the model extended with its base (coordinate rates, then the
    #: old stance foot's velocity; m/s, rad/s)
    extended_velocity: np.ndarray | None = None
    #: the ground's force on the stance foot at the collocation points (N, world axes of the
    #: step's frame: ``(x, z)`` in 2D, ``(x, y, z)`` in 3D)
    contact_forces: np.ndarray | None = None
    #: a gait of several steps per period (``optimize_gait(steps=k)``): every step, in order, each
    #: a :class:`Gait` of its own (its trajectory, impact, step time and Bézier coefficients); the
    #: fields above are then the first step's, except ``speed`` (the period's: Σ L / Σ T) and
    #: ``objective`` (the period's). None for a one-step gait
    steps: list[Gait] | None = None
    #: the mode of each step of a multi-step period (a walker whose stance feet are modes:
    #: ``["left", "right"]``); None for one step
    modes: list[str] | None = None
    #: an HZD gait's stability (:mod:`~amble.analysis.gait_stability`): ``restricted_multiplier``
    #: (``δ_zero²``, the multiplier of the restricted Poincaré map), ``max_multiplier`` (its bound
    #: in the optimisation, or None) and, once checked, ``closed_loop`` (the full-order multipliers
    #: of the closed loop). None when the restricted map is not one-dimensional-affine
    stability: dict[str, Any] | None = None

    def state(self, t: Any) -> np.ndarray:
        """The collocation solution at times ``t`` (s, within the step), by its Hermite interpolant."""
        n = len(self.state_names) // 2
        f = np.hstack([self.states[:, n:], self.accelerations])
        return hermite(np.atleast_1d(np.asarray(t, float)), self.step_time, self.states, f)

    def input(self, t: Any) -> np.ndarray:
        """The inputs at times ``t`` (s), quadratic on each interval through its three points (the
        Hermite–Simpson control)."""
        tt = np.atleast_1d(np.asarray(t, float))
        N = (len(self.times) - 1) // 2
        h = self.step_time / N
        i = np.clip((tt // h).astype(int), 0, N - 1)
        s = (tt - i * h) / h
        a, m, b = self.inputs[2 * i], self.inputs[2 * i + 1], self.inputs[2 * i + 2]
        return ((2 * (s - 0.5) * (s - 1))[:, None] * a + (-4 * s * (s - 1))[:, None] * m
                + (2 * s * (s - 0.5))[:, None] * b)

    def input_laws(self, model: Any) -> dict[sp.Symbol, sp.Expr]:
        """The optimised inputs as open-loop laws of time for ``model.control(...)``: on each
        interval the quadratic through its three collocation points (``Piecewise`` in ``t``,
        seconds since the start of the step), the last piece held beyond the step."""
        from ..modelling.geometry import t as time

        N = (len(self.times) - 1) // 2
        h = self.step_time / N
        by_name = {str(u): u for u in getattr(model, "inputs", [])}
        missing = [k for k in self.input_names if k not in by_name]
        if missing:
            raise ModelError(f"model {model.name!r} has no input(s) {', '.join(missing)} of this gait")
        laws = {}
        for j, name in enumerate(self.input_names):
            pieces = []
            for i in range(N):
                a, m, b = (float(v) for v in self.inputs[2 * i: 2 * i + 3, j])
                s = (time - i * h) / h
                half = sp.Rational(1, 2)
                expr = 2 * a * (s - half) * (s - 1) - 4 * m * s * (s - 1) + 2 * b * s * (s - half)
                pieces.append((expr, time < (i + 1) * h) if i < N - 1 else (expr, True))
            laws[by_name[name]] = sp.Piecewise(*pieces)
        return laws

    @property
    def max_violation(self) -> float:
        """The largest constraint violation of any kind (its own unit)."""
        return max((r["max_violation"] for r in self.constraints.values()), default=0.0)

    def to_json(self) -> dict[str, Any]:
        """The gait as JSON-ready data (the fields of ``gait.json``)."""
        return {
            "system": self.system, "state_names": self.state_names, "input_names": self.input_names,
            "parameters": self.params, "objective_name": self.objective_name, "objective": self.objective,
            "fixed_point": self.fixed_point.tolist(), "step_time": self.step_time,
            "step_length": self.step_length, "speed": self.speed,
            "pre_impact_state": self.pre_impact_state.tolist(), "impulse": self.impulse.tolist(),
            "trajectory": {"t": self.times.tolist(), "states": self.states.tolist(),
                           "accelerations": self.accelerations.tolist(), "inputs": self.inputs.tolist(),
                           "contact_force": None if self.contact_forces is None else self.contact_forces.tolist()},
            "constraints": self.constraints, "max_violation": self.max_violation,
            "bezier": self.bezier, "stability": self.stability, "solver": self.solver,
            **({"period": len(self.steps), "steps": [_step_json(g) for g in self.steps]} if self.steps else {}),
            **({"modes": self.modes} if self.modes else {}),
        }

    def save(self, path: str | Path) -> Path:
        """Write :meth:`to_json` to ``path`` (``.json``)."""
        p = Path(path)
        if p.suffix.lower() != ".json":
            raise OutputError(f"{p}: a gait is written as .json")
        if not p.parent.is_dir():
            raise OutputError(f"{p}: directory {p.parent} does not exist")
        try:
            p.write_text(json.dumps(self.to_json(), indent=1))
        except OSError as e:
            raise OutputError(f"{p}: cannot write ({e.strerror})") from None
        return p


def _step_json(g: Gait) -> dict[str, Any]:
    """One step of a multi-step gait in ``gait.json`` (the period's report and solver are at the top)."""
    d = g.to_json()
    for k in ("constraints", "solver", "max_violation", "objective", "objective_name", "system", "state_names",
              "input_names", "parameters"):
        d.pop(k, None)
    d["parameters"] = g.params
    return d


def constraint_report(groups: list, g: np.ndarray, lbg: np.ndarray, ubg: np.ndarray, w: np.ndarray,
                      lbw: np.ndarray, ubw: np.ndarray, bound_groups: list) -> dict[str, dict[str, Any]]:
    """Per kind of constraint: its count, largest violation, smallest slack and active count."""
    out: dict[str, dict[str, Any]] = {}
    i = 0
    for name, e, _, _ in groups:
        k = e.numel()
        out[name] = _rows(g[i:i + k], lbg[i:i + k], ubg[i:i + k])
        i += k
    for name, a, b in bound_groups:
        if b > a and np.any(np.isfinite(lbw[a:b]) | np.isfinite(ubw[a:b])):
            out[name] = _rows(w[a:b], lbw[a:b], ubw[a:b])
    return out


def _rows(v: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> dict[str, Any]:
    viol = np.maximum(np.maximum(lo - v, v - hi), 0.0)
    ineq = lo < hi
    slack = np.minimum(v - lo, hi - v)[ineq]
    return {"count": int(len(v)), "max_violation": float(viol.max(initial=0.0)),
            "equality": bool(not ineq.any()),
            "min_slack": float(slack.min()) if slack.size else None,
            "active": int(np.sum(slack < ACTIVE_TOL)) if slack.size else 0}


def bernstein(s: np.ndarray, degree: int) -> np.ndarray:
    """Bernstein basis ``C(M,k) sᵏ (1 − s)^(M−k)``, one column per ``k = 0..M``."""
    s = np.asarray(s, float)[:, None]
    k = np.arange(degree + 1)[None, :]
    c = np.array([comb(degree, j) for j in range(degree + 1)])[None, :]
    return c * s**k * (1 - s) ** (degree - k)


def bezier_fit(model: Any, fns: StepFunctions, X: np.ndarray, degree: int, P: np.ndarray,
               alpha: np.ndarray | None = None) -> dict[str, Any] | None:
    """HZD virtual constraints of the gait: each output ``h₀(q)`` (:attr:`StepFunctions.outputs`:
    the model's declared outputs, else the actuated quantities ``Bᵀq``) as a Bézier polynomial of
    degree ``degree`` in the phase ``s = (θ − θ⁺)/(θ⁻ − θ⁺)``, fitted by least squares over the
    collocation points unless ``alpha`` (nu × (M+1), the optimised coefficients of an HZD gait)
    is given; ``θ(q)`` is :attr:`StepFunctions.phase` (``θ⁺``, ``θ⁻`` its values after and before
    the impact). For a model with virtual constraints of that degree, ``params`` holds the values
    of its ``alpha``, ``phase_start`` and ``phase_end`` parameters (``simulate(..., params=...)``
    then runs its controller on this gait). Without the model's outputs it needs a constant ``B``
    (actuated quantities linear in ``q``); ``θ`` must increase strictly over the step; otherwise None."""
    if fns.nu == 0 or degree < 1:
        return None
    n = fns.n
    Q = X[:, :n]
    if fns.virtual is None:
        Bs = [np.asarray(fns.input_matrix(q, P), float).reshape(n, fns.nu) for q in Q]
        if any(np.abs(b - Bs[0]).max() > 1e-12 * max(np.abs(Bs[0]).max(), 1.0) for b in Bs):
            return None  # actuated quantities not linear in q: no single output map to report
    theta = np.array([float(fns.phase(q, P)) for q in Q])
    if np.any(np.diff(theta) <= 0):
        return None
    s = (theta - theta[0]) / (theta[-1] - theta[0])
    Y = np.array([np.asarray(fns.outputs(q, P), float).ravel() for q in Q])
    basis = bernstein(s, degree)
    if alpha is None:
        alpha = np.linalg.lstsq(basis, Y, rcond=None)[0].T
    alpha = np.asarray(alpha, float).reshape(fns.nu, degree + 1)
    out = {"degree": degree, "outputs": list(fns.output_texts or []), "inputs": list(fns.input_names),
           "phase": {"expression": fns.phase_text, "theta_plus": float(theta[0]), "theta_minus": float(theta[-1])},
           "alpha": alpha.tolist(), "fit_error": float(np.abs(basis @ alpha.T - Y).max())}
    vc = fns.virtual
    if vc is not None and vc["degree"] == degree and len(vc["alpha"]) == fns.nu:
        values = {name: float(alpha[i, k]) for i, row in enumerate(vc["alpha"]) for k, name in enumerate(row)}
        values[vc["phase_start"]], values[vc["phase_end"]] = float(theta[0]), float(theta[-1])
        out["params"] = values
    return out
