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
* every library model before and after the lean right-hand side (:func:`library_models`).
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

import contextlib
import functools
import io
import re
import statistics
import time
from pathlib import Path
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
GOAL_FLOOR_RATIO = 1.3
#: ``simulate()`` (recording on its 0.01 s grid) ÷ the fast path, at 20 and at 200 steps.
GOAL_RECORDING_RATIO = 1.3
#: ``amble simulate --json`` per-step cost ÷ the fast path's.
GOAL_CLI_RATIO = 1.2
#: humanoid-3d µs per walking step on the fast path.
GOAL_HUMANOID_US = 150.0
#: The C floor's µs per compass-gait step (200 steps, 1e-10) on the machine the humanoid goal was
#: set on: the goal as a multiple of the floor travels to machines of other speeds.
FLOOR_US_WHEN_SET = 8.6
#: Tolerances of the work–precision plot (rtol = atol).
WP_TOLERANCES: tuple[float, ...] = (1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12)
#: Where the work–precision plot is written (BENCHMARKS.md links it).
WP_PLOT = Path(__file__).resolve().parent / "work_precision.png"


def _amble_setup() -> tuple[Any, Any, Any]:
    """(system, kernels, parameter vector) of the compass gait with Drake's slope."""
    from amble.backend.kernels import compiled
    from amble.models import load
    from amble.simulation.simulate import parameter_vector

    system = load("compass-gait")
    k = compiled(system)
    return system, k, parameter_vector(k, DRAKE_PARAMS)


def amble_walk(k: Any, p: np.ndarray, x0: np.ndarray, steps: int, tol: float) -> tuple[int, np.ndarray]:
    """Walk ``steps`` steps on amble's fast path; returns (status code, final post-impact state).
    The options are made once per tolerance, as a caller walking many times would (laying out a
    new ``Options`` costs ≈ 70 k instructions, a third of a 20-step walk's Python)."""
    from amble.simulation.engine import run

    r = run(k, p, 0, x0, steps=steps, opts=_options(tol))
    return r.code, r.x


@functools.cache
def _options(tol: float) -> Any:
    from amble.simulation.engine import Options

    return Options(rtol=tol, atol=tol)


def _interleaved(k: Any, p: np.ndarray, x0: np.ndarray, steps: int, tol: float, repeats: int) -> dict[str, Any]:
    """Time amble's fast path and the C floor alternately; per-step Stats and final states."""

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


def _cli_walk(steps: int, x0: np.ndarray) -> None:
    """``amble simulate compass-gait --json`` in this process (output discarded)."""
    from amble.cli.main import main

    args = ["simulate", "compass-gait", "--set", "slope=0.0525", "--steps", str(steps),
            "--start", "x0=" + ",".join(repr(float(v)) for v in x0), "--json"]
    with contextlib.redirect_stdout(io.StringIO()):
        if main(args) != 0:
            raise RuntimeError(f"amble {' '.join(args)} failed")


def _recording_run(k: Any, p: np.ndarray, x0: np.ndarray, steps: int, mst: float) -> None:
    """The compiled recording alone: ``engine.run`` with samples on the 0.01 s grid, as ``simulate()``
    calls it, without the call's checks and its Trajectory (the C share of the recording)."""
    from amble.simulation.engine import run

    run(k, p, 0, x0, steps=steps, opts=_recording_options(mst), sample_dt=0.01, record=True)


@functools.cache
def _recording_options(mst: float) -> Any:
    from amble.simulation.engine import Options

    return Options(rtol=1e-10, atol=1e-10, max_step_time=mst)


