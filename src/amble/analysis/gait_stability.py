"""Stability of an HZD gait as a constraint of its optimisation: the multiplier of the restricted
Poincaré map.

On the hybrid zero dynamics of a robot with one degree of underactuation the Poincaré map is
one-dimensional. Let ``σ = b⊥ᵀ M(q) q̇`` be the momentum conjugate to the unactuated direction
(``b⊥`` spans the left null space of a constant ``B``, so the inputs drop out of
``σ̇ = b⊥ᵀ(Ṁ q̇ − h + Γ)``). When ``σ̇`` depends on the coordinates only — the unactuated
coordinate an absolute angle on which the kinetic energy does not depend, no damping — then on
the zero-dynamics surface ``Z`` (``q = Φ(θ)``, ``σ = I(θ) θ̇``) the quantity ``ζ = σ²/2`` changes
over a step by an amount that depends on ``θ`` only, and the impact multiplies ``σ`` by a
constant ``δ_zero = σ⁺/σ⁻``. The restricted map is

    ``ζ⁻_{k+1} = δ_zero² ζ⁻_k − V_zero(θ⁻)``

(Westervelt, Grizzle & Koditschek, IEEE TAC 48(1), 2003, Thm. 2 and Eq. 50; Westervelt et al.,
*Feedback Control of Dynamic Bipedal Robot Locomotion*, 2007, §5.4–5.5): its one multiplier is
``δ_zero²``. On a gait of the optimisation (``hzd=True``) both ends of the step lie on ``Z``, so
``δ_zero² = (σ(x⁺)/σ(x⁻))²`` is a smooth function of the first and the last collocated states —
exact, not a discretisation of anything, and differentiated by CasADi like every other
constraint. With the virtual constraints hybrid invariant (the gait's periodicity makes them so)
the closed-loop orbit lies on ``Z`` and one full-order multiplier equals ``δ_zero²`` for every
output gain; the others (transverse to ``Z``) vanish as the gain grows (``ε → 0``), so with a
fast enough output controller the spectral radius of the closed loop is ``δ_zero²``
(Westervelt et al. 2007, Thm. 5.3 and Cor. 5.2; Morris & Grizzle, IEEE TAC 54(8), 2009).

:func:`closed_loop_stability` checks that afterwards, independently of the formula: Newton on the
compiled closed loop's exact return map and its multipliers from the variational equations.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from ..backend.casadi_export import StepFunctions, casadi_module
from ..errors import ConvergenceError, ParameterError, StateError
from ..modelling.hybrid import HybridSystem
from .gait_result import Gait
from .poincare import find_fixed_point


def momentum_function(fns: StepFunctions, x_guess: np.ndarray, P: np.ndarray) -> Any:
    """``σ(q, q̇, p) = b⊥ᵀ M(q) q̇`` as a CasADi function, after checking (at the guessed points)
    that it is the zero dynamics' momentum: one unactuated direction of a constant ``B`` and
    ``σ̇`` independent of the velocities. :class:`ParameterError` otherwise."""
    ca = casadi_module()
    n, nu = fns.n, fns.nu
    if nu == 0:
        raise ParameterError("a stability constraint needs inputs: the model declares no actuators")
    Bs = [np.asarray(fns.input_matrix(x[:n], P), float).reshape(n, nu) for x in x_guess[:: max(1, len(x_guess) // 5)]]
    if any(np.abs(b - Bs[0]).max() > 1e-12 * max(np.abs(Bs[0]).max(), 1.0) for b in Bs):
        raise ParameterError("a stability constraint needs actuated quantities linear in q (a constant B)")
    U, sv, _ = np.linalg.svd(Bs[0])
    rank = int(np.sum(sv > 1e-10 * max(sv.max(initial=0.0), 1.0)))
    if rank != n - 1:
        raise ParameterError(f"a stability constraint needs exactly one unactuated direction (the restricted "
                             f"map is one-dimensional); the model has {n - rank}")
    b = U[:, -1]
    q, v = ca.SX.sym("q", n), ca.SX.sym("v", n)
    p = ca.SX.sym("p", len(fns.param_names))
    zero_u, zero_t = ca.SX.zeros(nu), ca.SX(0.0)
    rest = fns.dynamics(q, v, ca.SX.zeros(n), zero_u, zero_t, p)  # h − Γ
    Mv = fns.dynamics(q, v, v, zero_u, zero_t, p) - rest  # the residual is linear in the accelerations
    sigma = ca.dot(ca.DM(b), Mv)
    # σ̇ = b⊥ᵀ(Ṁ q̇ + M q̈) = b⊥ᵀ(Ṁ q̇ − h + Γ): the restricted map is affine in σ²/2 only when
    # this does not depend on q̇
    rate = ca.Function("rate", [q, v, p], [ca.jtimes(sigma, q, v) - ca.dot(ca.DM(b), rest)])
    rng = np.random.default_rng(0)
    for x in x_guess[:: max(1, len(x_guess) // 3)]:
        vv = rng.standard_normal(n)
        r1, r0 = float(rate(x[:n], vv, P)), float(rate(x[:n], np.zeros(n), P))
        scale = max(abs(r0), float(np.abs(np.asarray(fns.dynamics(x[:n], vv, 0 * vv, np.zeros(nu), 0.0, P))).max()),
                    1.0)
        if abs(r1 - r0) > 1e-8 * scale:
            raise ParameterError("a stability constraint needs the unactuated momentum's rate to depend on the "
                                 "coordinates only (an unactuated absolute angle, no damping): the restricted "
                                 "Poincaré map is not one-dimensional-affine here")
    return ca.Function("sigma", [q, v, p], [sigma], ["q", "qd", "p"], ["sigma"])


def period_multiplier(sigmas: list[Any], starts: list[Any], ends: list[Any], Ps: list[Any], n: int) -> Any:
    """The restricted Poincaré map's multiplier over a period of steps ``j`` (each from
    ``starts[j]`` to ``ends[j]``, its zero dynamics' momentum ``sigmas[j]``): the product of each
    footfall's ``δ_j² = (σ_{j+1}(x⁺_{j+1})/σ_j(x⁻_j))²`` — the map of a period is the composition
    of the steps' maps ``ζ ↦ δ_j² ζ − V_j``, each impact taking the momentum of one mode's zero
    dynamics to the next's (two stance modes: left, then right). One step: ``δ_zero²``."""
    S = len(sigmas)
    out = 1.0
    for j in range(S):
        k = (j + 1) % S
        out = out * (sigmas[k](starts[k][:n], starts[k][n:], Ps[k]) / sigmas[j](ends[j][:n], ends[j][n:], Ps[j])) ** 2
    return out


