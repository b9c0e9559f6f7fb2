"""3D models written the thesis' way: a chain of ``n`` links as points with ``link=``, rotation
matrices composed joint by joint (axes alternating x, y) and ``body_inertia`` per link — the style
of the thesis' 3D humanoid, without ``Model.rigid_tree()``. Each case is a cold build (derive,
generate, compile into a new cache) in a fresh process; wall time and CPU time of the process and
of its compilers. The model is the one ``tests/test_body_inertia_route.py`` checks against
Pinocchio.

Run alone: ``python -m benchmarks --only thesis3d --no-write``.
"""

from __future__ import annotations

import json
import os
import statistics
import subprocess
import sys
import tempfile

from benchmarks.common import Goal, Section, table

#: goals of the robot-file issue: cold builds of the thesis-style chain (s)
GOALS = {7: 3.0, 12: 8.0}

_CHILD = r"""
import json, os, resource, sys, time
import sympy as sp
from amble import HybridSystem, Model, Rx, Ry
from amble.backend.kernels import compiled
n = int(sys.argv[1])
t0 = time.perf_counter()
m = Model(f"thesis_chain{n}", dims=3)
q = m.coordinates(" ".join(f"q{i}" for i in range(n)))
g, l, mass = m.parameters(g=9.81, l=0.3, mass=1.0)
m.gravity(g)
R, tip, prev = sp.eye(3), sp.zeros(3, 1), "base"
m.point("base", (0, 0, 0))
for i, qi in enumerate(q):
    R = R * (Rx(qi) if i % 2 == 0 else Ry(qi))
    m.point(f"c{i}", tip - l / 2 * R[:, 2], mass=mass)
    tip = tip - l * R[:, 2]
    m.point(f"p{i}", tip, link=prev)
    prev = f"p{i}"
    m.body_inertia(R, sp.diag(0.01, 0.01, 0.002))
system = HybridSystem(f"thesis_chain{n}", m)
t1 = time.perf_counter()
compiled(system)
t2 = time.perf_counter()
me, cc = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
print(json.dumps({"model": t1 - t0, "build": t2 - t1, "cpu": me.ru_utime + me.ru_stime,
                  "cc": cc.ru_utime + cc.ru_stime}))
"""


def _cold(n: int, timeout: float) -> dict | None:
    with tempfile.TemporaryDirectory() as cache:
        env = {**os.environ, "AMBLE_CACHE_DIR": cache}
        try:
            out = subprocess.run([sys.executable, "-c", _CHILD, str(n)], env=env, capture_output=True, text=True,
                                 timeout=timeout, check=True).stdout
        except subprocess.TimeoutExpired:
            return None
    return json.loads(out.strip().splitlines()[-1])


def run(quick: bool = False) -> Section:
    sizes = [3, 5] if quick else [5, 7, 12]
    runs = 1 if quick else 2
    rows, goals, data = [], [], {}
    for n in sizes:
        got = [r for r in (_cold(n, 1800.0) for _ in range(runs)) if r is not None]
        if not got:
            rows.append([str(n), "> 1800", "", "", ""])
            data[n] = None
        else:
            med = {k: statistics.median(r[k] for r in got) for k in got[0]}
            data[n] = med
            rows.append([str(n), f"{med['model'] + med['build']:.1f}", f"{med['model']:.2f}",
                         f"{med['cpu']:.1f}", f"{med['cc']:.1f}"])
        if n in GOALS:
            total = None if data[n] is None else data[n]["model"] + data[n]["build"]
            goals.append(Goal(f"cold build, thesis-style {n}-link 3D chain (points, body_inertia)",
                              f"≤ {GOALS[n]:g} s", "—" if total is None else f"{total:.1f} s",
                              None if total is None else total <= GOALS[n]))
    md = [f"Cold builds in a fresh process and cache, median of {runs} (wall s; CPU s of the process and of "
          "the compilers it ran):", "",
          table(["links", "model + build s", "model s", "CPU s", "compilers CPU s"], rows)]
    return Section("Thesis-style 3D chains", "\n".join(md), goals, data)


if __name__ == "__main__":
    print(run("--quick" in sys.argv).markdown)
