"""Hybrid zero dynamics of a walker, numerically: invariance of the impact, gait design, the
restricted Poincaré map.

On ``Z ∩ S`` — the zero-dynamics surface at the footfall, ``q⁻ = Φ(θ⁻)``, ``q̇⁻ = Φ'(θ⁻) θ̇⁻``
— the compiled impact map gives ``x⁺ = Δ(x⁻)``. ``Z`` is *hybrid invariant* when ``x⁺`` lies on
``Z`` again: ``y(q⁺) = 0`` and ``ẏ(q⁺, q̇⁺) = 0``. Both are homogeneous in ``θ̇⁻`` (the impact is
linear in the velocities), so ``θ̇⁻ = 1`` tells for every speed. With invariance, the restricted
Poincaré map of ``ζ = θ̇²/2`` at the footfall is affine, ``ζ_{k+1} = δ² ζ_k − V_zero(θ⁻)``, with
``δ = θ̇⁺/θ̇⁻`` (Westervelt et al. 2007, Thm. 5.3): its one multiplier is ``δ²``, the limit of the
full-order multipliers as ``ε → 0``.
"""

from __future__ import annotations

import weakref
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
import sympy as sp
from scipy.integrate import solve_ivp

from ..backend.kernels import compiled
from ..derivation.equations import derive
from ..derivation.hzd import zero_dynamics
from ..errors import ModelError
from ..modelling.hybrid import HybridSystem
from ..simulation.simulate import parameter_vector


@dataclass
class ImpactOnZ:
    """The footfall from ``Z ∩ S`` at ``θ̇⁻ = 1``: post-impact state, ``δ = θ̇⁺``, the output
    and its rate after it (zero when ``Z`` is hybrid invariant), and the guard before it."""

    x_post: np.ndarray
    delta: float
    y: np.ndarray
    y_dot: np.ndarray
    guard: float

    @property
    def error(self) -> float:
        """Hybrid-invariance error: ``max(|y⁺|, |ẏ⁺|/|θ̇⁺|)`` (rad)."""
        return float(max(np.max(np.abs(self.y)), np.max(np.abs(self.y_dot)) / abs(self.delta)))



def _controlled_mode(system: HybridSystem):
    mode, model = next(((n, m) for n, m in system.modes.items() if m.virtual is not None), (None, None))
    if model is None:
        raise ModelError(f"system {system.name!r} has no virtual constraints")
    step = next((tr for tr in system.transitions if tr.step and tr.source == mode), None)
    if step is None:
        raise ModelError(f"system {system.name!r}: no footfall from mode {mode!r}")
    return mode, model, step


@dataclass
class _Functions:
    """NumPy functions of one model's zero dynamics and outputs (arguments: the named state or
    phase values, then the parameters in the model's order)."""

    Phi: Any
    dPhi: Any
    a: Any  # θ̈ at θ̇ = 0
    a1: Any  # θ̈ at θ̇ = 1
    y: Any
    y_dot: Any
    phase_rate: Any
    h0: Any
    h0_rate: Any
    phase: Any


_CACHE: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def zero_dynamics_functions(model: Any) -> _Functions:
    """NumPy functions of a model's zero dynamics (Φ, Φ', θ̈ at θ̇ = 0 and 1) and of its outputs,
    phase and their rates (cached per model; arguments: the values, then the parameters)."""
    hit = _CACHE.get(model)
    if hit is not None:
        return hit
    eq = derive(model)
    zd = zero_dynamics(model, eq.M, eq.h, eq.Gamma, eq.B)
    vc = model.virtual
    ps, q, qd = list(model.params), list(model.q), sp.Matrix(model.qd)
    th, thd = zd.theta, zd.theta_dot
    lam = lambda args, e: sp.lambdify([*args, *ps], e, "numpy", cse=True)
    acc = zd.theta_ddot
    H = model.jacobian(vc.y)
    dh0 = vc.outputs.jacobian(q)
    dth = sp.Matrix([vc.phase]).jacobian(q)
    x = [*q, *model.qd]
    hit = _Functions(
        Phi=lam([th], list(zd.Phi)), dPhi=lam([th], list(zd.dPhi)),
        a=lam([th], acc.xreplace({thd: 0})), a1=lam([th], acc.xreplace({thd: 1})),
        y=lam(x, list(vc.y)), y_dot=lam(x, list(H * qd)), phase_rate=lam(x, (dth * qd)[0]),
        h0=lam(x, list(vc.outputs)), h0_rate=lam(x, list(dh0 * qd)), phase=lam(x, vc.phase))
    _CACHE[model] = hit
    return hit


def impact_on_zero_dynamics(system: HybridSystem, params: Mapping[str, float] | None = None) -> ImpactOnZ:
    """The footfall from ``Z ∩ S`` (see the module), at these parameters."""
    mode, model, step = _controlled_mode(system)
    k = compiled(system)
    p = parameter_vector(k, params, system)
    pv = dict(zip(k.meta["params"], p.tolist()))
    fn = zero_dynamics_functions(model)
    pm = [pv[str(s)] for s in model.params]
    th_end = pv[str(model.virtual.phase_end)]
    x_pre = np.concatenate([np.asarray(fn.Phi(th_end, *pm), float), np.asarray(fn.dPhi(th_end, *pm), float)])
    names = [tr.name for tr in system.transitions if tr.source == mode]
    g = float(k.guards(mode, 0.0, x_pre, p)[names.index(step.name)])
    _, x_post = k.reset(step.name, 0.0, x_pre, p)
    if system.modes[step.target] is not model:
        raise ModelError(f"system {system.name!r}: the footfall must return to the controlled mode")
    args = [*x_post, *pm]
    return ImpactOnZ(np.asarray(x_post, float), float(fn.phase_rate(*args)), np.asarray(fn.y(*args), float),
                     np.asarray(fn.y_dot(*args), float), g)


