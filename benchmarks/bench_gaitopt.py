"""Gait optimisation: one periodic step by Hermite–Simpson collocation and IPOPT (CasADi).

Cases, each in this process with the compiled models already cached (the passive step that
starts an optimisation is walked by amble's compiled simulator; its one-time compile is not
timed), on a model built afresh for every run, so the time includes the derivation, the CasADi
export, building the NLP and the solve:

* ``compass-gait``, 3° slope (``slope`` = 0.0524 rad), no inputs, 30 intervals: the passive gait
  as a feasibility problem;
* the compass gait with a hip and an ankle torque, effort objective: the optimum is the passive
  gait (``∫u² ≈ 0``);
* the compass gait with a hip torque only, 0.8 m/s, Bézier virtual constraints (HZD), mesh
  refined 20 → 60 intervals;
* the passive compass gait on 4.6° with two steps per period (``steps=2``), its fixed points
  against Newton's period-2 orbit;
* RABBIT's proportions (``tests/data/rabbit.urdf`` walked as in the URDF guide, four joint
  torques ≤ 150 N·m): 0.8 m/s from standing still, 20 intervals. The time is the optimisation
  alone; loading the URDF and building the walker (about 5 s) is reported beside it;
* the library model ``rabbit`` (Westervelt et al.'s parameters, four joint torques ≤ 150 N·m)
  with ``hzd=True`` in its own virtual constraints (outputs, phase, degree 5), 0.8 m/s, 20
  intervals and refined 20 → 80, from standing still (and, beside it, the interpolated start:
  ``RABBIT_CASES``); the time includes deriving the model and the export.
  Its last column is Newton on the model's compiled HZD closed loop with the exported parameters.

Each row: wall time of the whole call (median and min of 5), IPOPT iterations and the time IPOPT
reports, the largest constraint violation, and the distance of the optimised fixed point from
:func:`amble.analysis.poincare.find_fixed_point` on the same system (for the HZD case: Newton on the
closed-loop return map under the HZD controller built with the exported α).

Run alone: ``python -m benchmarks --only gaitopt --no-write``.
"""

from __future__ import annotations

from typing import Any

from benchmarks.common import Goal, Section, Stats, sci, sec, table

SLOPE = 0.0524
GOAL_COMPASS_S = 2.0
GOAL_RABBIT_S = 10.0


def _compass(inputs: tuple[str, ...]) -> Any:
    from amble.models import compass_gait

    s = compass_gait.build()
    m = s.modes["compass-gait"]
    st, sw = m.q
    if "hip" in inputs:
        m.actuator("hip", on=sw - st, limit=40.0)
    if "ankle" in inputs:
        m.actuator("ankle", on=st, limit=20.0)
    return s


def _closed_loop(gait: Any) -> Any:
    import sympy as sp

    s = _compass(("hip",))
    m = s.modes["compass-gait"]
    bz = gait.bezier
    names = {str(x): x for x in [*m.q, *m.params]}
    m.virtual_constraints([sp.sympify(o, locals=names) for o in bz["outputs"]],
                          sp.sympify(bz["phase"]["expression"], locals=names), bz["alpha"],
                          (bz["phase"]["theta_plus"], bz["phase"]["theta_minus"]), epsilon=0.005)
    return s


CASES: list[tuple[str, tuple[str, ...], dict[str, Any]]] = [
    ("compass gait, passive (no inputs), N = 30", (), {"nodes": 30}),
    ("compass gait, hip + ankle, effort, N = 30", ("hip", "ankle"), {"nodes": 30}),
    ("compass gait, hip, 0.8 m/s, HZD, N = 20 → 60", ("hip",), {"nodes": [20, 60], "speed": 0.8, "hzd": True,
                                                              "bezier_degree": 6}),
]


