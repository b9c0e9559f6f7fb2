"""Gait design by optimisation: one periodic step of a walker (or a period of several steps,
``steps=2``) by direct collocation.

The unknowns are the states, accelerations and inputs at the ``2N + 1`` Hermite–Simpson points of
one step (:mod:`amble.analysis.collocation`), the free step time ``T``, and the impact's
post-impact extended velocity and impulse. The constraints are

* the equations of motion ``M(q) q̈ + h = Γ + B u`` at every point (implicit: no ``M⁻¹``),
* the collocation defects,
* the footfall: the guard ``g(x(T)) = 0`` with its enabling condition, then the derived plastic
  impact ``M_e (q̇e⁺ − q̇e⁻) = Jᵀλ, J q̇e⁺ = 0`` and the relabelling, which must give back the
  first state (periodicity),
* the speed ``L/T = V`` or the step length ``L``, ``L`` the impacting foot's distance ahead of the
  stance foot along the slope,
* actuator limits ``|u| ≤ limit`` (``Model.input_limits``), joint limits (a tree's joint limits and
  ``bounds``), unilateral contact ``F_n ≥ 0`` and, with ``mu``, the friction cone ``|F_t| ≤ μ F_n``
  at the stance foot over the whole step, a non-negative normal impulse at impact (and the old
  stance foot leaving the ground), and, with ``clearance``, the swing foot at least
  ``clearance · 4s(1 − s)`` above the ground at phase ``s = t/T``.

Objectives, all per unit distance walked: ``effort`` ``(1/L) ∫ ‖u‖² dt``, ``cot`` (cost of
transport) ``(1/(mₜ g L)) ∫ Σ |u_j v_j| dt`` with ``v = Bᵀq̇`` (each power split into its positive
and negative parts, ``u_j v_j = p⁺ − p⁻``, ``p± ≥ 0``, so that ``|u_j v_j| = p⁺ + p⁻`` at the optimum
without a kink), or a user expression
``c(q, q̇, u)``: ``(1/L) ∫ c dt``. With a pace given, ``L`` in the objective is its constrained value
(``V T`` or the step length), which keeps the objective bounded away from feasible points.
CasADi builds the problem from amble's derived expressions (:mod:`amble.backend.casadi_export`)
with exact sparse first and second derivatives; IPOPT solves it.
"""

from __future__ import annotations

import weakref
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import sympy as sp

from ..backend.cache import fingerprint
from ..backend.casadi_export import StepFunctions, casadi_module, step_functions
from ..errors import ParameterError
from ..modelling.footfall_cycle import cycle_footfalls
from ..modelling.hybrid import HybridSystem
from .collocation import defects, simpson_weights
from .gait_hzd import bezier_start, controller_key, virtual_constraints
from .gait_ipopt import raise_with_gait, solve_keeping_feasible
from .gait_layout import _bound_groups, _bounds, _gait
from .gait_options import _check_options, _check_stability_option, _expression, _integrand, _parameters
from .gait_result import Gait
from .gait_stability import momenta, period_rows, stability_report
from .gait_stages import period_gait, solve_stages
from .gait_start import initial_guess, start_vector

OBJECTIVES = ("effort", "cot")
#: a step whose equations of motion and contact force take more CasADi instructions than this is
#: solved on the problem expanded to scalar operations (``expand``): a 9-coordinate 3D tree biped
#: (7850) then takes 5.9 s of IPOPT instead of 24 s, paying 8 s to expand; RABBIT (860) would
#: pay more to expand (0.3 s more per design) than it saves
EXPAND_SIZE = 4000

