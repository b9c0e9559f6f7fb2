"""Rigid-body trees: cold build time, operation count, and q̈ per call beside Pinocchio's ABA.

Cases: a spatial chain of n rigid bodies (full inertia tensors, joint axes cycling y, x, z,
written with ``Model.rigid_tree()``) for n = 2 … 30, and the URDF robots of ``tests/data``
(12-DOF biped, 30-DOF humanoid) loaded with ``Model.from_urdf``. Each build runs in a fresh
interpreter with a fresh ``AMBLE_CACHE_DIR`` (no model compiled; the shared runtime seeded, its
one-time compile reported in a row of its own: :mod:`benchmarks.runtime_seed`): *build* = model +
derive + generate + compile + load (wall clock; imports excluded — the URDF parser's own import,
which pulls in trimesh and scipy.spatial, is done before the clock starts and reported
separately). The stages are timed inside the same run: *derive* (``derive`` as called by the code
generator), *generate* (the rest of code generation: common subexpressions, printing) and *cc*
(the C compiler, wall). ``ops``: :meth:`amble.Equations.count_ops` (M, h with shared
subexpressions); the growth exponent is the
least-squares slope of log ops against log n over the chain sizes n ≥ 4.

Per call: amble's q̈ (``amble_rhs``: M, h, Cholesky solve) timed **in C**, by a loop compiled
here that calls the generated library's entry point over 64 random states; Pinocchio's
``aba`` timed in a tight Python loop over the same states, and its binding's overhead measured
separately as the same loop over ``aba`` of a 1-joint model (so *net* = aba − binding). Medians of
5 repetitions, minima beside them.

Run alone: ``python -m benchmarks.bench_tree`` (``--quick`` for fewer cases).
"""

from __future__ import annotations

import argparse
import ctypes
import math
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from benchmarks.common import Goal, Section, child_env, emit_result, run_worker, table
from benchmarks.runtime_seed import SECTION_NOTE, row_text, seeded_cache_dir

DATA = Path(__file__).resolve().parents[1] / "tests" / "data"
STATES = 64  # random states cycled through by the per-call loops
REPEATS = 5

_TIMER_C = r"""
#include <time.h>
typedef int (*rhs_fn)(int, double, const double *, const double *, double *);
/* Seconds per call of rhs over `reps` calls cycling through `ns` states of size 2n. */
double amble_bench_rhs(void *f, int mode, int n, int ns, const double *xs, const double *p,
                       double *dx, long reps, double *sink) {
    rhs_fn rhs = (rhs_fn)f;
    struct timespec a, b;
    double s = 0.0;
    clock_gettime(CLOCK_MONOTONIC, &a);
    for (long r = 0; r < reps; ++r) {
        rhs(mode, 0.0, xs + (r % ns) * 2 * n, p, dx);
        s += dx[n];
    }
    clock_gettime(CLOCK_MONOTONIC, &b);
    *sink = s;
    return ((double)(b.tv_sec - a.tv_sec) + 1e-9 * (double)(b.tv_nsec - a.tv_nsec)) / (double)reps;
}
"""


def chain(n: int):
    from amble import Model
    from amble.modelling.tree import Joint

    m = Model(f"spatial_chain{n}", dims=3)
    m.gravity(9.81)
    tree = m.rigid_tree()
    axes = [(0, 1, 0), (1, 0, 0), (0, 0, 1)]
    parent = None
    for i in range(n):
        tree.body(f"l{i}", parent=parent, joint=Joint("revolute", axis=axes[i % 3], xyz=(0, 0, -0.3 if i else 0)),
                  mass=1.0 + 0.1 * i, com=(0.02, 0.01, -0.15),
                  inertia=[[0.02, 0.001, 0.0], [0.001, 0.03, 0.002], [0.0, 0.002, 0.01]])
        parent = f"l{i}"
    return m


def _timer(tmp: Path):
    """The C timing loop, compiled here (the same compiler and flags as the generated code)."""
    from amble.backend.cache import cflags, compiler

    src, so = tmp / "timer.c", tmp / "timer.so"
    src.write_text(_TIMER_C)
    subprocess.run([*compiler().split(), *cflags(), "-fPIC", "-shared", str(src), "-o", str(so)], check=True)
    lib = ctypes.CDLL(str(so))
    lib.amble_bench_rhs.restype = ctypes.c_double
    return lib


def _py_loop(fn, states, reps: int) -> float:
    """Seconds per call of ``fn(state)`` in a tight Python loop over ``states``."""
    fn(states[0])
    k = len(states)
    t0 = time.perf_counter()
    for r in range(reps):
        fn(states[r % k])
    return (time.perf_counter() - t0) / reps


def _stats(samples: list[float]) -> dict[str, float]:
    return {"median": statistics.median(samples), "min": min(samples)}


