"""Mean first-passage time by Monte Carlo: what a simulated step of :func:`amble.mfpt` costs beside
a plain walking step, and how its walks scale from one thread to two.

Model: the compass gait on ``slope ~ normal(0.0525, 0.01)`` rad (Byl & Tedrake's stochastic
compass gait; every walker starts from the gait at the mean slope), integrator rtol = atol =
1e-10 throughout (:class:`amble.simulation.engine.Options`' default, which :func:`amble.mfpt`
uses).

* plain walking step: ``engine.run`` walking 200 steps from the fixed point in one compiled call
  (the fast path of ``benchmarks.bench_walk``), per step;
* batched walk: ``walk_many`` walking ``RUNS`` walkers 20 steps each in one compiled call, per
  walker-step (what the Monte Carlo would cost if the terrain did not change every step);
* MFPT step: :func:`amble.mfpt` with ``RUNS`` walkers, per simulated step (falling steps counted):
  one compiled call per step of all walkers still up, each with its own draw of the slope, plus
  the Python around it (drawing, gathering the survivors); every walker starts from the fixed
  point found once beforehand (``start``), so the search is not timed;
* scaling: :func:`amble.mfpt` with ``SCALING_RUNS`` = 10⁵ walkers on ``threads=1`` and
  ``threads=2`` (the walks of a step shared row by row; the results do not depend on it).

Run alone: ``python -m benchmarks --only mfpt --no-write``.
"""

from __future__ import annotations

import os
import time
from typing import Any

import numpy as np

from benchmarks.common import Section, Stats, ratio, table, us

TERRAIN = "slope~normal(0.0525,0.01)"
RUNS = 5_000
SCALING_RUNS = 100_000
REPEATS = 5
SCALING_REPEATS = 3


def _setup() -> tuple[Any, Any, np.ndarray, np.ndarray]:
    from amble.analysis.poincare import find_fixed_point
    from amble.backend.kernels import compiled
    from amble.models import load
    from amble.simulation.simulate import parameter_vector

    system = load("compass-gait")
    k = compiled(system)
    p = parameter_vector(k, {"slope": 0.0525}, system)
    x0 = np.asarray(find_fixed_point(system, params={"slope": 0.0525}).fixed_point, float)
    return system, k, p, x0


def _per_step(fn: Any, steps_of: Any, repeats: int) -> tuple[Stats, Stats, Any]:
    """Wall and CPU time (s) per step of ``repeats`` calls, and the last result. On one thread the
    CPU time is the work itself: load on the machine stretches the wall time, much less the CPU."""
    walls, cpus, out = [], [], None
    for _ in range(repeats):
        t0, c0 = time.perf_counter(), time.process_time()
        out = fn()
        n = steps_of(out)
        walls.append((time.perf_counter() - t0) / n)
        cpus.append((time.process_time() - c0) / n)
    return Stats.of(walls), Stats.of(cpus), out


def run(quick: bool = False) -> Section:
    from amble import Terrain, mfpt
    from amble.simulation.engine import Options, walk_many
    from amble.simulation.engine import run as walk

    system, k, p, x0 = _setup()
    opts = Options(max_step_time=system.max_step_time)
    terrain = Terrain.parse(TERRAIN)
    runs = 500 if quick else RUNS
    repeats = 2 if quick else REPEATS
    walk(k, p, 0, x0, steps=200, opts=opts)  # warm-up
    plain, plain_cpu, _ = _per_step(lambda: walk(k, p, 0, x0, steps=200, opts=opts), lambda r: r.steps,
                                    10 * repeats)
    X = np.tile(x0, (runs, 1))
    batched, batched_cpu, _ = _per_step(
        lambda: walk_many(k, p, 0, X, x0, steps=20, check_every=20, tol=-1.0, opts=opts),
        lambda o: int(o["steps"].sum()), repeats)
    mc, mc_cpu, r = _per_step(
        lambda: mfpt(system, terrain, runs=runs, max_steps=10_000, seed=1, start=x0, opts=opts),
        lambda r: r.steps, repeats)
    rows = [[name, us(w.median), us(w.min), us(c.median), ratio(c.median, plain_cpu.median), ratio(w.min, plain.min)]
            for name, w, c in (("plain walk: `engine.run`, 200 steps", plain, plain_cpu),
                               (f"batched: `walk_many`, {runs} walkers × 20 steps", batched, batched_cpu),
                               (f"`amble.mfpt`, {runs} walkers", mc, mc_cpu))]
    md = [f"Compass gait, `{TERRAIN}`, rtol = atol = 1e-10; µs per simulated step (median and minimum of "
          f"{repeats}, the plain walk {10 * repeats}; CPU: this process's CPU time). "
          f"The MFPT run: {r.runs} walkers, {r.steps} steps, MFPT {r.mfpt:.2f} steps "
          f"(interval {r.ci_low:.2f}–{r.ci_high:.2f}).", "",
          table(["", "wall µs/step median", "wall min", "CPU µs/step median", "÷ plain (CPU medians)",
                 "÷ plain (wall minima)"], rows), ""]
    data: dict[str, Any] = {"plain_us": plain.median * 1e6, "batched_us": batched.median * 1e6,
                            "mfpt_us": mc.median * 1e6, "plain_cpu_us": plain_cpu.median * 1e6,
                            "mfpt_cpu_us": mc_cpu.median * 1e6, "mfpt": r.mfpt, "steps": r.steps}
    n_scale = 10_000 if quick else SCALING_RUNS
    srep = 1 if quick else SCALING_REPEATS
    walls: dict[int, list[float]] = {1: [], 2: []}
    results = {}
    for _ in range(srep):  # interleaved, so load on the machine hits both alike
        for threads in (1, 2):
            t0 = time.perf_counter()
            results[threads] = mfpt(system, terrain, runs=n_scale, max_steps=10_000, seed=2, threads=threads,
                                    start=x0, opts=opts)
            walls[threads].append(time.perf_counter() - t0)
    s1, s2 = Stats.of(walls[1]), Stats.of(walls[2])
    same = results[1].to_json() == results[2].to_json()
    res = results[1]
    md += [f"{n_scale:,} walkers ({res.steps:,} steps, MFPT {res.mfpt:.3f}, interval {res.ci_low:.3f}–"
           f"{res.ci_high:.3f}), seconds (median and minimum of {srep}, 1 and 2 threads interleaved); the "
           f"two give {'the same' if same else '**different**'} result:", "",
           table(["threads", "s median", "s min", "µs/step median", "speed-up"],
                 [[1, f"{s1.median:.2f}", f"{s1.min:.2f}", us(s1.median / res.steps), "1.00×"],
                  [2, f"{s2.median:.2f}", f"{s2.min:.2f}", us(s2.median / res.steps), ratio(s1.median, s2.median)]]),
           "", f"Load average at the end (1, 5, 15 min): {' '.join(f'{v:.2f}' for v in os.getloadavg())}. "
           "The machine is a shared 2-core virtual machine with other work running: single timings "
           "wander by tens of percent, and two threads can only reach 2× when the second core is idle."]
    data.update({"scaling_runs": n_scale, "t1_s": s1.median, "t2_s": s2.median, "same": same})
    return Section("Mean first-passage time: Monte Carlo", "\n".join(md), [], data)


if __name__ == "__main__":
    print(run().markdown)