def run(quick: bool = False) -> Section:
    import time

    import numpy as np

    from amble.analysis.gait_optimisation import optimize_gait
    from amble.analysis.poincare import find_fixed_point

    reps = 2 if quick else 5
    rows, data = [], {}
    goals = []
    for label, inputs, kw in CASES:
        optimize_gait(_compass(inputs), params={"slope": SLOPE}, **kw)  # compile the passive walker once
        walls, gait = [], None
        for _ in range(reps):
            s = _compass(inputs)
            t0 = time.perf_counter()
            gait = optimize_gait(s, params={"slope": SLOPE}, **kw)
            walls.append(time.perf_counter() - t0)
        st = Stats.of(walls)
        ref_sys = _closed_loop(gait) if kw.get("hzd") else _compass(inputs)
        lc = find_fixed_point(ref_sys, gait.fixed_point, params={"slope": SLOPE})
        err = float(np.abs(lc.fixed_point - gait.fixed_point).max())
        sv = gait.solver
        its = sv.get("iterations_total", sv["iterations"])
        ipopt = sv.get("time_total_s", sv["time_s"])
        rows.append([label, sec(st.median, 2), sec(st.min, 2), str(its), sec(ipopt, 2), sci(gait.max_violation),
                     f"{gait.objective:.4g}", sci(err)])
        data[label] = {"walls": walls, "iterations": its, "ipopt_s": ipopt, "fixed_point_error": err,
                       "objective": gait.objective}
        if inputs == ("hip", "ankle"):
            goals.append(Goal("gait optimisation, compass gait with hip and ankle torques (3° slope, N = 30)",
                              f"≤ {GOAL_COMPASS_S:g} s",
                              f"{st.median:.2f} s (min {st.min:.2f}), {its} iterations",
                              st.median <= GOAL_COMPASS_S))
    rows.append(_two_steps(reps))
    r_row, r_goal = _rabbit(2 if quick else 3)
    rows.append(r_row)
    goals.append(r_goal)
    l_rows, l_goals, l_data = _rabbit_library(1 if quick else 3)
    rows.extend(l_rows)
    goals.extend(l_goals)
    data.update(l_data)
    md = [
        f"Wall time of `optimize_gait` (derive, CasADi export, NLP build, IPOPT solve), median and min of {reps} "
        "runs with the compiled passive walker cached; IPOPT iterations and IPOPT's own time (both summed "
        "over the meshes of a refinement); largest constraint violation; objective (effort: ∫‖u‖² dt per m); "
        "distance of the fixed point from Newton on the exact return map (`find_fixed_point`).",
        "",
        table(["case", "median s", "min s", "iterations", "IPOPT s", "max violation", "objective",
               "‖x* − x_Newton‖∞"], rows),
    ]
    return Section("Gait optimisation", "\n".join(md), goals, data)


#: starts of the library RABBIT's gait: standing still in the model's posture (its default
#: start: a feasibility solve with the step time held, then the optimisation) — the issue's goal —
#: and the interpolated step beside it.
RABBIT_CASES: list[tuple[str, dict[str, Any]]] = [
    ("from standing still (default start), N = 20", {"guess": "stand", "step_time": 0.4, "nodes": 20}),
    ("from standing still, N = 20 → 80 (the closed loop within 1e-4 of it)",
     {"guess": "stand", "step_time": 0.4, "nodes": [20, 80]}),
    ("interpolated start (posture to its relabelling), N = 20",
     {"guess": "interpolate", "step_time": 0.4, "nodes": 20}),
]


