"""Benchmark: basin maps of the compass gait in one process on 1 and 2 threads, and on 1 and 2
Dask LocalCluster workers; ``amble sweep`` from the command line on 1 and 2 workers, on local
processes and on Dask (:mod:`benchmarks.bench_sweep_cli`).

In-process (:func:`threads`): the same cells walked one ``engine.run`` call per run of footfalls
(the loop basin maps used before) and in blocks by ``engine.walk_many`` (one compiled call per
block, ``amble_walk_batch``), each on a thread pool of 1 and 2 threads; one ``walk_many`` batch
whose rows 1 or 2 threads take one at a time (``threads=``); and ``sweep(system, "basin", ...)``
itself in this process (12 × 12 and 40 × 40 maps, tasks side by side on the threads). Throughput in walks per second and
per core, medians of interleaved repeats, and the share of a one-thread run spent outside the
compiled calls (holding the GIL), split into a basin's set-up and its Python per cell. The goal:
the batched path and basin maps scale ≥ 1.8× from 1 to 2 threads.

On Dask (:func:`_one`), besides wall clock, the CPU time of the workers and of the client process
(client and scheduler) and the share of a core the workers got while computing: on a loaded
machine the wall clock measures the machine, the CPU time the work.

Run with ``python -m benchmarks.bench_sweep`` (not part of pytest). Grid: post-impact stance
angle −0.35…−0.10 rad × stance angular velocity 0.8…1.4 rad/s (swing = 2·slope − stance, swing
velocity from the fixed point), at most 60 footfalls per cell, slope 0.05 rad. Prints the
cluster start-up time (workers started, amble imported and the compiled model loaded in each)
separately from the map time (the goal, ≤ 10 s on 2 cores, is met by either), the speed-up
and the throughput in initial conditions per second. The same map from the command line:
``amble sweep compass-gait --kind basin --x stance=-0.35:-0.10:100 --x stance_dot=0.8:1.4:100
--set slope=0.05 --workers 2`` (which integrates at the CLI's tolerance, 1e-10, not 1e-8).
"""

from __future__ import annotations

import argparse
import math
import statistics
import time
from concurrent.futures import ThreadPoolExecutor

import numpy as np

from benchmarks.common import Goal, Section, table

#: Goal: throughput of the batched path on 2 threads ÷ on 1 thread.
GOAL_SCALING = 1.8
#: How the rows and goals of an in-process basin map name the call they time.
BASIN_ROW = '`sweep(…, "basin", …)`'


def _box(n: int) -> dict[str, np.ndarray]:
    """The basin grid: n post-impact stance angles −0.35…−0.10 rad × n stance velocities 0.8…1.4 rad/s."""
    return {"stance": np.linspace(-0.35, -0.10, n), "stance_dot": np.linspace(0.8, 1.4, n)}


def _warm(system) -> None:
    from amble.backend.kernels import compiled

    compiled(system, derivatives=True)  # what a basin task loads (the section projection needs them)


def _cpu() -> float:
    return time.process_time()


def _one(system, n: int, workers: int, steps: int) -> tuple[float, float, dict[str, int], dict[str, float]]:
    """(start-up s, map s, outcome counts, CPU accounting) of an n × n basin on a LocalCluster.

    CPU accounting, which the machine's load does not inflate the way it does wall clock: CPU
    seconds of the workers (summed) and of this process (client and scheduler), and the wall
    seconds the tasks took on their workers (task stream); their ratio is the share of a core the
    workers got while computing."""
    from dask.distributed import Client, LocalCluster, get_task_stream

    from amble.analysis.sweep import sweep

    t0 = time.perf_counter()
    cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None)
    client = Client(cluster)
    client.run(_warm, system)  # import amble and load the compiled model in each worker
    t1 = time.perf_counter()
    try:
        w0, c0 = client.run(_cpu), time.process_time()
        with get_task_stream(client) as ts:
            res = sweep(system, "basin", _box(n), steps=steps, scheduler=client, progress=False)
        t2 = time.perf_counter()
        w1, c1 = client.run(_cpu), time.process_time()
        compute = sum(ss["stop"] - ss["start"] for t in ts.data for ss in t["startstops"] if ss["action"] == "compute")
    finally:
        client.close()
        cluster.close()
    cpu = {"workers_cpu_s": sum(w1[a] - w0[a] for a in w0), "client_cpu_s": c1 - c0, "task_wall_s": compute,
           "tasks": len(ts.data)}
    return t1 - t0, t2 - t1, res.counts(), cpu