def hybrid_invariance_error(system: HybridSystem, params: Mapping[str, float] | None = None) -> float:
    """How far the impact leaves the zero-dynamics surface: ``max(|y⁺|, |ẏ⁺|/|θ̇⁺|)`` (rad)."""
    return impact_on_zero_dynamics(system, params).error


def invariant_parameters(system: HybridSystem, params: Mapping[str, float] | None = None) -> dict[str, float]:
    """The parameters with ``phase_start``, ``α_{i,0}`` and ``α_{i,1}`` replaced so that ``Z`` is
    hybrid invariant (Westervelt et al. 2007, Thm. 6.5): ``α₀ = h₀(q⁺)``, ``θ⁺ = θ(q⁺)`` and
    ``α₁ = α₀ + (θ⁻ − θ⁺)/M · (∂h₀/∂q q̇⁺)/(∂θ/∂q q̇⁺)`` — the post-impact state depends only on
    ``α_M``, ``α_{M−1}`` and ``θ⁻`` (degree ``M ≥ 3``)."""
    _, model, _ = _controlled_mode(system)
    vc = model.virtual
    if vc.degree < 3:
        raise ModelError(f"model {model.name!r}: invariant Bézier coefficients need degree ≥ 3")
    out = dict(system.parameters)
    out.update(params or {})
    imp = impact_on_zero_dynamics(system, out)
    fn = zero_dynamics_functions(model)
    args = [*imp.x_post, *[out[str(s)] for s in model.params]]
    h0, dh0 = np.asarray(fn.h0(*args), float), np.asarray(fn.h0_rate(*args), float)
    th_plus = float(fn.phase(*args))
    th_end = out[str(vc.phase_end)]
    out[str(vc.phase_start)] = th_plus
    for i in range(vc.alpha.rows):
        out[str(vc.alpha[i, 0])] = float(h0[i])
        out[str(vc.alpha[i, 1])] = float(h0[i] + (th_end - th_plus) / vc.degree * dh0[i] / imp.delta)
    return out


@dataclass
class RestrictedMap:
    """The restricted Poincaré map ``ζ⁺ ↦ δ² (A ζ⁺ + C)`` of ``ζ = θ̇²/2`` (see the module), its
    fixed point ``zeta_plus`` and multiplier ``δ² A``, and the full post-impact state of that
    gait on ``Z`` (``x_post``; a guess for :func:`~amble.analysis.poincare.find_fixed_point`)."""

    A: float
    C: float
    delta: float
    zeta_plus: float
    multiplier: float
    x_post: np.ndarray
    min_zeta: float  # smallest ζ over the step: > 0 when θ̇ keeps its sign (the gait exists)


def restricted_map(system: HybridSystem, params: Mapping[str, float] | None = None) -> RestrictedMap:
    """The restricted Poincaré map of the zero dynamics at these parameters (gravity the only
    force besides the inputs)."""
    _, model, _ = _controlled_mode(system)
    pv = dict(system.parameters)
    pv.update(params or {})
    if any(e != 0 for e in model.generalized_force):
        raise ModelError(f"model {model.name!r}: the restricted map needs Γ = 0 besides the inputs")
    fn = zero_dynamics_functions(model)
    pm = [pv[str(s)] for s in model.params]
    a = lambda th: float(fn.a(th, *pm))
    a1 = lambda th: float(fn.a1(th, *pm))
    vc = model.virtual
    th0, th1 = pv[str(vc.phase_start)], pv[str(vc.phase_end)]

    def rhs(th: float, z: np.ndarray) -> list[float]:
        av = a(th)
        b2 = 2.0 * (a1(th) - av)
        return [av + b2 * z[0], b2 * z[1]]

    sol = solve_ivp(rhs, (th0, th1), [0.0, 1.0], rtol=1e-12, atol=1e-14, dense_output=True)
    C, A = float(sol.y[0, -1]), float(sol.y[1, -1])
    imp = impact_on_zero_dynamics(system, pv)
    d2 = imp.delta**2
    zp = d2 * C / (1.0 - d2 * A) if d2 * A != 1.0 else float("nan")
    grid = np.linspace(th0, th1, 201)
    zs = sol.sol(grid)
    min_zeta = float(np.min(zs[0] + zp * zs[1]))
    n = len(model.q)
    speed = np.sqrt(2.0 * zp) / imp.delta if zp > 0 else float("nan")  # θ̇⁻ of the gait
    x_post = np.concatenate([imp.x_post[:n], imp.x_post[n:] * speed])
    return RestrictedMap(A, C, imp.delta, zp, d2 * A, x_post, min_zeta)