def _rabbit_library(reps: int) -> tuple[list[list[str]], list[Goal], dict[str, Any]]:
    """The library model ``rabbit`` (its own virtual constraints, HZD), 0.8 m/s, the cases of
    ``RABBIT_CASES``; the fixed point checked by Newton on the model's
    compiled closed loop with the exported parameters."""
    import time

    import numpy as np

    from amble.analysis.gait_optimisation import optimize_gait
    from amble.analysis.poincare import find_fixed_point
    from amble.models import rabbit

    rows, goals, data = [], [], {}
    for i, (label, kw) in enumerate(RABBIT_CASES):
        walls, gait = [], None
        for _ in range(reps):
            s = rabbit.build()  # afresh: the time includes the derivation and the CasADi export
            t0 = time.perf_counter()
            gait = optimize_gait(s, speed=0.8, hzd=True, **kw)
            walls.append(time.perf_counter() - t0)
        st = Stats.of(walls)
        lc = find_fixed_point(rabbit.build(), gait.fixed_point, params=gait.bezier["params"])
        err = float(np.abs(lc.fixed_point - gait.fixed_point).max())
        sv = gait.solver
        its, ipopt = sv["iterations_total"], sv["time_total_s"]
        name = f"`rabbit` (library, HZD), 0.8 m/s, {label}"
        rows.append([name, sec(st.median, 2), sec(st.min, 2), str(its), sec(ipopt, 2), sci(gait.max_violation),
                     f"{gait.objective:.4g}", sci(err)])
        data[name] = {"walls": walls, "iterations": its, "ipopt_s": ipopt, "fixed_point_error": err,
                      "objective": gait.objective, "newton_residual": float(lc.residual)}
        if i == 0:  # the goal: the one-step gait; the refined mesh is reported beside it
            goals.append(Goal(f"gait optimisation, library RABBIT one step at 0.8 m/s with HZD, {label}",
                              f"≤ {GOAL_RABBIT_S:g} s", f"{st.median:.2f} s (min {st.min:.2f}), {its} iterations",
                              st.median <= GOAL_RABBIT_S))
    return rows, goals, data


def _two_steps(reps: int) -> list[str]:
    """The passive compass gait on 4.6° (past its first period doubling), two steps per period;
    the distance of both steps' post-impact states from Newton's period-2 orbit."""
    import time

    import numpy as np

    from amble.analysis.gait_optimisation import optimize_gait
    from amble.analysis.poincare import find_fixed_point

    slope = float(np.deg2rad(4.6))
    optimize_gait(_compass(()), params={"slope": slope}, nodes=[20, 60], steps=2)  # compile the walker once
    walls, gait = [], None
    for _ in range(reps):
        s = _compass(())
        t0 = time.perf_counter()
        gait = optimize_gait(s, params={"slope": slope}, nodes=[20, 60], steps=2)
        walls.append(time.perf_counter() - t0)
    st = Stats.of(walls)
    lc = find_fixed_point(_compass(()), gait.fixed_point, params={"slope": slope}, period=2)
    err = max(float(np.abs(np.asarray(o) - g.fixed_point).max()) for o, g in zip(lc.orbit, gait.steps))
    sv = gait.solver
    return ["compass gait, passive, 4.6°, two steps (period 2), N = 20 → 60", sec(st.median, 2), sec(st.min, 2),
            str(sv["iterations_total"]), sec(sv["time_total_s"], 2), sci(gait.max_violation), f"{gait.objective:.4g}",
            sci(err)]


def _rabbit(reps: int) -> tuple[list[str], Goal]:
    import sys
    import time

    from amble.analysis.gait_optimisation import optimize_gait
    from benchmarks.common import REPO_ROOT

    sys.path.insert(0, str(REPO_ROOT / "tests" / "optimisation"))
    from test_gait_rabbit import rabbit_walker  # the walker of the URDF guide with four actuators

    walls, builds, gait = [], [], None
    for _ in range(reps):
        t0 = time.perf_counter()
        s = rabbit_walker()
        builds.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        gait = optimize_gait(s, speed=0.8, guess="stand", step_time=0.4, nodes=20)
        walls.append(time.perf_counter() - t0)
    st = Stats.of(walls)
    sv = gait.solver
    row = [f"RABBIT proportions (URDF), 0.8 m/s from standing, N = 20 (+ {Stats.of(builds).median:.1f} s to "
           "load and build)", sec(st.median, 2), sec(st.min, 2), str(sv["iterations"]), sec(sv["time_s"], 2),
           sci(gait.max_violation), f"{gait.objective:.4g}", "—"]
    goal = Goal("gait optimisation, RABBIT proportions (URDF walker) one step from standing",
                f"≤ {GOAL_RABBIT_S:g} s", f"{st.median:.2f} s (min {st.min:.2f}), {sv['iterations']} iterations",
                st.median <= GOAL_RABBIT_S)
    return row, goal


if __name__ == "__main__":
    sec_ = run()
    print(sec_.markdown)
    for g in sec_.goals:
        print(g)
