"""Compass-gait walking speed and accuracy: amble beside SciPy DOP853, Drake and a hand-written C floor.

All runs walk N steps from the same post-impact state on the stable limit cycle
(:data:`benchmarks.peers.compass_scipy.LIMIT_CYCLE_X0`, Drake's state order = amble's compass-gait
order: stance, swing, stance_dot, swing_dot) with Drake's default parameters (m_H = 10 kg,
m = 5 kg, a = b = 0.5 m, g = 9.81 m/s², slope 0.0525 rad; amble's compass-gait default slope is
0.05, so ``slope=0.0525`` is passed).

* amble fast path: ``amble.simulation.simulate.run(k, p, 0, x0, steps=N, opts=Options(rtol=tol, atol=tol))``
  — the whole walk (integration, event location, resets) in one compiled call; timed around the
  Python call (kernels already built, one warm-up call).
* ``amble.simulate(...)``: the user-facing call that also records the sampled trajectory.
* C floor (:mod:`benchmarks.peers.floor`): the leanest hand-written C loop (same DOP853 and
  event location, Drake's equations written out by hand), timed around its ctypes call. amble
  and the floor are timed interleaved, repeat by repeat, so machine load hits both alike.
* SciPy ``solve_ivp(DOP853)`` with a terminal event per step, and Drake's own ``CompassGait``
  hybrid system with ``runge_kutta3`` (Drake's default) and ``runge_kutta5`` at target accuracy =
  tol (:mod:`benchmarks.peers.compass_drake`; skipped with a reason if pydrake is missing).

Accuracy: max-abs error of the N-th post-impact state against two independent tight references,
SciPy DOP853 at rtol = atol = 1e-13 and amble at 1e-13.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from benchmarks.common import Goal, Section, Stats, ratio, sci, table, time_calls, us

#: Tolerances (rtol = atol; Drake: target accuracy).
TOLERANCES: tuple[float, ...] = (1e-10, 1e-8)

#: Parameters that make amble's compass gait Drake's.
DRAKE_PARAMS: dict[str, float] = {"slope": 0.0525}

#: Goals (stated at every tolerance).
GOAL_US_PER_STEP = 30.0
GOAL_SPEEDUP = 100.0
GOAL_FLOOR_RATIO = 3.0


def _amble_setup() -> tuple[Any, Any, Any]:
    """(system, kernels, parameter vector) of the compass gait with Drake's slope."""
    from amble.backend.kernels import build
    from amble.models import load
    from amble.simulation.simulate import parameter_vector

    system = load("compass-gait")
    k = build(system)
    return system, k, parameter_vector(k, DRAKE_PARAMS)


def amble_walk(k: Any, p: np.ndarray, x0: np.ndarray, steps: int, tol: float) -> tuple[int, np.ndarray]:
    """Walk ``steps`` steps on amble's fast path; returns (status code, final post-impact state)."""
    from amble.simulation.engine import Options, run

    r = run(k, p, 0, x0, steps=steps, opts=Options(rtol=tol, atol=tol))
    return r.code, r.x


def _interleaved(k: Any, p: np.ndarray, x0: np.ndarray, steps: int, tol: float, repeats: int) -> dict[str, Any]:
    """Time amble's fast path and the C floor alternately; per-step Stats and final states."""
    import time

    from benchmarks.peers import floor

    amble_walk(k, p, x0, steps, tol)  # warm-up
    fl = floor.simulate(x0, steps, tol, tol)  # compile + warm-up
    a_walls, f_walls = [], []
    status, xa = 0, None
    for _ in range(repeats):
        t0 = time.perf_counter()
        status, xa = amble_walk(k, p, x0, steps, tol)
        a_walls.append(time.perf_counter() - t0)
        fl = floor.simulate(x0, steps, tol, tol)
        f_walls.append(fl["call_wall_s"])
    if status != 2:
        raise RuntimeError(f"amble walk ended with status code {status}, expected 2 (completed)")
    return {
        "amble": Stats.of([w / steps for w in a_walls]),
        "floor": Stats.of([w / steps for w in f_walls]),
        "amble_x": xa,
        "floor_x": fl["post_impact_states"][-1],
        "floor_nfev": fl["nfev"] / steps,
    }