def optimize_gait(
    system: HybridSystem,
    *,
    params: Mapping[str, float] | None = None,
    speed: float | None = None,
    step_length: float | None = None,
    objective: str | sp.Expr = "effort",
    nodes: int | Sequence[int] = 30,
    guess: str | Sequence[float] | None = None,
    step_time: float | None = None,
    posture: Sequence[float] | None = None,
    mu: float | None = None,
    clearance: float | None = None,
    bounds: Mapping[str, tuple[float | None, float | None]] | None = None,
    bezier_degree: int | None = None,
    phase: Any = None,
    max_iter: int = 500,
    tol: float = 1e-10,
    hzd: bool | None = None,
    progress: bool = False,
    steps: int | None = None,
    step_params: Sequence[Mapping[str, float]] | None = None,
    max_multiplier: float | None = None,
) -> Gait:
    """A periodic one-step gait of a one-mode walker that minimises ``objective``.

    ``speed`` (m/s) or ``step_length`` (m) fix the gait's pace (at most one; neither leaves it
    free). ``objective``: ``"effort"``, ``"cot"`` or an integrand (sympy expression or text in the
    model's coordinates, velocities, inputs and parameters). ``nodes``: collocation intervals; a
    list (e.g. ``[20, 60]``) solves on each mesh in turn, each started from the previous solution
    (mesh refinement: the coarse solve finds the gait, the fine one makes it accurate).
    ``guess``: a post-impact state to start from (walked passively for one step where that
    works), ``"passive"`` (a passive step on the system's own gait: the default of a model
    without feedback), ``"stand"`` (standing still in the posture of the system's guess for
    ``step_time``: the default of a model under feedback, e.g. with virtual constraints) or
    ``"interpolate"`` (from that posture to the relabelled one); see
    :func:`~amble.analysis.gait_start.initial_guess`. A start without motion is solved first for
    the constraints alone (see :func:`~amble.analysis.gait_stages.solve_stages`).
    ``posture``: the coordinates (rad, m) of a ``"stand"`` or ``"interpolate"`` start instead of
    the system's guess (e.g. a stride held still in double support).
    ``bounds``: ``{state name: (low, high)}`` limits on coordinates or velocities at every point.
    ``bezier_degree``, ``phase``: the Bézier virtual constraints reported with the gait (the phase
    an expression of the coordinates). For a model that declares virtual constraints
    (:meth:`Model.virtual_constraints`) both default to its own — its phase, its outputs and its
    degree — and ``bezier["params"]`` holds its ``alpha``/``phase_start``/``phase_end`` parameter
    values for the gait; otherwise the outputs are the actuated quantities ``B_jᵀ q``, the degree 5
    and the phase the hip's distance ahead of the stance foot.
    ``hzd``: the gait satisfies its virtual constraints exactly — each output is a Bézier
    polynomial (coefficients unknowns of the problem) in the phase at the mesh points — so that
    the HZD controller with the exported ``bezier`` (the optimised ``α``) reproduces it (FROST's
    formulation). Default: on for a model that declares virtual constraints, off otherwise.
    ``progress``: solver iterations and constraint violation on stderr.
    ``steps``: steps per period (default 1). With ``steps=2`` each step has its own unknowns,
    footfall, impact and relabelling into the next step (the last into the first); a ``speed``
    holds over the period, a ``step_length`` for each step, the objective is the period's per unit
    distance; ``step_params`` (one mapping per step) overrides parameter values step by step
    (e.g. leg masses of a robot whose legs differ, swapped from one step to the next). The
    result's fields are the first step's and :attr:`Gait.steps` holds every step.
    ``max_multiplier``: an upper bound on the multiplier ``δ_zero²`` of the restricted Poincaré map
    of an HZD gait (one step, one unactuated absolute angle; :mod:`~amble.analysis.gait_stability`),
    the spectral radius of the closed loop under a fast enough output controller: e.g. ``0.5``.
    An HZD gait reports ``δ_zero²`` in :attr:`Gait.stability`;
    :func:`~amble.analysis.gait_stability.closed_loop_stability` adds the closed loop's
    multipliers.

    Raises :class:`ParameterError` / :class:`StateError` / :class:`ModelError` on bad input and
    :class:`SolverError` (naming the reason and the most violated constraint) when IPOPT fails.
    """
    ca = casadi_module()
    footfalls = cycle_footfalls(system)
    S = _period_length(system, footfalls, steps)
    hzd, bezier_degree = _check_options(system, speed, step_length, mu, step_time, clearance, nodes, hzd,
                                        bezier_degree, max_iter, S)
    _check_stability_option(max_multiplier, hzd, S)
    pvals = _parameters(system, params)
    if step_params is not None and len(step_params) != S:
        raise ParameterError(f"step_params must hold one mapping per step ({S}), got {len(step_params)}")
    pvs = [_parameters(system, {**pvals, **dict(sp_ or {})}) for sp_ in (step_params or [{}] * S)]
    models, fnss, nothing_to_optimise = _period_functions(system, footfalls, S, objective, phase)
    fns = fnss[0]
    n, nu, d = fns.n, fns.nu, fns.dims
    Ps = [np.array([pv[k] for k in f.param_names]) for f, pv in zip(fnss, pvs)]

    levels = [nodes] if isinstance(nodes, int) else list(nodes)
    guesses = initial_guess(system, fnss, pvals, guess, levels[0], step_time, posture, steps=S)
    x_guesses, t_guesses = [x for x, _ in guesses], [t for _, t in guesses]
    sigmas = momenta(fnss, x_guesses, Ps, max_multiplier, hzd)

    def solve(N: int, x_guesses: list[np.ndarray], t_guesses: list[float], warms: list[Gait] | None, hzd: bool,
              feasibility: bool = False, refine: bool = True) -> list[Gait]:
        """One NLP over the ``S`` steps of a period: a block of unknowns per step ``(X, A, U, T, qe,
        λ, power, α)``; each step's footfall, impact and relabelling lead into the next step's first
        state, the last step's into the first's."""
        K = 2 * N + 1
        cot = isinstance(objective, str) and objective == "cot"
        Mb = bezier_degree
        groups: list[tuple[str, Any, float, float]] = []  # (name, expression, lower, upper)

        def add(name: str, expr: Any, lo: float = 0.0, hi: float = 0.0) -> None:
            if expr.numel():
                groups.append((name, ca.vec(expr), lo, hi))

        ws, lbws, ubws, w0s, bound_groups = [], [], [], [], []
        Xs, QEs, Ts, integrals, dists, Ls = [], [], [], [], [], []
        wts = ca.DM(simpson_weights(N))
        offset = 0
        # the Bézier coefficients of steps whose modes name them alike (a walker whose stance
        # feet are modes with one mirrored controller) are one set of unknowns, with one phase
        # range: the parameters the controller runs on have one value
        owners: dict[tuple, tuple[int, Any]] = {}
        alpha_at: list[tuple[int, int]] = []  # per step: where its coefficients are in the unknowns
        for j in range(S):
            Pj, xg, tg, wj = Ps[j], x_guesses[j], t_guesses[j], warms[j] if warms else None
            fns = fnss[j]
            # MX with each model function mapped over the points: the graph holds one copy of each
            # function, not 2N + 1 inlined ones (building the problem is then independent of N)
            X, A, U = ca.MX.sym(f"x{j}", 2 * n, K), ca.MX.sym(f"a{j}", n, K), ca.MX.sym(f"u{j}", nu, K)
            Tv, QE, LAM = ca.MX.sym(f"T{j}"), ca.MX.sym(f"qe{j}", n + d), ca.MX.sym(f"lam{j}", d)
            PW = ca.MX.sym(f"power{j}", 2 * nu if cot else 0, K)  # positive and negative parts of each power
            key = controller_key(fns) if hzd else None
            owner = owners.get(key) if key is not None else None
            AL = ca.MX.sym(f"alpha{j}", nu if hzd else 0, Mb + 1) if owner is None else owner[1]
            ALw = AL if owner is None else ca.MX(0, 1)  # in this step's unknowns, or in the owner's
            w = ca.vertcat(ca.vec(X), ca.vec(A), ca.vec(U), Tv, QE, LAM, ca.vec(PW), ca.vec(ALw))
            h = Tv / N
            taus = ca.DM(np.arange(K)[None, :] / 2.0) * h
            Q, V = X[:n, :], X[n:, :]
            F = ca.vertcat(V, A)
            add("dynamics", fns.dynamics.map(K)(Q, V, A, U, taus, Pj))
            add("collocation", ca.vertcat(*defects([X[:, 0:-1:2], X[:, 1::2], X[:, 2::2]],
                                                   [F[:, 0:-1:2], F[:, 1::2], F[:, 2::2]], h)))
            qN, vN = X[:n, -1], X[n:, -1]
            add("impact", fns.impact(qN, vN, QE, LAM, Pj))
            add("guard", fns.guard(qN, vN, Pj))
            add("guard_enabled", fns.enabled(qN, vN, Pj), 0.0, np.inf)
            L = fns.distance(qN, Pj)
            if step_length is not None:
                add("step_length", L - step_length)
            nrm = fns.normal(Pj)
            add("impact_impulse", ca.dot(nrm, LAM), 0.0, np.inf)
            add("liftoff", ca.dot(nrm, QE[n:]), 0.0, np.inf)
            forces = fns.contact.map(K)(Q, V, A, Pj)  # d × K
            normals = ca.mtimes(nrm.T, forces)
            add("contact", normals, 0.0, np.inf)
            if mu is not None:
                tangential = forces - ca.mtimes(nrm, normals)
                add("friction", mu**2 * normals**2 - ca.sum1(tangential**2), 0.0, np.inf)
            if clearance is not None and K > 2:
                s_ = np.arange(1, K - 1) / (K - 1)
                lift = fns.guard.map(K - 2)(Q[:, 1:-1], V[:, 1:-1], Pj)
                add("clearance", lift - ca.DM(clearance * 4 * s_ * (1 - s_))[:, 0].T, 0.0, np.inf)
            if hzd:
                add("virtual_constraints", virtual_constraints(fns, X, Pj, xg, AL))
                if owner is not None:  # the same phase range as the step that owns the coefficients
                    X0, f0, P0 = Xs[owner[0]], fnss[owner[0]], Ps[owner[0]]
                    add("shared_phase", ca.vertcat(fns.phase(X[:n, 0], Pj) - f0.phase(X0[:n, 0], P0),
                                                   fns.phase(X[:n, -1], Pj) - f0.phase(X0[:n, -1], P0)))
            if cot:  # |power| = its positive plus its negative part, each ≥ 0
                add("power", U * fns.actuator_rates.map(K)(Q, V, Pj) - (PW[:nu, :] - PW[nu:, :]))
            run, scale = _running_cost(ca, fns, objective, U, PW, Q, V, taus, Pj)
            integrals.append(scale * h * ca.mtimes(run, wts))
            # per unit distance: with the pace given, the distance is divided by its constrained
            # value (V T or the step length), not by the foot's position — equal at a feasible
            # point, but away from one (standing still: the swing foot behind the stance foot,
            # L ≤ 0) L is not bounded away from zero and the objective ∫u²/L is unbounded below
            dists.append(speed * Tv if speed is not None else step_length if step_length is not None else L)
            Xs.append(X)
            QEs.append(QE)
            Ts.append(Tv)
            Ls.append(L)
            # bounds
            lbw, ubw = _bounds(models[j], fns, bounds, N, tg)
            if feasibility:
                # the step time held at the guess's: free, it collapses to its lower bound (standing
                # still, the defects h·f of a falling robot shrink with h = T/N), where no step fits
                it = (3 * n + nu) * K
                lbw[it] = ubw[it] = tg
            lbws.append(np.concatenate([lbw, np.zeros(PW.numel()), np.full(ALw.numel(), -np.inf)]))
            ubws.append(np.concatenate([ubw, np.full(PW.numel() + ALw.numel(), np.inf)]))
            alpha0 = (np.array(wj.bezier["alpha"]) if hzd and wj is not None and wj.bezier
                      else bezier_start(fns, xg, Pj, Mb) if hzd else np.zeros(0))
            alpha0 = alpha0 if owner is None else np.zeros(0)
            if owner is None and key is not None:
                owners[key] = (j, AL)
            alpha_at.append((offset + w.numel() - AL.numel(), offset + w.numel()) if owner is None
                            else alpha_at[owner[0]])
            w0s.append(np.concatenate([start_vector(fns, xg, tg, N, Pj, wj), np.zeros(PW.numel()),
                                       alpha0.ravel(order="F")]))
            bound_groups += [(name, offset + lo, offset + hi) for name, lo, hi in _bound_groups(fns, N)]
            offset += w.numel()
            ws.append(w)
        for j in range(S):  # each footfall leads into the next step (the last into the first)
            qN = Xs[j][:n, -1]
            add("periodicity", fnss[j].relabel(qN, QEs[j], Ps[j]) - Xs[(j + 1) % S][:, 0])
        period_rows(add, Xs, Ls, Ts, sigmas if hzd else None, Ps, n, speed, max_multiplier)
        J = sum(integrals[1:], integrals[0]) / sum(dists[1:], dists[0])
        if feasibility:
            # a first solve from a start without motion looks for any step (no objective): see gait_stages.solve_stages
            J = ca.MX(0.0)
        w = ca.vertcat(*ws)
        lbw, ubw = np.concatenate(lbws), np.concatenate(ubws)
        w0 = np.concatenate(w0s)
        g = ca.vertcat(*[e for _, e, _, _ in groups])
        lbg = np.concatenate([np.full(e.numel(), lo) for _, e, lo, _ in groups])
        ubg = np.concatenate([np.full(e.numel(), hi) for _, e, _, hi in groups])
        n_eq = int(np.sum(lbg == ubg))
        if n_eq > w.numel():
            pace = " and a speed or step length" if (speed or step_length) else ""
            raise ParameterError(f"the gait is over-determined: {n_eq} equations for {w.numel()} unknowns (a "
                                 f"model with {nu} input(s){pace}); declare actuators or drop the speed or "
                                 "step length")

        opts = {"ipopt.tol": tol, "ipopt.constr_viol_tol": min(tol, 1e-10), "ipopt.max_iter": max_iter,
                "ipopt.print_level": 5 if progress else 0, "print_time": False, "ipopt.sb": "yes",
                "ipopt.mu_strategy": "adaptive",
                "expand": fnss[0].dynamics.n_instructions() + fnss[0].contact.n_instructions() > EXPAND_SIZE}
        if warms is not None and refine:
            # a finer mesh starts next to the coarse optimum: a small barrier parameter and a start
            # kept where it is (not pushed into the interior) take a handful of iterations instead
            # of re-solving from a central path (RABBIT 20 → 60 intervals: 10 iterations, not 83)
            opts.update({"ipopt.mu_init": 1e-5, "ipopt.warm_start_init_point": "yes",
                         "ipopt.warm_start_bound_push": 1e-8, "ipopt.warm_start_mult_bound_push": 1e-8})
        sol, stats, report, elapsed = solve_keeping_feasible(
            ca, {"x": w, "f": J, "g": g}, opts, progress, tol, groups, bound_groups,
            feasibility=feasibility or nothing_to_optimise, x0=w0, lbx=lbw, ubx=ubw, lbg=lbg, ubg=ubg)
        wopt = np.asarray(sol["x"]).ravel()
        status = stats.get("return_status", "unknown")
        info = {"status": status, "iterations": int(stats.get("iter_count", 0)), "time_s": elapsed, "nodes": N}
        failure = stats.get("failure")
        out, start = [], 0
        for j in range(S):
            size = ws[j].numel()
            a, b = alpha_at[j]
            alpha = wopt[a:b].reshape(bezier_degree + 1, nu).T if hzd and nu else None
            out.append(_gait(system, models[j], fnss[j], pvs[j], wopt[start:start + size], N, objective,
                             float(sol["f"]), report, dict(info), bezier_degree, alpha))
            start += size
        raise_with_gait(failure, out, [footfalls[j % len(footfalls)].source for j in range(S)])
        return out

    stages = solve_stages(fnss[0], x_guesses[0], Ps[0], levels, hzd)
    warms, total_iter, total_time = _run_stages(solve, stages, x_guesses, t_guesses)
    warm = warms[0] if S == 1 else period_gait(warms, [footfalls[j % len(footfalls)].source for j in range(S)])
    warm.solver.update({"iterations_total": total_iter, "time_total_s": total_time, "levels": levels})
    warm.stability = stability_report(sigmas, warms, Ps, n, max_multiplier)
    return warm


