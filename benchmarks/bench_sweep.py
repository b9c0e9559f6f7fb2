"""Benchmark: basin maps of the compass gait in one process on 1 and 2 threads, and on 1 and 2
Dask LocalCluster workers.

In-process (:func:`threads`): the same cells walked one ``engine.run`` call per run of footfalls
(the loop basin maps used before) and in blocks by ``engine.walk_many`` (one compiled call per
block, ``amble_walk_batch``), each on a thread pool of 1 and 2 threads; one ``walk_many`` batch
whose rows 1 or 2 threads take one at a time (``threads=``); and ``basin()`` itself in this process.
Throughput in walks per second and per core, medians of interleaved repeats. The goal: the
batched path scales ≥ 1.8× from 1 to 2 threads.

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
import statistics
import time
from concurrent.futures import ThreadPoolExecutor

import numpy as np

from benchmarks.common import Goal, Section, table

#: Goal: throughput of the batched path on 2 threads ÷ on 1 thread.
GOAL_SCALING = 1.8


def _warm(system) -> None:
    from amble.backend.kernels import build

    build(system)


def _one(system, n: int, workers: int, steps: int) -> tuple[float, float, dict[str, int]]:
    from dask.distributed import Client, LocalCluster

    from amble.analysis.sweep import basin

    t0 = time.perf_counter()
    cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None)
    client = Client(cluster)
    client.run(_warm, system)  # import amble and load the compiled model in each worker
    t1 = time.perf_counter()
    try:
        res = basin(system, ("stance", "stance_dot"), ((-0.35, -0.10), (0.8, 1.4)), (n, n), steps=steps,
                    scheduler=client, progress=False)
    finally:
        client.close()
        cluster.close()
    t2 = time.perf_counter()
    return t1 - t0, t2 - t1, res.counts()


def _cells(system, n: int):
    """(kernels, parameters, fixed point, n² initial post-impact states around the fixed point)."""
    from amble.analysis.poincare import find_fixed_point
    from amble.backend.kernels import build
    from amble.simulation.simulate import parameter_vector

    k = build(system)
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
    rows the threads take one by one; and ``basin()`` in this process (``threads=``), which
    also puts every cell on the section in Python."""
    from amble.analysis.basin import basin
    from amble.analysis.defaults import BASIN_TOL
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
    nb = max(4, n // 2)  # the basin map: a smaller grid (its cells are projected in Python)
    grid = (("stance", "stance_dot"), ((-0.35, -0.10), (0.8, 1.4)), (nb, nb))
    paths = {
        "one call per run (Python loop), blocks on a pool": (lambda w: list(pools[w].map(loop, blocks)), len(x0)),
        "`walk_many`, blocks of 16 on a pool": (lambda w: list(pools[w].map(batched, blocks)), len(x0)),
        "**one `walk_many(threads=)` batch** (rows taken one by one)":
            (lambda w: walk_many(k, p, 0, x0, xs, steps=steps, check_every=every, tol=tol, opts=opts, threads=w),
             len(x0)),
        f"`basin()` in process, {nb} × {nb}, `threads=` (with the section projection)":
            (lambda w: basin(system, *grid, steps=steps, scheduler="synchronous", progress=False, threads=w),
             nb * nb),
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
    rows, data, goals = [], {}, []
    for name, (_, cells) in paths.items():
        t1, t2 = statistics.median(times[(name, 1)]), statistics.median(times[(name, 2)])
        b1, b2 = min(times[(name, 1)]), min(times[(name, 2)])
        c1 = statistics.median(cpu[(name, 1)])
        data[name] = {"1": cells / t1, "2": cells / t2, "scaling": t1 / t2, "scaling_best": b1 / b2,
                      "cpu_per_walk_s": c1 / cells}
        h = held.get(name)
        if h is not None:
            data[name]["gil_share"] = h
        rows.append([name, f"{cells / t1:,.0f}", f"{cells / t2:,.0f}", f"{cells / t1:,.0f}", f"{cells / t2 / 2:,.0f}",
                     f"{t1 / t2:.2f}×", f"{b1 / b2:.2f}×", f"{c1 / cells * 1e6:.0f}",
                     "—" if h is None else f"{h * 100:.1f} % → {1 / (h + (1 - h) / 2):.2f}×"])
    shared = data["**one `walk_many(threads=)` batch** (rows taken one by one)"]
    goals.append(Goal("basin cells, batched, 2 threads ÷ 1 thread (in-process)", f"≥ {GOAL_SCALING:g}×",
                      f"{shared['scaling']:.2f}× (best of each: {shared['scaling_best']:.2f}×; GIL held "
                      f"{shared['gil_share'] * 100:.1f} % of a one-thread run: ≤ "
                      f"{1 / (shared['gil_share'] + (1 - shared['gil_share']) / 2):.2f}× on two free cores)",
                      shared["scaling"] >= GOAL_SCALING))
    bas = data[f"`basin()` in process, {nb} × {nb}, `threads=` (with the section projection)"]
    goals.append(Goal("`basin()` in process, 2 threads ÷ 1 thread", "(reported)",
                      f"{bas['scaling']:.2f}× (best of each: {bas['scaling_best']:.2f}×; GIL held "
                      f"{bas['gil_share'] * 100:.1f} %)", None))
    md = (f"{n} × {n} compass-gait basin cells (≤ {steps} footfalls, checked every {every}, rtol = atol = "
          f"{BASIN_TOL:g}); medians (and the ratio of the best runs) of {reps} interleaved repeats, CPU time of "
          "the process per walk on one thread. *per core* = walks/s ÷ threads. *GIL held*: the share of a "
          "one-thread run's CPU time spent outside the compiled calls (Python, holding the GIL), and the "
          "speed-up on two free cores it allows (Amdahl) — what the code permits, whatever the machine's load; "
          "the wall-clock columns show what the machine gave.\n\n"
          + table(["path", "walks/s, 1 thread", "walks/s, 2 threads", "per core, 1 thread", "per core, 2 threads",
                   "2 ÷ 1 (median)", "2 ÷ 1 (best)", "CPU µs/walk", "GIL held → bound on 2 cores"], rows))
    return md, goals, data


def _gil_share(k, fn, reps: int = 3) -> float:
    """Share of a one-thread call of ``fn`` spent outside the compiled batch calls (CPU time of
    this thread, least of ``reps``): the part that holds the GIL and cannot run on two cores."""
    from amble.backend.kernels import build
    from amble.models import load

    kernels = {id(x): x for x in (k, build(load("compass-gait"), derivatives=True))}.values()
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
        best = 1.0
        for _ in range(reps):
            inside[0] = 0.0
            t0 = time.thread_time()
            fn(1)
            total = time.thread_time() - t0
            best = min(best, (total - inside[0]) / total if total > 0 else 1.0)
        return best
    finally:
        for kk, name, raw in saved:
            setattr(kk, name, raw)


def run(quick: bool = False) -> Section:
    """In-process thread scaling; with a full run also the Dask LocalCluster basin map."""
    md, goals, data = threads(quick)
    parts = ["### In one process: 1 and 2 threads", "", md]
    if not quick:
        from amble.backend.kernels import build
        from amble.models import load

        system = load("compass-gait")
        build(system)
        n, steps = 100, 60
        cells = n * n
        rows = []
        for w in (1, 2):
            start, t_map, _ = _one(system, n, w, steps)
            data[f"dask_{w}"] = {"start_s": start, "map_s": t_map}
            rows.append([str(w), f"{start:.2f} s", f"{t_map:.2f} s", f"{cells / t_map:,.0f}",
                         f"{cells / t_map / w:,.0f}"])
        parts += ["", f"### Dask LocalCluster: {n} × {n} basin map, ≤ {steps} footfalls per cell", "",
                  table(["workers", "start-up", "map", "cells/s", "cells/s per worker"], rows)]
        sp = data["dask_1"]["map_s"] / data["dask_2"]["map_s"]
        goals.append(Goal("basin map, Dask 2 workers ÷ 1 worker", "(reported)",
                          f"{sp:.2f}× ({cells / data['dask_1']['map_s']:,.0f} and "
                          f"{cells / data['dask_2']['map_s'] / 2:,.0f} cells/s per worker)", None))
    return Section("Basin maps and sweeps: scaling with cores", "\n".join(parts), goals, data)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=100, help="grid size per axis (default 100)")
    ap.add_argument("--steps", type=int, default=60, help="footfalls per cell at most (default 60)")
    args = ap.parse_args()
    from amble.analysis.sweep import basin
    from amble.backend.kernels import build
    from amble.models import load

    system = load("compass-gait")
    build(system)  # compile once, outside the timings
    cells = args.n * args.n
    t0 = time.perf_counter()
    ref = basin(system, ("stance", "stance_dot"), ((-0.35, -0.10), (0.8, 1.4)), (args.n, args.n),
                steps=args.steps, scheduler="synchronous", progress=False)
    t_serial = time.perf_counter() - t0
    print(f"{args.n} × {args.n} basin map, ≤ {args.steps} steps per cell: {ref.counts()}")
    print(f"in-process (no Dask):  {t_serial:6.2f} s   {cells / t_serial:8.0f} initial conditions/s")
    times = {}
    for w in (1, 2):
        start, t_map, counts = _one(system, args.n, w, args.steps)
        assert counts == ref.counts(), "distributed result differs from the in-process one"
        times[w] = t_map
        print(f"{w} worker(s): start-up {start:5.2f} s, map {t_map:6.2f} s, total {start + t_map:6.2f} s   "
              f"{cells / t_map:8.0f} initial conditions/s")
    print(f"speed-up 2 vs 1 worker (map only): {times[1] / times[2]:.2f}×")
    ok = times[2] <= 10.0
    print(f"goal ≤ 10 s on 2 workers: {'met' if ok else 'NOT met'} ({times[2]:.2f} s)")


if __name__ == "__main__":
    main()