def worker(case: str) -> None:
    import numpy as np

    if not case.startswith("chain"):
        t0 = time.perf_counter()
        import yourdfpy  # noqa: F401 - the parser's import (trimesh, scipy.spatial) is not build time
        parser_import_s = time.perf_counter() - t0
    from amble import HybridSystem, Model
    from amble.backend import cache, codegen
    from amble.backend.kernels import compiled

    stage = {"derive": 0.0, "cc": 0.0, "generate": 0.0}

    def timed(mod, attr, key):
        f = getattr(mod, attr)

        def wrapper(*a, **kw):
            t = time.perf_counter()
            try:
                return f(*a, **kw)
            finally:
                stage[key] += time.perf_counter() - t
        setattr(mod, attr, wrapper)

    timed(codegen, "derive", "derive")
    timed(codegen, "generate", "generate")
    timed(cache, "_compile", "cc")
    cpu0 = time.process_time()
    ch0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    m = chain(int(case[5:])) if case.startswith("chain") else Model.from_urdf(DATA / f"{case}.urdf")
    model_s = time.perf_counter() - t0
    sys_ = HybridSystem(m.name, m)
    k = compiled(sys_)
    build_s = time.perf_counter() - t0
    ch1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu_s = time.process_time() - cpu0 + (ch1.ru_utime - ch0.ru_utime) + (ch1.ru_stime - ch0.ru_stime)
    n = len(m.q)
    out = {"case": case, "n": n, "build_s": build_s, "cpu_s": cpu_s, "model_s": model_s,
           "derive_s": stage["derive"], "generate_s": stage["generate"] - stage["derive"], "cc_s": stage["cc"],
           "ops": codegen.derive(m).count_ops()}
    if not case.startswith("chain"):
        out["parser_import_s"] = parser_import_s
    rng = np.random.default_rng(0)
    xs = [np.concatenate([rng.uniform(-1, 1, n), rng.uniform(-1, 1, n)]) for _ in range(STATES)]
    flat = np.ascontiguousarray(np.concatenate(xs))
    p = np.asarray(k.meta["param_defaults"] or [0.0], dtype=float)
    dx = np.zeros(2 * n)
    sink = ctypes.c_double()
    with tempfile.TemporaryDirectory() as tmp:
        timer = _timer(Path(tmp))
        fptr = ctypes.cast(k._lib.amble_rhs, ctypes.c_void_p)
        dp = lambda a: a.ctypes.data_as(ctypes.c_void_p)
        reps = max(2000, int(2e6 / max(n * n, 1)))
        samples = [timer.amble_bench_rhs(fptr, 0, n, STATES, dp(flat), dp(p), dp(dx), ctypes.c_long(reps),
                                         ctypes.byref(sink)) for _ in range(REPEATS)]
    out["rhs_c_s"] = _stats(samples)
    out["rhs_ctypes_s"] = _stats([_py_loop(lambda x: k.rhs(0, 0.0, x, p), xs, 20000) for _ in range(REPEATS)])
    try:
        import pinocchio as pin
    except ImportError:
        emit_result(out)
        return
    if not case.startswith("chain"):  # the chain has no URDF: its Pinocchio time is not measured
        pm = pin.buildModelFromUrdf(str(DATA / f"{case}.urdf"))
        pd = pm.createData()
        tau = np.zeros(n)
        pstates = [(x[:n].copy(), x[n:].copy()) for x in xs]
        out["pin_aba_s"] = _stats([_py_loop(lambda s: pin.aba(pm, pd, s[0], s[1], tau), pstates, 20000)
                                   for _ in range(REPEATS)])
        one = pin.Model()
        one.appendBodyToJoint(one.addJoint(0, pin.JointModelRY(), pin.SE3.Identity(), "j"),
                              pin.Inertia.Random(), pin.SE3.Identity())
        od = one.createData()
        z1 = [(np.zeros(1), np.zeros(1))] * 4
        out["pin_binding_s"] = _stats([_py_loop(lambda s: pin.aba(one, od, s[0], s[1], s[1]), z1, 20000)
                                       for _ in range(REPEATS)])
        out["pin_version"] = pin.__version__
    emit_result(out)


def _cold(case: str, runs: int) -> dict | None:
    """``runs`` cold builds of a case (fresh process and cache each); the last run's numbers with
    the build times of all."""
    got, builds = None, []
    for _ in range(runs):
        cache = seeded_cache_dir()
        try:
            r = run_worker("benchmarks.bench_tree", ["--worker", case], child_env(cache), timeout_s=1200)
        finally:
            shutil.rmtree(cache, ignore_errors=True)
        if r is None:
            return None
        got = r
        builds.append(r["build_s"])
    got["builds"] = builds
    return got


def _slope(ns: list[int], ops: list[int]) -> float:
    xs, ys = [math.log(v) for v in ns], [math.log(v) for v in ops]
    mx, my = sum(xs) / len(xs), sum(ys) / len(ys)
    return sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sum((x - mx) ** 2 for x in xs)


def _build_cell(r: dict) -> str:
    b = r["builds"]
    med = statistics.median(b)
    return f"{med:.2f} s" + (f" (min {min(b):.2f}, {len(b)} runs)" if len(b) > 1 else "")


