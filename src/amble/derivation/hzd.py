"""The controller and the zero dynamics of virtual constraints (hybrid zero dynamics).

For outputs ``y = h₀(q) − h_d(θ(q))`` (:mod:`amble.modelling.virtual`) with ``H = ∂y/∂q``, the
dynamics ``M q̈ + h = Γ + B u`` give ``ÿ = L_f² y + L_g L_f y · u`` with

    L_g L_f y = H M⁻¹ B,        L_f² y = ∂(H q̇)/∂q · q̇ + H M⁻¹ (Γ − h),

and the input–output linearising law (Westervelt et al. 2007, Eq. 5.42) is

    u = (L_g L_f y)⁻¹ (−L_f² y − kp y/ε² − kd ẏ/ε),

which makes every output a critically damped (``kd² = 4 kp``) or other second-order system with
time scale ``ε``. Nothing is inverted symbolically: ``M⁻¹[B, Γ − h]`` and the ``nu × nu`` solve
are Gaussian eliminations written as a sequence of named intermediate quantities (the
``compact`` definitions of :class:`~amble.derivation.equations.Equations`), ``O(n³)`` small
expressions that the generated C evaluates in order.

On the zero-dynamics surface ``Z = {y = 0, ẏ = 0}`` of a system with one degree of
underactuation and outputs and phase *affine* in ``q`` (relative joint angles and a linear
phase, as usual), the configuration is ``q = Φ(θ)`` with ``Φ`` from the constant map
``T = ∂[h₀; θ]/∂q``, and the motion is the one-degree-of-freedom system

    θ̈ = −β (M Φ'' θ̇² + h − Γ) / (β M Φ'),       evaluated at q = Φ(θ), q̇ = Φ'(θ) θ̇,

with ``β`` a row annihilating ``B`` (the unactuated equation). :func:`zero_dynamics` returns it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import sympy as sp

from ..errors import ModelError


class _Defs:
    """A growing list of named intermediate quantities (symbol, expression)."""

    def __init__(self, prefix: str) -> None:
        self.items: list[tuple[sp.Symbol, sp.Expr]] = []
        self.prefix = prefix

    def name(self, e: Any) -> sp.Expr:
        e = sp.sympify(e)
        if e.is_Number or e.is_Symbol:
            return e
        s = sp.Symbol(f"{self.prefix}{len(self.items)}", real=True)
        self.items.append((s, e))
        return s


def _solve(defs: _Defs, A: list[list[sp.Expr]], rhs: list[list[sp.Expr]]) -> list[list[sp.Expr]]:
    """``A⁻¹ rhs`` by Gaussian elimination without pivoting (A symmetric positive definite, or a
    decoupling matrix regular on the gait), every updated entry a named quantity."""
    n, m = len(A), len(rhs[0]) if rhs else 0
    a = [list(r) + list(b) for r, b in zip(A, rhs)]
    for k in range(n):
        piv = a[k][k]
        if piv == 0:
            raise ModelError("HZD: a zero pivot in the elimination (the decoupling matrix is structurally singular)")
        for i in range(k + 1, n):
            if a[i][k] == 0:
                continue
            f = defs.name(a[i][k] / piv)
            for j in range(k + 1, n + m):
                if a[k][j] != 0:
                    a[i][j] = defs.name(a[i][j] - f * a[k][j])
    x = [[sp.Integer(0)] * m for _ in range(n)]
    for i in reversed(range(n)):
        for j in range(m):
            acc = a[i][n + j] - sum((a[i][k] * x[k][j] for k in range(i + 1, n)), sp.Integer(0))
            x[i][j] = defs.name(acc / a[i][i])
    return x


def hzd_law(model: Any, M: sp.Matrix, h: sp.Matrix, Gamma: sp.Matrix, B: sp.Matrix, prefix: str = "hzd_"
            ) -> tuple[list[tuple[sp.Symbol, sp.Expr]], sp.Matrix]:
    """The input–output linearising law of ``model.virtual``: ``(definitions, u)``, ``u`` in
    terms of the definitions (in order) and the state; ``M``, ``h`` may themselves be written
    with earlier named quantities."""
    vc = model.virtual
    q, qd = model.q, sp.Matrix(model.qd)
    n, nu = len(q), B.cols
    defs = _Defs(prefix)
    y = vc.y
    H = model.jacobian(y)
    yd = H * qd
    ddy0 = sp.zeros(nu, 1)
    for k, qk in enumerate(q):
        ddy0 += yd.applyfunc(lambda e, qk=qk: model.diff(e, qk)) * qd[k]
    Ms = [[defs.name(M[i, j]) for j in range(n)] for i in range(n)]
    f = [[defs.name(Gamma[i] - h[i])] for i in range(n)]
    X = _solve(defs, Ms, [[B[i, j] for j in range(nu)] + f[i] for i in range(n)])
    Hs = [[defs.name(H[i, j]) for j in range(n)] for i in range(nu)]
    A = [[defs.name(sum((Hs[i][k] * X[k][j] for k in range(n)), sp.Integer(0))) for j in range(nu)]
         for i in range(nu)]
    eps, kp, kd = vc.epsilon, vc.kp, vc.kd
    rhs = []
    for i in range(nu):
        lf2 = ddy0[i] + sum((Hs[i][k] * X[k][nu] for k in range(n)), sp.Integer(0))
        v = -kp * y[i] / eps**2 - kd * yd[i] / eps
        rhs.append([defs.name(v - lf2)])
    u = _solve(defs, A, rhs)
    return defs.items, sp.Matrix([r[0] for r in u])


@dataclass
class ZeroDynamics:
    """The motion on ``Z``: ``q = Phi(θ)``, ``q̇ = dPhi(θ) θ̇`` and ``θ̈ = theta_ddot(θ, θ̇)``;
    all expressions of ``theta``, ``theta_dot`` and the model's parameters."""

    theta: sp.Symbol
    theta_dot: sp.Symbol
    Phi: sp.Matrix
    dPhi: sp.Matrix
    theta_ddot: sp.Expr