def restricted_multiplier(sigma: Any, x_post: Any, x_pre: Any, P: Any, n: int) -> Any:
    """``δ_zero² = (σ(x⁺)/σ(x⁻))²`` of a step from ``x_post`` to ``x_pre`` (CasADi expressions;
    with NumPy states a CasADi ``DM``)."""
    return (sigma(x_post[:n], x_post[n:], P) / sigma(x_pre[:n], x_pre[n:], P)) ** 2


def period_rows(add: Any, Xs: list[Any], Ls: list[Any], Ts: list[Any], sigmas: list[Any] | None,
                 Ps: list[np.ndarray], n: int, speed: float | None, max_multiplier: float | None) -> None:
    """The constraints on a whole period: its pace, and the bound on the restricted Poincaré
    map's multiplier over it (on a solve with the virtual constraints, ``sigmas`` given)."""
    if max_multiplier is not None and sigmas is not None:
        add("stability", period_multiplier(sigmas, [X[:, 0] for X in Xs], [X[:, -1] for X in Xs], Ps, n),
            -np.inf, max_multiplier)
    if speed is not None:
        add("speed", sum(Ls[1:], Ls[0]) - speed * sum(Ts[1:], Ts[0]))


def stability_report(sigmas: list[Any] | None, gaits: list[Gait], Ps: list[np.ndarray], n: int,
                      max_multiplier: float | None) -> dict[str, Any] | None:
    if sigmas is None:
        return None
    value = float(period_multiplier(sigmas, [g.fixed_point for g in gaits], [g.pre_impact_state for g in gaits],
                                    Ps, n))
    return {"restricted_multiplier": value, "max_multiplier": max_multiplier}


def momenta(fnss: list[StepFunctions], x_guesses: list[np.ndarray], Ps: list[np.ndarray],
             max_multiplier: float | None, wanted: bool) -> list[Any] | None:
    """The zero dynamics' momentum σ of each step of an HZD gait (``wanted``;
    :func:`~amble.analysis.gait_stability.momentum_function`), or None where it does not exist and
    no bound asks for it."""
    if not wanted:
        return None
    try:
        return [momentum_function(f, x, P) for f, x, P in zip(fnss, x_guesses, Ps)]
    except ParameterError:
        if max_multiplier is not None:
            raise
        return None


def closed_loop_stability(system: HybridSystem, gait: Any, params: Mapping[str, float] | None = None) -> dict:
    """The full-order multipliers of the closed loop that walks ``gait`` (an HZD gait of a model
    with its own virtual constraints: ``gait.bezier["params"]``), by Newton on the compiled
    closed loop's exact return map from ``gait.fixed_point``. ``params``: other parameter
    values (e.g. the output gain ``epsilon``). Stored in ``gait.stability["closed_loop"]`` and
    returned: ``multipliers`` (``[re, im]`` pairs, by decreasing modulus), ``spectral_radius``,
    ``residual``, ``fixed_point_distance`` (from the collocated fixed point), or ``error`` when
    Newton does not converge."""
    bz = gait.bezier or {}
    if "params" not in bz:
        raise StateError("the gait has no parameters of the model's own virtual constraints (an HZD gait of a "
                         "model that declares them): there is no closed loop to check")
    values = {**gait.params, **bz["params"], **dict(params or {})}
    try:
        lc = find_fixed_point(system, gait.fixed_point, params=values)
    except ConvergenceError as e:
        out: dict[str, Any] = {"error": str(e)}
    else:
        mu = np.asarray(lc.multipliers, complex)
        mu = mu[np.argsort(-np.abs(mu))]
        out = {"multipliers": [[float(z.real), float(z.imag)] for z in mu],
               "spectral_radius": float(np.abs(mu).max(initial=0.0)), "residual": float(lc.residual),
               "fixed_point_distance": float(np.abs(lc.fixed_point - gait.fixed_point).max())}
    if gait.stability is None:
        gait.stability = {}
    gait.stability["closed_loop"] = out
    return out