def _cells(system, n: int):
    """(kernels, parameters, fixed point, n² initial post-impact states around the fixed point)."""
    from amble.analysis.poincare import find_fixed_point
    from amble.backend.kernels import compiled
    from amble.simulation.simulate import parameter_vector

    k = compiled(system)
    p = parameter_vector(k, {"slope": 0.05})
    xs = find_fixed_point(system, params={"slope": 0.05}).fixed_point
    a, b = np.meshgrid(np.linspace(-0.35, -0.10, n), np.linspace(0.8, 1.4, n), indexing="ij")
    x0 = np.tile(xs, (n * n, 1))
    x0[:, 0], x0[:, 2] = a.ravel(), -b.ravel() if xs[2] < 0 else b.ravel()
    x0[:, 1] = 2 * 0.05 - x0[:, 0]  # both feet on the slope
    return k, p, xs, x0


def threads(quick: bool = False) -> tuple[str, list[Goal], dict]:
    """Walks per second (and per core) on 1 and 2 threads of: the one-call-per-run loop and
    ``walk_many`` in fixed blocks, both on a thread pool; one ``walk_many(threads=)`` batch whose
    rows the threads take one by one; and a basin sweep in this process (``threads=``), which
    also puts every cell on the section in Python."""
    from amble.analysis import basin_setup
    from amble.analysis.defaults import BASIN_TOL
    from amble.analysis.sweep import sweep
    from amble.models import load
    from amble.simulation.engine import Options, run, walk_many

    system = load("compass-gait")
    n, steps, every, tol, block = (12, 30, 5, 1e-4, 16) if quick else (24, 60, 5, 1e-4, 16)
    k, p, xs, x0 = _cells(system, n)
    opts = Options(rtol=BASIN_TOL, atol=BASIN_TOL, max_step_time=system.max_step_time)
    blocks = [x0[i:i + block] for i in range(0, len(x0), block)]

    def loop(xb):  # the per-walk Python loop (as basin cells ran before amble_walk_batch)
        for x in xb:
            done = 0
            while done < steps:
                r = run(k, p, 0, x, steps=min(every, steps - done), opts=opts)
                if not r.completed:
                    break
                done += every
                x = r.x
                if float(np.max(np.abs(x - xs))) < tol:
                    break

    def batched(xb):
        walk_many(k, p, 0, xb, xs, steps=steps, check_every=every, tol=tol, opts=opts)

    pools = {w: ThreadPoolExecutor(w) for w in (1, 2)}
    small, big = (12, 24) if quick else (12, 40)  # basin maps: the earlier 12 × 12, and one whose cells dominate

    def bas(m: int, w: int, kept: bool = False):
        if not kept:  # each call works out its fixed point and section, as a first call in a process does
            basin_setup.forget()
        return sweep(system, "basin", _box(m), steps=steps, scheduler="synchronous", progress=False, threads=w)

    paths = {
        "one call per run (Python loop), blocks on a pool": (lambda w: list(pools[w].map(loop, blocks)), len(x0)),
        "`walk_many`, blocks of 16 on a pool": (lambda w: list(pools[w].map(batched, blocks)), len(x0)),
        "**one `walk_many(threads=)` batch** (rows taken one by one)":
            (lambda w: walk_many(k, p, 0, x0, xs, steps=steps, check_every=every, tol=tol, opts=opts, threads=w),
             len(x0)),
        **{_basin_row(m): (lambda w, m=m: bas(m, w), m * m) for m in (small, big)},
        **{_basin_row(m, kept=True): (lambda w, m=m: bas(m, w, kept=True), m * m) for m in (small, big)},
    }
    times: dict[tuple[str, int], list[float]] = {(name, w): [] for name in paths for w in (1, 2)}
    cpu: dict[tuple[str, int], list[float]] = {(name, w): [] for name in paths for w in (1, 2)}
    reps = 3 if quick else 7
    try:
        for fn, _ in paths.values():
            fn(1)  # warm-up
        for _ in range(reps):
            for name, (fn, _) in paths.items():
                for w in (1, 2):
                    t0, c0 = time.perf_counter(), time.process_time()
                    fn(w)
                    times[(name, w)].append(time.perf_counter() - t0)
                    cpu[(name, w)].append(time.process_time() - c0)
    finally:
        for pool in pools.values():
            pool.shutdown()
    held = {name: _gil_share(k, fn) for name, (fn, _) in paths.items() if "threads=" in name}
    # a basin's set-up (fixed point, section, result store) is serial whatever the grid: measured
    # alone as a 1 × 1 map, it splits the serial time into set-up and per cell
    setup = _gil_share(k, lambda w: bas(1, w), reps=7)
    setup_kept = _gil_share(k, lambda w: bas(1, w, kept=True), reps=7)
    rows, data, goals = [], {}, []
    for name, (_, cells) in paths.items():
        t1, t2 = statistics.median(times[(name, 1)]), statistics.median(times[(name, 2)])
        b1, b2 = min(times[(name, 1)]), min(times[(name, 2)])
        c1 = statistics.median(cpu[(name, 1)])
        data[name] = {"1": cells / t1, "2": cells / t2, "scaling": t1 / t2, "scaling_best": b1 / b2,
                      "cpu_per_walk_s": c1 / cells}
        h, outside, total = held.get(name, (None, None, None))
        bound = None
        if h is not None:
            # basin tasks run side by side: their Python overlaps the other thread's compiled walks,
            # only the set-up runs alone; one batch's own Python (thread starts) runs alone
            s0 = (setup_kept if "kept" in name else setup)[1] if name.startswith(BASIN_ROW) else outside
            bound = total / (s0 + max(outside - s0, (total - s0) / 2))
            data[name].update(gil_share=h, serial_s=outside, bound_2_cores=bound)
        rows.append([name, f"{cells / t1:,.0f}", f"{cells / t2:,.0f}", f"{cells / t1:,.0f}", f"{cells / t2 / 2:,.0f}",
                     f"{t1 / t2:.2f}×", f"{b1 / b2:.2f}×", f"{c1 / cells * 1e6:.0f}",
                     "—" if h is None else f"{h * 100:.1f} % → {bound:.2f}×"])
    shared = data["**one `walk_many(threads=)` batch** (rows taken one by one)"]
    goals.append(Goal("basin cells, batched, 2 threads ÷ 1 thread (in-process)", f"≥ {GOAL_SCALING:g}×",
                      f"{shared['scaling']:.2f}× (best of each: {shared['scaling_best']:.2f}×; GIL held "
                      f"{shared['gil_share'] * 100:.1f} % of a one-thread run: ≤ "
                      f"{shared['bound_2_cores']:.2f}× on two free cores)",
                      shared["scaling"] >= GOAL_SCALING))
    for m in (small, big):
        b = data[_basin_row(m)]
        b["serial_per_cell_s"] = (b["serial_s"] - setup[1]) / (m * m - 1)
        goals.append(Goal(f"{BASIN_ROW} {m} × {m} in process, 2 threads ÷ 1 thread", f"≥ {GOAL_SCALING:g}×",
                          f"{b['scaling']:.2f}× (best of each: {b['scaling_best']:.2f}×; GIL held "
                          f"{b['gil_share'] * 100:.1f} %: ≤ {b['bound_2_cores']:.2f}× on two free cores)",
                          b["scaling"] >= GOAL_SCALING))
    data["basin_setup_s"] = setup[1]
    md = (f"{n} × {n} compass-gait basin cells (≤ {steps} footfalls, checked every {every}, rtol = atol = "
          f"{BASIN_TOL:g}); medians (and the ratio of the best runs) of {reps} interleaved repeats, CPU time of "
          "the process per walk on one thread. *per core* = walks/s ÷ threads. *GIL held*: the share of a "
          "one-thread run's CPU time spent outside the compiled calls (Python, holding the GIL), and the "
          "speed-up on two free cores it allows — what the code permits, whatever the machine's load: a "
          "basin's tasks run side by side, so their Python overlaps the other thread's compiled walks and only "
          "the set-up runs alone (bound T₁ ÷ (set-up + max(Python, (T₁ − set-up) ÷ 2))); one batch's own Python "
          "runs alone (Amdahl); "
          "the wall-clock columns show what the machine gave. A basin's serial time is its set-up (fixed point, "
          f"section, result store: {setup[1] * 1e3:.1f} ms, a 1 × 1 map; {setup_kept[1] * 1e3:.1f} ms with the "
          "fixed point and section kept from an earlier call of the same system and parameters, "
          "`amble.analysis.basin_setup` — the goal rows work them out in every call) plus, per cell, "
          + ", ".join(f"{data[_basin_row(m)]['serial_per_cell_s'] * 1e6:.1f} µs ({m} × {m})" for m in (small, big))
          + " (Python: keys, the rows as text, the result store).\n\n"
          + table(["path", "walks/s, 1 thread", "walks/s, 2 threads", "per core, 1 thread", "per core, 2 threads",
                   "2 ÷ 1 (median)", "2 ÷ 1 (best)", "CPU µs/walk", "GIL held → bound on 2 cores"], rows))
    return md, goals, data


