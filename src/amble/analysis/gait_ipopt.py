"""IPOPT on a gait's NLP (:func:`~amble.analysis.gait_optimisation.optimize_gait`): the solve with
its output on stderr and Ctrl-C kept as an interrupt, the constraint report, and a failure
named by its reason and the most violated constraint."""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from ..errors import SolverError
from .gait_result import Gait, constraint_report
from .gait_stages import period_gait
from .solver_io import Interrupts, StdoutToStderr

_FAILURES = {
    "Infeasible_Problem_Detected": "the constraints are infeasible",
    "Restoration_Failed": "restoration failed (no feasible point near the iterate)",
    "Maximum_Iterations_Exceeded": "iteration limit reached",
    "Maximum_CpuTime_Exceeded": "time limit reached",
    "Search_Direction_Becomes_Too_Small": "search direction too small",
    "Error_In_Step_Computation": "error in step computation",
    "Invalid_Number_Detected": "a non-finite number in the model's functions",
    "Diverging_Iterates": "diverging iterates",
}


def _solve_nlp(ca: Any, nlp: dict[str, Any], opts: dict[str, Any], progress: bool, tol: float,
               groups: list[tuple[str, Any, float, float]], bound_groups: list[tuple[str, int, int]],
               feasibility: bool = False, **problem: Any
               ) -> tuple[dict[str, Any], dict[str, Any], dict[str, Any], float]:
    """IPOPT on ``nlp`` from ``problem`` (start and bounds): the solution, IPOPT's statistics, the
    constraint report and the seconds it took; a failure is a :class:`SolverError` naming the reason
    and the most violated constraint, Ctrl-C a ``KeyboardInterrupt``.

    ``feasibility``: the problem has nothing to optimise (a passive walker: no inputs, or a zero
    objective), so a last iterate that satisfies every constraint within ``tol`` is the answer
    whatever IPOPT's status. A passive walker's step has as many equations as unknowns, and IPOPT
    often ends such a problem in a failed restoration phase at a point where every constraint
    holds (7 of 9 compass gaits far from the defaults)."""
    solver = ca.nlpsol("gait", "ipopt", nlp, opts)
    t0 = time.perf_counter()
    with StdoutToStderr(progress), Interrupts() as interrupted:
        sol = solver(**problem)
    if interrupted:  # CasADi turns Ctrl-C into a solver failure: it is the user's interrupt
        raise KeyboardInterrupt
    elapsed = time.perf_counter() - t0
    stats = solver.stats()
    gval = np.asarray(sol["g"]).ravel()
    report = constraint_report(groups, gval, problem["lbg"], problem["ubg"], np.asarray(sol["x"]).ravel(),
                               problem["lbx"], problem["ubx"], bound_groups)
    status = stats.get("return_status", "unknown")
    feasible = feasibility and all(r["max_violation"] <= tol for r in report.values())
    if feasible and not stats.get("success", False):
        stats["return_status"] = f"Feasible_Point_Found ({status})"
    if not stats.get("success", False) and status != "Solved_To_Acceptable_Level" and not feasible:
        worst = max(report.items(), key=lambda kv: kv[1]["max_violation"])
        reason = _FAILURES.get(status, status.replace("_", " ").lower())
        binding = (f"most violated: {worst[0]} (by {worst[1]['max_violation']:.3g})"
                   if worst[1]["max_violation"] > tol else "at the starting point" if not stats.get("iter_count")
                   else "every constraint holds at the last iterate (the optimality conditions do not)")
        err = SolverError(f"gait optimisation failed after {stats.get('iter_count', '?')} iterations: {reason}; "
                          f"{binding}")
        if stats.get("iter_count") and worst[1]["max_violation"] <= tol:
            # a gait that satisfies every constraint, not certified optimal: the caller may keep it
            err.feasible = (sol, stats, report, elapsed)
        raise err
    return sol, stats, report, elapsed


def solve_keeping_feasible(*args: Any, **kw: Any) -> tuple[dict, dict, dict, float]:
    """:func:`_solve_nlp`; a failure whose last iterate satisfies every
    constraint comes back as a solution with the error in ``stats["failure"]``, to be raised again
    with its gait once read back (:func:`raise_with_gait`)."""
    try:
        return _solve_nlp(*args, **kw)
    except SolverError as e:
        if getattr(e, "feasible", None) is None:
            raise
        sol, stats, report, elapsed = e.feasible
        return sol, {**stats, "failure": e}, report, elapsed


def raise_with_gait(failure: SolverError | None, gaits: list[Gait], modes: list[str]) -> None:
    """Raise ``failure`` (if any) carrying the gait of its last iterate: feasible, not optimal."""
    if failure is None:
        return
    failure.gait = gaits[0] if len(gaits) == 1 else period_gait(gaits, modes)
    raise failure
