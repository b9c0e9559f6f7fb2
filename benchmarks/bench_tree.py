"""Rigid-body trees: cold build time, operation count and q̈ per call beside Pinocchio's ABA.

Cases: a spatial chain of n rigid bodies (full inertia tensors, joint axes cycling y, x, z,
written with ``Model.rigid_tree()``), and the URDF robots of ``tests/data`` (12-DOF biped,
30-DOF humanoid) loaded with ``Model.from_urdf``. Each case runs in a fresh interpreter with an
empty ``AMBLE_CACHE_DIR``: build = model + derive + generate + compile (imports not timed).
``ops``: :meth:`amble.Equations.count_ops`. Per-call times are from Python loops over
``Kernels.rhs`` (ctypes) and ``pinocchio.aba`` — both include their binding's overhead, measured
separately with a trivial call of each binding (ctypes: the 1-DOF chain; Pinocchio: ``aba`` of a
1-joint model).

Run alone: ``python -m benchmarks.bench_tree`` (``--quick`` for fewer cases).
"""

from __future__ import annotations

import argparse
import shutil
import sys
import time
from pathlib import Path

from benchmarks.common import Section, child_env, emit_result, fresh_cache_dir, run_worker, table

DATA = Path(__file__).resolve().parents[1] / "tests" / "data"


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


def _per_call(fn, reps: int = 20000) -> float:
    fn()
    t0 = time.perf_counter()
    for _ in range(reps):
        fn()
    return (time.perf_counter() - t0) / reps


def worker(case: str) -> None:
    import numpy as np

    from amble import HybridSystem, Model, derive
    from amble.backend.kernels import build

    t0 = time.perf_counter()
    m = chain(int(case[5:])) if case.startswith("chain") else Model.from_urdf(DATA / f"{case}.urdf")
    k = build(HybridSystem(m.name, m))
    build_s = time.perf_counter() - t0
    n = len(m.q)
    rng = np.random.default_rng(0)
    x = np.concatenate([rng.uniform(-1, 1, n), rng.uniform(-1, 1, n)])
    p = np.zeros(1)
    out = {"case": case, "n": n, "build_s": build_s, "ops": derive(m).count_ops(),
           "rhs_s": _per_call(lambda: k.rhs(0, 0.0, x, p))}
    try:
        import pinocchio as pin
    except ImportError:
        emit_result(out)
        return
    if case.startswith("chain"):  # no URDF for the chain: its Pinocchio time is not measured
        emit_result(out)
        return
    pm = pin.buildModelFromUrdf(str(DATA / f"{case}.urdf"))
    pd = pm.createData()
    q, v, tau = x[:n].copy(), x[n:].copy(), np.zeros(n)
    out["pin_aba_s"] = _per_call(lambda: pin.aba(pm, pd, q, v, tau))
    one = pin.Model()
    one.appendBodyToJoint(one.addJoint(0, pin.JointModelRY(), pin.SE3.Identity(), "j"),
                          pin.Inertia.Random(), pin.SE3.Identity())
    od = one.createData()
    z1 = np.zeros(1)
    out["pin_binding_s"] = _per_call(lambda: pin.aba(one, od, z1, z1, z1))
    emit_result(out)


def run(quick: bool = False) -> Section:
    cases = ["chain1", "chain2", "chain7", "biped12"] if quick else \
        ["chain1", "chain2", "chain4", "chain7", "chain12", "chain20", "biped12", "humanoid30"]
    rows, data = [], {}
    for case in cases:
        cache = fresh_cache_dir()
        try:
            r = run_worker("benchmarks.bench_tree", ["--worker", case], child_env(cache), timeout_s=900)
        finally:
            shutil.rmtree(cache, ignore_errors=True)
        if r is None:
            rows.append([case, "", "> 900 s", "", "", ""])
            continue
        data[case] = r
        us = lambda s: f"{s * 1e6:.2f} µs" if s is not None else "—"
        rows.append([case, r["n"], f"{r['build_s']:.1f} s", r["ops"], us(r["rhs_s"]), us(r.get("pin_aba_s"))])
    md = table(["case", "dof", "cold build", "ops (M, h)", "q̈ per call (amble, ctypes)",
                "Pinocchio aba per call (Python)"], rows)
    one = data.get("chain1")
    notes = []
    if one:
        notes.append(f"ctypes call overhead (1-DOF chain q̈): {one['rhs_s'] * 1e6:.2f} µs")
    pb = next((r.get("pin_binding_s") for r in data.values() if r.get("pin_binding_s")), None)
    if pb:
        notes.append(f"Pinocchio binding overhead (1-joint aba): {pb * 1e6:.2f} µs")
    return Section("Rigid-body trees", md + ("\n\n" + "; ".join(notes) + "." if notes else ""), [], data)


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