def _basin_row(m: int, kept: bool = False) -> str:
    """The row of an m × m basin sweep: its set-up worked out in the call (the goal's), or ``kept``
    from an earlier call with the same system and parameters (:mod:`amble.analysis.basin_setup`)."""
    how = "set-up kept from the call before" if kept else "with its set-up"
    return f"{BASIN_ROW} in process, {m} × {m}, `threads=` ({how}; the section projection)"


def _gil_share(k, fn, reps: int = 3) -> tuple[float, float, float]:
    """Share of a one-thread call of ``fn`` spent outside the compiled batch calls (CPU time of
    this thread): the part that holds the GIL; those seconds and the call's. Of ``reps`` calls,
    the one with the least time outside (the serial part is what this estimates; the least is
    the one least inflated by the machine, and set-up and map are then compared alike)."""
    from amble.backend.kernels import compiled
    from amble.models import load

    kernels = {id(x): x for x in (k, compiled(load("compass-gait"), derivatives=True))}.values()
    inside = [0.0]
    saved = []
    for kk in kernels:
        for name in ("_walk_batch", "_project_batch"):
            raw = getattr(kk, name)
            saved.append((kk, name, raw))

            def timed(*a, raw=raw):
                t0 = time.thread_time()
                raw(*a)
                inside[0] += time.thread_time() - t0
            setattr(kk, name, timed)
    try:
        best = (math.inf, 1.0, math.inf)
        for _ in range(reps):
            inside[0] = 0.0
            t0 = time.thread_time()
            fn(1)
            total = time.thread_time() - t0
            best = min(best, (total - inside[0], (total - inside[0]) / total if total > 0 else 1.0, total))
        return best[1], best[0], best[2]
    finally:
        for kk, name, raw in saved:
            setattr(kk, name, raw)