def run(quick: bool = False) -> Section:
    """Time and check every walker at each tolerance; return the section."""
    import amble
    from benchmarks.peers import compass_drake, compass_scipy

    steps = 20 if quick else 200
    reps_fast = 7 if quick else 21
    reps_slow = 5
    x0 = np.array(compass_scipy.LIMIT_CYCLE_X0, dtype=float)
    system, k, p = _amble_setup()

    print(f"walk: references ({steps} steps at 1e-13) ...", flush=True)
    ref_scipy = compass_scipy.reference(x0, steps, 1e-13)
    st, ref_amble = amble_walk(k, p, x0, steps, 1e-13)
    ref_x = ref_scipy["post_impact_states"][-1]
    refs_diff = float(np.max(np.abs(ref_amble - ref_x)))

    def errs(x: np.ndarray) -> tuple[float, float]:
        return float(np.max(np.abs(x - ref_x))), float(np.max(np.abs(x - ref_amble)))

    drake_ok, drake_reason = compass_drake.available()
    results: dict[float, dict[str, Any]] = {}
    md: list[str] = []
    goals: list[Goal] = []
    for tol in TOLERANCES:
        print(f"walk: tol {tol:.0e}: amble + floor (interleaved) ...", flush=True)
        il = _interleaved(k, p, x0, steps, tol, reps_fast)
        print(f"walk: tol {tol:.0e}: amble.simulate (recording) ...", flush=True)
        full_stats, traj = time_calls(
            lambda tol=tol: amble.simulate(system, x0, params=DRAKE_PARAMS, steps=steps, rtol=tol, atol=tol), reps_slow)
        print(f"walk: tol {tol:.0e}: SciPy DOP853 ...", flush=True)
        sc = compass_scipy.walk(x0, steps, tol, tol, repeats=reps_slow)
        drake: dict[str, dict[str, Any]] = {}
        for scheme in compass_drake.SCHEMES:
            print(f"walk: tol {tol:.0e}: Drake {scheme} ...", flush=True)
            drake[scheme] = compass_drake.walk(x0, steps, tol, scheme, repeats=reps_slow)

        a = il["amble"]
        rows = []

        def row(name: str, s: Stats | None, x: np.ndarray | None, nfev: float | None, vs_amble: str,
                rows: list = rows) -> None:
            e1, e2 = errs(x) if x is not None else (None, None)
            rows.append([name, us(s.median if s else None), us(s.min if s else None),
                         "—" if nfev is None else f"{nfev:.0f}", sci(e1), sci(e2), vs_amble])

        row("**amble** `simulate.run` (fast path)", a, il["amble_x"], None, "1×")
        row("amble `simulate()` (records trajectory)", Stats(full_stats.median / steps, full_stats.min / steps, 5),
            np.asarray(traj.final_post_impact_state, dtype=float), None, ratio(full_stats.median / steps, a.median))
        row("C floor (hand-written DOP853 loop)", il["floor"], il["floor_x"], il["floor_nfev"],
            ratio(il["floor"].median, a.median))
        s_sc = Stats(sc["time_per_step_s"], sc["min_time_per_step_s"], sc["repeats"])
        row("SciPy `solve_ivp` DOP853", s_sc, sc["post_impact_states"][-1], sc["nfev_per_step"],
            ratio(s_sc.median, a.median))
        for scheme, d in drake.items():
            if not d.get("available"):
                rows.append([f"Drake {scheme}", f"skipped: {d.get('skip_reason')}", "", "", "", "", ""])
                continue
            s_d = Stats(d["time_per_step_s"], d["min_time_per_step_s"], d["repeats"])
            row(f"Drake {d.get('drake_version') or ''} {scheme}", s_d, d["post_impact_states"][-1],
                d["nfev_per_step"], ratio(s_d.median, a.median))
        md += [f"#### rtol = atol = {tol:.0e} (Drake: target accuracy {tol:.0e}), {steps} steps", "",
               table(["walker", "µs/step (median)", "µs/step (min)", "f-evals/step",
                      f"error after {steps} steps vs SciPy 1e-13", "vs amble 1e-13", "time / amble"], rows), ""]

        sp_ratio = s_sc.median / a.median
        goals.append(Goal(f"amble µs/step, tol {tol:.0e}", f"≤ {GOAL_US_PER_STEP:g} µs",
                          f"{a.median * 1e6:.1f} µs (min {a.min * 1e6:.1f})", a.median * 1e6 <= GOAL_US_PER_STEP))
        goals.append(Goal(f"speed-up vs SciPy DOP853, tol {tol:.0e}", f"≥ {GOAL_SPEEDUP:g}×", f"{sp_ratio:.0f}×",
                          sp_ratio >= GOAL_SPEEDUP))
        avail = {s: d for s, d in drake.items() if d.get("available")}
        if avail:
            best = min(avail, key=lambda s: avail[s]["time_per_step_s"])
            dr = avail[best]["time_per_step_s"] / a.median
            goals.append(Goal(f"speed-up vs Drake (faster scheme: {best}), tol {tol:.0e}", f"≥ {GOAL_SPEEDUP:g}×",
                              f"{dr:.0f}×", dr >= GOAL_SPEEDUP))
        else:
            goals.append(Goal(f"speed-up vs Drake, tol {tol:.0e}", f"≥ {GOAL_SPEEDUP:g}×",
                              f"skipped: {drake_reason}", None))
        fr = a.median / il["floor"].median
        goals.append(Goal(f"amble / C floor, tol {tol:.0e}", f"≤ {GOAL_FLOOR_RATIO:g}×",
                          f"{fr:.2f}× (min/min {a.min / il['floor'].min:.2f}×)", fr <= GOAL_FLOOR_RATIO))
        results[tol] = {"interleaved": il, "simulate": full_stats, "scipy": sc, "drake": drake}

    head = [
        f"Compass gait (Drake's parameters, slope 0.0525 rad), {steps} walking steps from the limit-cycle "
        "post-impact state. Medians and minima of repeated whole walks divided by the number of steps: "
        f"amble fast path and C floor {reps_fast} repeats each (interleaved), everything else {reps_slow}. "
        "Errors are the max-abs difference of the final post-impact state (rad, rad/s) from two "
        f"independent references at rtol = atol = 1e-13 (SciPy DOP853, self-error estimate "
        f"{ref_scipy['self_error']:.1e}; amble); the two references differ by {refs_diff:.1e}. "
        "*time / amble* = that walker's median time per step divided by amble's fast path.",
        "",
    ]
    data = {"steps": steps, "refs_diff": refs_diff, "ref_self_error": ref_scipy["self_error"],
            "results": results}
    return Section("Walking: compass gait", "\n".join(head + md).rstrip(), goals, data)
