"""Benchmark: a 100 × 100 basin map of the compass gait on 1 and 2 Dask LocalCluster workers.

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
import time


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