def run(quick: bool = False) -> Section:
    ns = [2, 4, 7] if quick else [2, 3, 4, 6, 7, 8, 12, 16, 20, 24, 30]
    robots = ["biped12"] if quick else ["biped12", "humanoid30"]
    repeat = {"chain7": 1 if quick else 3, "biped12": 1 if quick else 3}
    data: dict[str, dict] = {}
    rows = []
    for nn in ns:
        case = f"chain{nn}"
        r = _cold(case, repeat.get(case, 1))
        if r is None:
            rows.append([nn, "> 1200 s", "", "", "", "", "", "", ""])
            continue
        data[case] = r
        rows.append([nn, _build_cell(r), f"{r['cpu_s']:.2f} s", f"{r['model_s']:.2f}", f"{r['derive_s']:.2f}",
                     f"{r['generate_s']:.2f}", f"{r['cc_s']:.2f}", r["ops"], f"{r['rhs_c_s']['median'] * 1e6:.2f} µs"])
    fit = [(r["n"], r["ops"]) for r in data.values() if r["n"] >= 4]
    slope = _slope([a for a, _ in fit], [b for _, b in fit]) if len(fit) >= 2 else None
    rows.append(["runtime, once per machine", row_text((8, 16) if quick else (8, 16, 32, 64)),
                 "", "", "", "", "", "", ""])
    md = [SECTION_NOTE, "", "Spatial chain (axes cycling y, x, z; full inertia tensors):", "",
          table(["n", "cold build (wall)", "CPU (process + cc)", "model s", "derive s", "generate s", "cc s",
                 "ops (M, h)", "q̈ per call (C)"], rows)]
    if slope is not None:
        md += ["", f"Operation count grows as n^{slope:.2f} (least-squares fit of log ops on log n, "
                   f"n = {min(a for a, _ in fit)} … {max(a for a, _ in fit)})."]
    prow = []
    for case in robots:
        r = _cold(case, repeat.get(case, 1))
        if r is None:
            prow.append([case, "", "> 1200 s", "", "", "", "", "", ""])
            continue
        data[case] = r
        aba, bind = r.get("pin_aba_s"), r.get("pin_binding_s")
        c = r["rhs_c_s"]
        cell = lambda s: f"{s['median'] * 1e6:.2f} µs (min {s['min'] * 1e6:.2f})" if s else "—"
        net = {"median": aba["median"] - bind["median"], "min": aba["min"] - bind["min"]} if aba and bind else None
        prow.append([case, r["n"], _build_cell(r), r["ops"], cell(c), cell(aba), cell(bind), cell(net),
                     f"{c['median'] / net['median']:.2f}×" if net else "—"])
    md += ["", "URDF robots (`tests/data`), q̈ per call beside Pinocchio's ABA in the same run:", "",
           table(["robot", "dof", "cold build (wall)", "ops (M, h)", "amble q̈ (C loop)", "Pinocchio aba (Python loop)",
                  "Pinocchio binding (1-joint aba)", "Pinocchio aba net", "amble / Pinocchio net"], prow)]
    notes = []
    pi = next((r["parser_import_s"] for r in data.values() if "parser_import_s" in r), None)
    if pi is not None:
        notes.append(f"URDF parser import (yourdfpy → trimesh, scipy.spatial), not in the build times: {pi:.2f} s")
    ct = next((r["rhs_ctypes_s"]["median"] - r["rhs_c_s"]["median"] for r in data.values() if r["n"] <= 2), None)
    if ct is not None:
        notes.append(f"ctypes call overhead of `Kernels.rhs` (n = 2 chain, Python loop − C loop): {ct * 1e6:.2f} µs")
    pv = next((r["pin_version"] for r in data.values() if "pin_version" in r), None)
    if pv:
        notes.append(f"Pinocchio {pv}")
    if notes:
        md += ["", "; ".join(notes) + "."]
    goals = []
    for case, target, label in (("chain7", 3.0, "cold build, 7-link spatial chain"),
                                ("biped12", 10.0, "cold build, 12-DOF biped (URDF)"),
                                ("humanoid30", 60.0, "cold build, 30-DOF humanoid (URDF)")):
        r = data.get(case)
        goals.append(Goal(label, f"≤ {target:g} s", _build_cell(r) if r else "not run",
                          (statistics.median(r["builds"]) <= target) if r else None))
    for case in robots:
        r = data.get(case)
        if r and r.get("pin_aba_s"):
            net = r["pin_aba_s"]["median"] - r["pin_binding_s"]["median"]
            goals.append(Goal(f"q̈ per call ≤ Pinocchio aba (net of binding), {case}", "≤ 1×",
                              f"{r['rhs_c_s']['median'] / net:.2f}×", r["rhs_c_s"]["median"] <= net))
    return Section("Rigid-body trees", "\n".join(md), goals, data)


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--worker")
    ap.add_argument("--quick", action="store_true")
    a = ap.parse_args(argv)
    if a.worker:
        worker(a.worker)
        return
    s = run(quick=a.quick)
    print(s.markdown)


if __name__ == "__main__":
    main(sys.argv[1:])