def _run_stages(solve: Any, stages: list[tuple[int, bool, bool, bool]], x_guesses: list[np.ndarray],
                t_guesses: list[float]) -> tuple[list[Gait], int, float]:
    """The solves of :func:`~amble.analysis.gait_stages.solve_stages` in turn, each from the
    previous solution: the gaits of the last, the iterations and the solver's seconds of all."""
    warms: list[Gait] | None = None
    iters, secs = 0, 0.0
    for N, with_vc, feasible, refine in stages:
        if warms is not None:  # a later stage starts from the previous solution, interpolated
            x_guesses = [wg.state(np.linspace(0.0, wg.step_time, 2 * N + 1)) for wg in warms]
            t_guesses = [wg.step_time for wg in warms]
        warms = solve(N, x_guesses, t_guesses, warms, with_vc, feasible, refine)
        iters += warms[0].solver["iterations"]
        secs += warms[0].solver["time_s"]
    assert warms is not None
    return warms, iters, secs


def _period_functions(system: HybridSystem, footfalls: list, S: int, objective: Any, phase: Any
                      ) -> tuple[list[Any], list[StepFunctions], bool]:
    """Each step's model and exported functions over a period of ``S`` footfalls (a walker whose
    stance feet are modes alternates its modes; one that relabels its legs repeats its one), and
    whether the problem has nothing to optimise (no inputs, or the integrand 0: any gait that
    satisfies the constraints is optimal)."""
    models = [system.modes[footfalls[j % len(footfalls)].source] for j in range(S)]
    named = isinstance(objective, str) and objective in OBJECTIVES
    integrands = [None if named else _integrand(m, objective) for m in models]
    fnss = [_step_functions(system, integrands[j], _expression(m, phase, "phase") if phase is not None else None,
                            footfalls[j % len(footfalls)].name)
            for j, m in enumerate(models)]
    if any((f.n, f.nu, f.dims) != (fnss[0].n, fnss[0].nu, fnss[0].dims) for f in fnss):
        raise ParameterError(f"system {system.name!r}: the modes of a period need the same numbers of coordinates "
                             "and inputs")
    return models, fnss, fnss[0].nu == 0 or (integrands[0] is not None and integrands[0] == 0)