def recording(system: Any, k: Any, p: np.ndarray, x0: np.ndarray, quick: bool) -> tuple[str, list[Goal]]:
    """``simulate()`` and the CLI's ``--json`` beside the fast path, interleaved, at 20 and 200 steps;
    the compiled recording alone (``engine.run(record=True)``) shows how much of ``simulate()``'s
    cost is the C side's. Wall time judges the goals; thread CPU time (not counting the time the
    process waits for a core on a loaded machine) is shown beside it."""
    import amble

    reps = 7 if quick else 15
    fns = {
        "fast path `simulate.run`": lambda n: amble_walk(k, p, x0, n, 1e-10),
        "`amble.simulate()` (0.01 s grid)": lambda n: amble.simulate(system, x0, params=DRAKE_PARAMS, steps=n),
        "`amble simulate --json` (in-process)": lambda n: _cli_walk(n, x0),
        "recording alone: `engine.run(record=True)`": lambda n: _recording_run(k, p, x0, n, system.max_step_time),
    }
    walls: dict[tuple[str, int], list[float]] = {(name, n): [] for name in fns for n in (20, 200)}
    cpus: dict[tuple[str, int], list[float]] = {(name, n): [] for name in fns for n in (20, 200)}
    for fn in fns.values():
        fn(20)  # warm-up
    for _ in range(reps):
        for n in (20, 200):
            for name, fn in fns.items():
                c0, t0 = time.thread_time(), time.perf_counter()
                fn(n)
                walls[(name, n)].append(time.perf_counter() - t0)
                cpus[(name, n)].append(time.thread_time() - c0)
    med = {key: statistics.median(v) for key, v in walls.items()}
    cpu = {key: statistics.median(v) for key, v in cpus.items()}
    fast = "fast path `simulate.run`"
    rows = []
    for name in fns:
        per = (med[(name, 200)] - med[(name, 20)]) / 180  # the cost of a step, without the call's fixed cost
        cper = (cpu[(name, 200)] - cpu[(name, 20)]) / (cpu[(fast, 200)] - cpu[(fast, 20)])
        rows.append([name, us(med[(name, 20)] / 20), us(med[(name, 200)] / 200), us(per),
                     ratio(med[(name, 20)], med[(fast, 20)]), ratio(med[(name, 200)], med[(fast, 200)]),
                     ratio(per, (med[(fast, 200)] - med[(fast, 20)]) / 180),
                     f"{cpu[(name, 20)] / cpu[(fast, 20)]:.2f}× / {cpu[(name, 200)] / cpu[(fast, 200)]:.2f}× / "
                     f"{cper:.2f}×"])
    goals = []
    sim = "`amble.simulate()` (0.01 s grid)"
    for n in (20, 200):
        r = med[(sim, n)] / med[(fast, n)]
        goals.append(Goal(f"`simulate()` ÷ fast path, {n} steps", f"≤ {GOAL_RECORDING_RATIO:g}×", f"{r:.2f}×",
                          r <= GOAL_RECORDING_RATIO))
    cli = "`amble simulate --json` (in-process)"
    per_cli = (med[(cli, 200)] - med[(cli, 20)]) / (med[(fast, 200)] - med[(fast, 20)])
    goals.append(Goal("`amble simulate --json` per-step cost ÷ fast path", f"≤ {GOAL_CLI_RATIO:g}×",
                      f"{per_cli:.2f}×", per_cli <= GOAL_CLI_RATIO))
    md = ("Compass gait at rtol = atol = 1e-10, medians of "
          f"{reps} interleaved repeats. *per step* = (time of 200 steps − time of 20 steps) / 180: the cost "
          "of one more step without the call's fixed cost (argument checks, the trajectory object). "
          "*recording alone* is the compiled run with its 0.01 s samples and nothing else: the share of "
          "`simulate()`'s cost that is the C side's (the 7th-order dense output takes three more right-hand "
          "sides in every integrator step with a sample in it). The last column is the same three ratios "
          "in thread CPU time, which a loaded machine's waits for a core do not inflate.\n\n"
          + table(["path", "µs/step, 20 steps", "µs/step, 200 steps", "µs per step (marginal)",
                   "÷ fast, 20 steps", "÷ fast, 200 steps", "÷ fast, marginal",
                   "÷ fast in CPU time (20 / 200 / marginal)"], rows))
    return md, goals


def humanoid(quick: bool) -> tuple[str, list[Goal]]:
    """humanoid-3d on the fast path from its default start: µs per walking step."""
    from amble.backend.kernels import compiled
    from amble.models import load
    from amble.simulation.engine import Options, run
    from amble.simulation.simulate import initial_state, parameter_vector
    from benchmarks.peers import compass_scipy, floor

    system = load("humanoid-3d")
    k = compiled(system)
    p = parameter_vector(k, None)
    mi, x = initial_state(system, k, None, None)
    opts = Options(max_step_time=system.max_step_time)
    steps = 3 if quick else 10
    r = run(k, p, mi, x, steps=steps, opts=opts)  # warm-up, and how far it walks
    n = max(r.steps, 1)
    floor.simulate(compass_scipy.LIMIT_CYCLE_X0, 200, 1e-10, 1e-10)  # compile + warm-up
    walls, floors = [], []
    for _ in range(5 if quick else 9):  # interleaved with the floor: load hits both alike
        t0 = time.perf_counter()
        run(k, p, mi, x, steps=steps, opts=opts)
        walls.append((time.perf_counter() - t0) / n)
        floors.append(floor.simulate(compass_scipy.LIMIT_CYCLE_X0, 200, 1e-10, 1e-10)["call_wall_s"] / 200)
    st, fl = Stats.of(walls), Stats.of(floors)
    per_floor, bound = st.median / fl.median, GOAL_HUMANOID_US / FLOOR_US_WHEN_SET
    goals = [Goal("humanoid-3d µs/step (fast path)", f"≤ {GOAL_HUMANOID_US:g} µs",
                  f"{st.median * 1e6:.0f} µs (min {st.min * 1e6:.0f})", st.median * 1e6 <= GOAL_HUMANOID_US),
             Goal("humanoid-3d step ÷ C floor's compass step (same run)", f"≤ {bound:.1f}×", f"{per_floor:.1f}×",
                  per_floor <= bound)]
    md = (f"humanoid-3d from its default start, {r.steps} walking steps ({r.status}), rtol = atol = 1e-10: "
          f"median {st.median * 1e6:.0f} µs/step, min {st.min * 1e6:.0f} µs/step ({st.n} repeats). The C floor's "
          f"compass-gait step, timed alternately with it: median {fl.median * 1e6:.1f} µs. The goal of "
          f"{GOAL_HUMANOID_US:g} µs was set on a machine where the floor took {FLOOR_US_WHEN_SET:g} µs a step; "
          f"stated as a multiple of the floor ({bound:.1f}×) it can be checked on a machine of any speed.")
    return md, goals


