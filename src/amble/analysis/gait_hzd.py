"""Virtual constraints inside a gait optimisation (the HZD formulation of FROST).

With ``hzd=True`` each output ``h₀(q)`` — the model's declared virtual-constraint outputs, else
the actuated quantities ``Bᵀq`` (:attr:`StepFunctions.outputs`) — must follow a Bézier polynomial in the phase
``s = (θ − θ⁺)/(θ⁻ − θ⁺)`` (:mod:`amble.modelling.virtual`), the coefficients ``α`` being unknowns
of the problem: the gait then lies on the zero-dynamics surface, and the HZD controller with the
optimised ``α`` reproduces it. Outputs and their rates are constrained at the mesh points.
"""

from __future__ import annotations

from math import comb
from typing import Any

import numpy as np

from ..backend.casadi_export import StepFunctions, casadi_module
from ..errors import ParameterError
from .gait_result import bernstein


def _input_map(fns: StepFunctions, x: np.ndarray, P: np.ndarray) -> np.ndarray:
    """``B`` (n × nu) as numbers, the same at every guessed point, or a ParameterError."""
    Bs = [np.asarray(fns.input_matrix(xi[: fns.n], P), float).reshape(fns.n, fns.nu) for xi in x]
    if any(np.abs(b - Bs[0]).max() > 1e-12 * max(np.abs(Bs[0]).max(), 1.0) for b in Bs):
        raise ParameterError("virtual constraints need actuated quantities linear in q (a constant B)")
    return Bs[0]


def virtual_constraints(fns: StepFunctions, X: Any, P: np.ndarray, x_guess: np.ndarray, alpha: Any) -> Any:
    """The outputs ``y = h₀(q) − h_d(s, α)`` and their rates ``ẏ`` at the mesh points (``X`` holds
    all ``2N + 1`` points), ``s = (θ − θ⁺)/(θ⁻ − θ⁺)`` with ``θ⁺``, ``θ⁻`` the phase at the first
    and the last point. The midpoints are left free: there ``y = 0`` would fix the inputs a
    second time and make them ring between the points; ``ẏ = 0`` puts the post-impact state on
    the zero-dynamics surface and keeps the interpolant on it between the mesh points."""
    ca = casadi_module()
    if fns.nu == 0:
        raise ParameterError("virtual constraints need inputs: the model declares no actuators")
    n, nu, degree = fns.n, fns.nu, alpha.shape[1] - 1
    if fns.virtual is None:
        _input_map(fns, x_guess, P)  # the outputs Bᵀq need a constant B
    q, v, a = ca.SX.sym("q", n), ca.SX.sym("v", n), ca.SX.sym("alpha", nu, degree + 1)
    t0, t1 = ca.SX.sym("t0"), ca.SX.sym("t1")
    s = (fns.phase(q, P) - t0) / (t1 - t0)
    basis = ca.vertcat(*[comb(degree, k) * s**k * (1 - s) ** (degree - k) for k in range(degree + 1)])
    y = fns.outputs(q, P) - ca.mtimes(a, basis)
    yf = ca.Function("y", [q, v, a, t0, t1], [y, ca.jtimes(y, q, v)])
    K = X.shape[1]
    th0, th1 = fns.phase(X[:n, 0], P), fns.phase(X[:n, -1], P)
    mesh = list(range(0, K, 2))
    ys, yds = yf.map(len(mesh))(X[:n, mesh], X[n:, mesh], alpha, th0, th1)
    return ca.vertcat(ca.vec(ys), ca.vec(yds))


def bezier_start(fns: StepFunctions, x: np.ndarray, P: np.ndarray, degree: int) -> np.ndarray:
    """Least-squares Bézier coefficients (nu × (M+1)) of the guessed trajectory."""
    theta = np.array([float(fns.phase(xi[: fns.n], P)) for xi in x])
    span = theta[-1] - theta[0]
    s = (theta - theta[0]) / span if abs(span) > 1e-12 else np.linspace(0.0, 1.0, len(x))
    Y = np.array([np.asarray(fns.outputs(xi[: fns.n], P), float).ravel() for xi in x])
    alpha, *_ = np.linalg.lstsq(bernstein(s, degree), Y, rcond=None)
    return alpha.T


def controller_key(fns: StepFunctions) -> tuple | None:
    """The parameter names of a step's own virtual constraints (its Bézier coefficients and phase
    range), or None without them."""
    vc = fns.virtual
    if vc is None:
        return None
    return (*(k for row in vc["alpha"] for k in row), vc["phase_start"], vc["phase_end"])