def zero_dynamics(model: Any, M: sp.Matrix, h: sp.Matrix, Gamma: sp.Matrix, B: sp.Matrix) -> ZeroDynamics:
    """The zero dynamics of ``model.virtual`` (one degree of underactuation; outputs and phase
    affine in ``q``; ``B`` constant) from the expanded ``M``, ``h`` and passive ``Γ``."""
    vc = model.virtual
    q = model.q
    n = len(q)
    if vc is None or B.cols != n - 1:
        raise ModelError(f"model {model.name!r}: zero dynamics need virtual constraints with one input fewer "
                         "than coordinates")
    c = sp.Matrix([*vc.outputs, vc.phase])
    T = c.jacobian(q)
    if any(e.free_symbols & set(q) for e in T) or any(e.free_symbols & set(q) for e in B):
        raise ModelError(f"model {model.name!r}: zero dynamics need outputs, phase and B affine in q")
    th, thd = sp.Symbol("theta", real=True), sp.Symbol("theta_dot", real=True)
    c0 = c.subs({qi: 0 for qi in q})
    Tinv = T.inv()
    Phi = Tinv * (sp.Matrix([*vc.desired(th), th]) - c0)
    dPhi = Phi.diff(th)
    ddPhi = dPhi.diff(th)
    beta = B.T.nullspace()[0].T
    on_z = {**{qi: Phi[i] for i, qi in enumerate(q)}, **{vi: dPhi[i] * thd for i, vi in enumerate(model.qd)}}
    Mz, hz, gz = M.xreplace(on_z), h.xreplace(on_z), Gamma.xreplace(on_z)
    num = (beta * (Mz * ddPhi * thd**2 + hz - gz))[0, 0]
    den = (beta * Mz * dPhi)[0, 0]
    return ZeroDynamics(th, thd, Phi, dPhi, -num / den)