def _unhoisted(system: Any) -> Any:
    """The system's kernels generated with ``generate(..., hoist_params=False)`` (parameter-only
    subexpressions recomputed at every use, M solved as if dense), cached beside the regular
    library under a key of their own."""
    import hashlib
    import json

    from amble.backend import cache
    from amble.backend.codegen import generate
    from amble.backend.files import write_atomic
    from amble.backend.kernels import Kernels

    key = hashlib.sha256(f"{cache.structure_key(system)}:no-hoist-dense".encode()).hexdigest()[:24]
    d = cache.cache_dir()
    hit = cache.cached(d, key)
    if hit is None:
        src, meta = generate(system, hoist_params=False)
        so, digest = cache._compile(src, key, d)
        meta = {**meta, "library": so.name, "library_sha256": digest}
        write_atomic(d / f"{key}.json", json.dumps(meta).encode())
        hit = (so, meta)
    return Kernels(*hit)


def library_models(quick: bool) -> tuple[str, list[Goal]]:
    """Every library model on the fast path from its default start, before and after the lean
    right-hand side (hoisted parameter-only subexpressions, the sparse solve), interleaved run by
    run (and the C floor, a compass gait)."""
    from amble.backend.kernels import compiled
    from amble.models import load, names
    from amble.simulation.engine import Options, run
    from amble.simulation.simulate import initial_state, parameter_vector
    from benchmarks.peers import compass_scipy, floor

    steps, reps = (3, 3) if quick else (10, 9)
    rows = []
    for name in names():
        print(f"walk: library model {name} ...", flush=True)
        system = load(name)
        k_new, k_old = compiled(system), _unhoisted(system)
        p = parameter_vector(k_new, None)
        mi, x = initial_state(system, k_new, None, None)
        opts = Options(max_step_time=system.max_step_time)
        r = run(k_new, p, mi, x, steps=steps, opts=opts)  # warm-up, and how far it walks
        run(k_old, p, mi, x, steps=steps, opts=opts)
        n = max(r.steps, 1)
        walls: dict[str, list[float]] = {"old": [], "new": []}
        for _ in range(reps):
            for tag, kk in (("old", k_old), ("new", k_new)):
                t0 = time.perf_counter()
                run(kk, p, mi, x, steps=steps, opts=opts)
                walls[tag].append((time.perf_counter() - t0) / n)
        old, new = Stats.of(walls["old"]), Stats.of(walls["new"])
        found = re.search(r"#define NHOIST (\d+)", k_new.path.with_suffix(".c").read_text())
        nh = found.group(1) if found else "?"
        rows.append([name, f"{r.steps} ({r.status})", nh, us(old.median), us(new.median),
                     f"{new.median / old.median:.2f}×", f"{new.min / old.min:.2f}×"])
    fl = [floor.simulate(compass_scipy.LIMIT_CYCLE_X0, 200, 1e-10, 1e-10)["call_wall_s"] / 200 for _ in range(reps)]
    rows.append(["C floor (compass gait, Drake's parameters, 200 steps, 1e-10)", "200", "—", "—",
                 us(statistics.median(fl)), "—", "—"])
    md = (f"Each library model from its default start, {steps} walking steps per run on the fast path at its "
          f"default tolerances, µs per walking step, medians of {reps} runs. *before* is the model's library "
          "generated with `generate(system, hoist_params=False)`: parameter-only subexpressions recomputed at "
          "every use and M solved as if dense, in the natural order — the right-hand side as it was before "
          "both (the nested sin² + cos² pairing of `backend/trig.py` is in both); *after* is the default "
          "library. The two are timed alternately run by run. *hoisted* is the number of values in the "
          "parameter prelude.\n\n"
          + table(["model", "steps walked", "hoisted", "µs/step before", "µs/step after",
                   "after ÷ before (medians)", "(minima)"], rows))
    return md, []