def _dask(system, n: int, steps: int, reps: int, data: dict, goals: list[Goal]) -> list[str]:
    """The Dask LocalCluster table of an n × n basin map on 1 and 2 workers (``reps`` interleaved
    runs), its numbers into ``data`` (``dask_{w}`` for the 100 × 100 map, ``dask_{n}_{w}``
    otherwise) and its goal into ``goals``."""
    cells, rows = n * n, []
    runs: dict[int, list[dict[str, float]]] = {1: [], 2: []}
    for _ in range(reps):  # interleaved: a change in the machine's load hits both alike
        for w in (1, 2):
            start, t_map, _, cpu = _one(system, n, w, steps)
            runs[w].append({"start_s": start, "map_s": t_map, **cpu})
    tag = "dask" if n == 100 else f"dask_{n}"
    for w in (1, 2):
        d = data[f"{tag}_{w}"] = {key: statistics.median(r[key] for r in runs[w]) for key in runs[w][0]}
        rows.append([str(w), f"{d['start_s']:.2f} s", f"{d['map_s']:.2f} s", f"{cells / d['map_s']:,.0f}",
                     f"{cells / d['map_s'] / w:,.0f}", f"{d['workers_cpu_s']:.2f} s",
                     f"{cells / d['workers_cpu_s']:,.0f}", f"{d['client_cpu_s']:.2f} s",
                     f"{d['workers_cpu_s'] / d['task_wall_s'] * w:.2f}"])
    d1, d2 = data[f"{tag}_1"], data[f"{tag}_2"]
    sp = d1["map_s"] / d2["map_s"]
    # what two free cores would give: the workers' CPU split evenly, plus the client's own work
    free = (d1["workers_cpu_s"] + d1["client_cpu_s"]) / (d2["workers_cpu_s"] / 2 + d2["client_cpu_s"])
    big = n != 100
    goals.append(Goal(f"basin map {n} × {n} ({cells:,} cells), Dask 2 workers ÷ 1 worker" if big
                      else "basin map, Dask 2 workers ÷ 1 worker",
                      f"≥ {GOAL_SCALING:g}×" if big else "(reported)",
                      f"{sp:.2f}× wall, map only ({d1['map_s']:.2f} → {d2['map_s']:.2f} s; cluster start-up "
                      f"{d1['start_s']:.2f} and {d2['start_s']:.2f} s besides); cores given to 2 workers "
                      f"{d2['workers_cpu_s'] / d2['task_wall_s'] * 2:.2f}; from CPU times {free:.2f}× on two free "
                      f"cores; per worker CPU s: {cells / d1['workers_cpu_s']:,.0f} and "
                      f"{cells / d2['workers_cpu_s']:,.0f} cells", sp >= GOAL_SCALING if big else None))
    return ["", f"### Dask LocalCluster: {n} × {n} basin map ({cells:,} cells), ≤ {steps} footfalls per cell", "",
            f"Medians of {reps} interleaved runs; {d1['tasks']:.0f} tasks of "
            f"{cells / d1['tasks']:.0f} cells. *start-up*: the cluster started, amble imported and the compiled "
            "model loaded in each worker (the overhead of a Dask sweep besides its map); *worker CPU*: CPU "
            "seconds of the workers, summed; *cells per worker CPU s* is the throughput per core the work "
            "itself allows, which the machine's load does not change; *client CPU*: this process (client, "
            "scheduler, result file); *cores given*: worker CPU ÷ the wall time the tasks took on their "
            "workers × workers — below the number of workers, the machine ran other things on those cores.",
            "", table(["workers", "start-up", "map", "cells/s", "cells/s per worker", "worker CPU",
                       "cells per worker CPU s", "client CPU", "cores given"], rows)]