def _period_length(system: HybridSystem, footfalls: list, steps: int | None) -> int:
    """Footfalls per period: ``steps``, by default one cycle of the walker's modes; a
    :class:`ParameterError` for a number that is not a multiple of the cycle."""
    if steps is None:
        return len(footfalls)
    if not (isinstance(steps, int) and 1 <= steps <= 8):
        raise ParameterError(f"steps must be an integer in [1, 8], got {steps!r}")
    if steps % len(footfalls):
        cycle = " → ".join([*(t.source for t in footfalls), footfalls[0].source])
        raise ParameterError(f"steps={steps}: a gait of {system.name!r} returns to its first mode after a multiple "
                             f"of {len(footfalls)} footfalls ({cycle})")
    return steps


#: the exported step functions per system (id, weak reference, its fingerprint and the objective's
#: and phase's expressions): re-exporting RABBIT (its derivation and the translation to CasADi)
#: costs 0.4 s of a 2 s design
_EXPORTS: dict[tuple, tuple[Any, StepFunctions]] = {}


def _step_functions(system: HybridSystem, integrand: sp.Expr | None, phase: sp.Expr | None,
                    transition: str | None = None) -> StepFunctions:
    """:func:`~amble.backend.casadi_export.step_functions`, once per system and declaration:
    any edit of a declaration advances its revision (:func:`amble.backend.cache.fingerprint`),
    which makes a new key."""
    key = (id(system), fingerprint(system), None if integrand is None else sp.srepr(integrand),
           None if phase is None else sp.srepr(phase), transition)
    hit = _EXPORTS.get(key)
    if hit is not None and hit[0]() is system:
        return hit[1]
    fns = step_functions(system, integrand, phase, transition)
    if len(_EXPORTS) >= 32:  # systems made per call would fill it
        _EXPORTS.clear()
    _EXPORTS[key] = (weakref.ref(system), fns)
    return fns


def _running_cost(ca: Any, fns: StepFunctions, objective: Any, U: Any, PW: Any, Q: Any, V: Any, taus: Any,
                  Pj: Any) -> tuple[Any, float]:
    """The objective's integrand at the ``K`` points (a 1 × K row) and its scale: ``effort`` Σu²,
    ``cot`` the absolute actuator power per unit weight, else the user's integrand."""
    K, nu = Q.shape[1], U.shape[0]
    if isinstance(objective, str) and objective == "effort":
        return (ca.sum1(U**2) if nu else ca.MX.zeros(1, K)), 1.0
    if isinstance(objective, str) and objective == "cot":
        return (ca.sum1(PW) if nu else ca.MX.zeros(1, K)), 1.0 / float(fns.weight(Pj))
    return fns.integrand.map(K)(Q, V, U, taus, Pj), 1.0