def work_precision(k: Any, p: np.ndarray, x0: np.ndarray, steps: int, ref_x: np.ndarray, quick: bool) -> str:
    """Error after ``steps`` steps against time per step, for amble, the C floor and SciPy (Drake
    when importable), each at a range of tolerances; writes :data:`WP_PLOT`."""
    from benchmarks.peers import compass_drake, compass_scipy

    tols = WP_TOLERANCES[1::2] if quick else WP_TOLERANCES
    series: dict[str, list[tuple[float, float, float]]] = {"amble (fast path)": [], "C floor": [],
                                                           "SciPy DOP853": []}
    drake_ok, _ = compass_drake.available()
    if drake_ok:
        series["Drake runge_kutta5"] = []
    for tol in tols:
        il = _interleaved(k, p, x0, steps, tol, 5 if quick else 9)
        series["amble (fast path)"].append((tol, il["amble"].median, float(np.max(np.abs(il["amble_x"] - ref_x)))))
        series["C floor"].append((tol, il["floor"].median, float(np.max(np.abs(il["floor_x"] - ref_x)))))
        if tol >= 1e-10 or not quick:
            sc = compass_scipy.walk(x0, steps, tol, tol, repeats=5)
            series["SciPy DOP853"].append((tol, sc["time_per_step_s"],
                                           float(np.max(np.abs(np.asarray(sc["post_impact_states"][-1]) - ref_x)))))
        if drake_ok:
            d = compass_drake.walk(x0, steps, tol, "runge_kutta5", repeats=5)
            if d.get("available"):
                series["Drake runge_kutta5"].append(
                    (tol, d["time_per_step_s"], float(np.max(np.abs(np.asarray(d["post_impact_states"][-1]) - ref_x)))))
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(figsize=(6.4, 4.4))
        for name, pts in series.items():
            if pts:
                ax.loglog([t * 1e6 for _, t, _ in pts], [max(e, 1e-16) for _, _, e in pts], "o-", label=name)
        ax.set_xlabel("time per walking step (µs, median)")
        ax.set_ylabel(f"max-abs error after {steps} steps")
        ax.set_title("Compass gait: work–precision (rtol = atol from 1e-5 to 1e-12)")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend()
        fig.tight_layout()
        fig.savefig(WP_PLOT, dpi=110)
        plt.close(fig)
        img = f"![work–precision](benchmarks/{WP_PLOT.name})\n\n"
    except ImportError:
        img = "(matplotlib not installed: no plot)\n\n"
    rows = [[name, f"{tol:.0e}", us(t), sci(e)] for name, pts in series.items() for tol, t, e in pts]
    return (f"Error of the {steps}-th post-impact state against the SciPy 1e-13 reference, against the "
            "median time per step, each walker at each tolerance (every peer warmed up by an untimed run "
            "first, as amble is). The same integrator (DOP853) gives amble, the floor and SciPy the same "
            "error at a tolerance: the horizontal distance between their curves is framework cost, the "
            "slope is the integrator's order.\n\n" + img
            + table(["walker", "rtol = atol", "µs/step (median)", f"error after {steps} steps"], rows))


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
    print("walk: recording and the CLI beside the fast path ...", flush=True)
    rec_md, rec_goals = recording(system, k, p, x0, quick)
    print("walk: humanoid-3d ...", flush=True)
    hum_md, hum_goals = humanoid(quick)
    print("walk: library models ...", flush=True)
    lib_md, lib_goals = library_models(quick)
    print("walk: work–precision ...", flush=True)
    wp_md = work_precision(k, p, x0, steps, ref_x, quick)
    goals += rec_goals + hum_goals + lib_goals
    md += ["#### Recording and the command line", "", rec_md, "", "#### humanoid-3d", "", hum_md, "",
           "#### Every library model: before and after the lean right-hand side", "", lib_md, "",
           "#### Work–precision", "", wp_md, ""]
    data = {"steps": steps, "refs_diff": refs_diff, "ref_self_error": ref_scipy["self_error"],
            "results": results}
    return Section("Walking: compass gait", "\n".join(head + md).rstrip(), goals, data)