def run(quick: bool = False) -> Section:
    """In-process thread scaling, the command line on local processes and on Dask; with a full run
    also the Dask LocalCluster basin maps (100 × 100 and 317 × 317, about 10⁵ cells)."""
    from benchmarks import bench_sweep_cli

    md, goals, data = threads(quick)
    parts = ["### In one process: 1 and 2 threads", "", md]
    cli_md, cli_goals, data["cli"] = bench_sweep_cli.run(quick)
    goals += cli_goals
    parts += ["", "### Command line: `amble sweep` on 1 and 2 workers", "", cli_md]
    if not quick:
        from amble.backend.kernels import compiled
        from amble.models import load

        system = load("compass-gait")
        compiled(system)
        parts += _dask(system, 100, 60, 3, data, goals)
        parts += _dask(system, 317, 60, 3, data, goals)
    return Section("Basin maps and sweeps: scaling with cores", "\n".join(parts), goals, data)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=100, help="grid size per axis (default 100)")
    ap.add_argument("--steps", type=int, default=60, help="footfalls per cell at most (default 60)")
    args = ap.parse_args()
    from amble.analysis.sweep import sweep
    from amble.backend.kernels import compiled
    from amble.models import load

    system = load("compass-gait")
    compiled(system)  # compile once, outside the timings
    cells = args.n * args.n
    t0 = time.perf_counter()
    ref = sweep(system, "basin", _box(args.n), steps=args.steps, scheduler="synchronous", progress=False)
    t_serial = time.perf_counter() - t0
    print(f"{args.n} × {args.n} basin map, ≤ {args.steps} steps per cell: {ref.counts()}")
    print(f"in-process (no Dask):  {t_serial:6.2f} s   {cells / t_serial:8.0f} initial conditions/s")
    times = {}
    for w in (1, 2):
        start, t_map, counts, cpu = _one(system, args.n, w, args.steps)
        assert counts == ref.counts(), "distributed result differs from the in-process one"
        times[w] = t_map
        print(f"{w} worker(s): start-up {start:5.2f} s, map {t_map:6.2f} s, total {start + t_map:6.2f} s   "
              f"{cells / t_map:8.0f} initial conditions/s; worker CPU {cpu['workers_cpu_s']:.2f} s, client CPU "
              f"{cpu['client_cpu_s']:.2f} s")
    print(f"speed-up 2 vs 1 worker (map only): {times[1] / times[2]:.2f}×")
    ok = times[2] <= 10.0
    print(f"goal ≤ 10 s on 2 workers: {'met' if ok else 'NOT met'} ({times[2]:.2f} s)")


if __name__ == "__main__":
    main()
