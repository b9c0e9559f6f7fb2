"""Derive + compile cost of an n-link planar pendulum chain: amble beside SymPy's ``LagrangesMethod``.

The chain: point mass ``m_i`` at the end of massless link ``i`` of length ``l_i``; absolute angles
``q_i`` measured from the downward vertical (positive counter-clockwise seen with x right, z up);
gravity ``g`` along −z. Masses, lengths and ``g`` are run-time parameters on both sides.

amble side, in a fresh interpreter with a fresh ``AMBLE_CACHE_DIR`` (a cold cache: no model
compiled, the shared runtime seeded — :mod:`benchmarks.runtime_seed`; its one-time compile is a
row of its own):
``amble`` and its code generator are imported first (not timed, as the peer imports SymPy before
its clock starts); then the Model is written, wrapped in a :class:`amble.HybridSystem` with no
transitions and built with :func:`amble.backend.kernels.compiled` — which runs :func:`amble.derive`, generates
the C source and compiles it into a shared library. The total is that whole sequence; the
breakdown (derive / code generation / C compile) comes from timing wrappers put around the three
internal calls. ``ops`` is :meth:`amble.Equations.count_ops` (M, h, Γ with common subexpressions
shared).

Peer: :mod:`benchmarks.peers.sympy_chain` (``LagrangesMethod`` + ``lambdify(cse=True)``, fresh
process per n, killed after 60 s).

Correctness: for a few n the worker evaluates amble's compiled q̈ at a random state and
compares it with the peer's lambdified equations and with an independent Newton–Euler solve
(:func:`benchmarks.peers.sympy_chain.newton_euler_qdd`).

Run alone: ``python -m benchmarks --only derive``; one worker: ``python -m benchmarks.bench_derive --worker 6``.
"""

from __future__ import annotations

import argparse
import shutil
import time
from collections.abc import Sequence
from typing import Any

from benchmarks.common import (
    Goal,
    Section,
    Stats,
    child_env,
    emit_result,
    ratio,
    run_worker,
    sci,
    sec,
    table,
)
from benchmarks.runtime_seed import SECTION_NOTE, row_text, seeded_cache_dir

#: Chain sizes with a stated goal: n -> seconds (cold derive + codegen + compile).
GOALS: dict[int, float] = {6: 1.0, 20: 10.0}

#: Chains whose compiled q̈ is checked against the peer and Newton–Euler.
CHECK_N: tuple[int, ...] = (2, 3, 5, 8)

#: Sizes tried past n = 20, as long as amble stays under :data:`LIMIT_S`.
BEYOND_N: tuple[int, ...] = (25, 30, 40, 50, 60)

#: Per-n budget (s): the peer is stopped at the first n past it; amble's extension likewise.
LIMIT_S: float = 60.0


def build_chain(n: int) -> Any:
    """The n-link chain as an amble Model (see the module docstring for conventions)."""
    import sympy as sp

    from amble import Model

    model = Model(f"chain{n}")
    q = model.coordinates(" ".join(f"q{i + 1}" for i in range(n)))
    q = list(q) if isinstance(q, (list, tuple)) else [q]
    defaults = {f"m{i + 1}": 1.0 for i in range(n)} | {f"l{i + 1}": 1.0 for i in range(n)} | {"g": 9.81}
    par = model.parameters(**defaults)
    m, l, g = par[:n], par[n:2 * n], par[2 * n]
    model.point("pivot", (0, 0))
    pos = sp.Matrix([0, 0])
    prev = "pivot"
    for i in range(n):
        pos = pos + l[i] * sp.Matrix([sp.sin(q[i]), -sp.cos(q[i])])
        model.point(f"p{i + 1}", pos, mass=m[i], link=prev)
        prev = f"p{i + 1}"
    model.gravity(g)
    return model


def worker(n: int, check: bool) -> dict[str, Any]:
    """Time the cold build of the n-link chain in this (fresh) process; optionally check q̈."""
    import amble
    import amble.backend.cache as cache
    import amble.backend.codegen as codegen
    import amble.backend.kernels as kernels
    import amble.backend.runtime as runtime

    spans: dict[str, float] = {"derive_s": 0.0, "generate_s": 0.0, "compile_s": 0.0}
    captured: list[Any] = []

    def timed(fn: Any, key: str, keep: bool = False) -> Any:
        def wrapper(*args: Any, **kw: Any) -> Any:
            t0 = time.perf_counter()
            out = fn(*args, **kw)
            spans[key] += time.perf_counter() - t0
            if keep:
                captured.append(out)
            return out

        return wrapper

    # Instrument the three stages of a cold build (module globals are looked up at call time).
    codegen.derive = timed(codegen.derive, "derive_s", keep=True)
    codegen.generate = timed(codegen.generate, "generate_s")
    cache._compile = timed(cache._compile, "compile_s")

    t0 = time.perf_counter()
    model = build_chain(n)
    system = amble.HybridSystem(f"chain{n}", {"swing": model})
    t1 = time.perf_counter()
    k = kernels.compiled(system)
    t2 = time.perf_counter()
    eq = captured[0]
    out: dict[str, Any] = {
        "n": n,
        "model_s": t1 - t0,
        "derive_s": spans["derive_s"],
        "codegen_s": spans["generate_s"] - spans["derive_s"],
        "compile_s": spans["compile_s"],
        "build_s": t2 - t1,
        "total_s": t2 - t0,
        "count_ops": eq.count_ops(),
        "runtime_compiles": runtime.COMPILES,  # 0: the seeded runtime was used, as intended
    }
    if check:
        out.update(check_qdd(k, n))
    return out


def check_qdd(k: Any, n: int, seed: int = 0) -> dict[str, float]:
    """Relative q̈ differences: amble vs the peer's lambdified equations and vs Newton–Euler."""
    import numpy as np

    from amble.simulation.simulate import parameter_vector
    from benchmarks.peers import sympy_chain

    rng = np.random.default_rng(seed)
    q = rng.uniform(-np.pi, np.pi, n)
    qd = rng.normal(0.0, 2.0, n)
    m = rng.uniform(0.5, 2.0, n)
    l = rng.uniform(0.5, 1.5, n)
    g = 9.81
    vals = {f"m{i + 1}": m[i] for i in range(n)} | {f"l{i + 1}": l[i] for i in range(n)} | {"g": g}
    p = parameter_vector(k, vals)
    qdd_amble = k.rhs("swing", 0.0, np.concatenate([q, qd]), p)[n:]
    fun = sympy_chain.compile_equations(sympy_chain.derive(n))
    mass, forcing = fun(q, qd, m, l, g)
    qdd_peer = np.linalg.solve(np.asarray(mass, dtype=float), np.asarray(forcing, dtype=float).ravel())
    qdd_ne = sympy_chain.newton_euler_qdd(q, qd, m, l, g)

    def rel(a: Any, b: Any) -> float:
        return float(np.max(np.abs(a - b)) / max(1.0, float(np.max(np.abs(b)))))

    return {"vs_peer_rel": rel(qdd_amble, qdd_peer), "vs_newton_euler_rel": rel(qdd_amble, qdd_ne)}


def amble_once(n: int, check: bool = False, timeout_s: float = 180.0) -> dict[str, Any] | None:
    """One cold build of the n-chain in a fresh process with a fresh cache dir (no model in it; the
    shared runtime seeded: :mod:`benchmarks.runtime_seed`)."""
    cache = seeded_cache_dir()
    try:
        args = [str(n)] + (["--check"] if check else [])
        return run_worker("benchmarks.bench_derive", ["--worker", *args], child_env(cache), timeout_s)
    finally:
        shutil.rmtree(cache, ignore_errors=True)


def run(quick: bool = False) -> Section:
    """Run both sides for n = 2…20 (amble also beyond while under 60 s); return the section."""
    from benchmarks.peers import sympy_chain

    ns = list(range(2, 9)) if quick else list(range(2, 21))
    reps_goal = 1 if quick else 5
    check_n = CHECK_N[:2] if quick else CHECK_N
    amble_res: dict[int, dict[str, Any]] = {}
    amble_stats: dict[int, Stats] = {}
    checks: dict[int, dict[str, float]] = {}

    print("derive: amble (fresh process, cold cache) ...", flush=True)
    beyond = [] if quick else list(BEYOND_N)
    stop_note = ""
    for n in ns + beyond:
        if n > 20 and amble_res:
            last = max(amble_res)
            if amble_stats[last].median > LIMIT_S:
                break
            # cost grows roughly like n³ (ops ~ n³ from the chain's coupling); skip hopeless sizes
            guess = amble_stats[last].median * (n / last) ** 3
            if guess > 1.5 * LIMIT_S:
                stop_note = (f"amble not run for n = {n}: extrapolated from n = {last} to ≈ {guess:.0f} s "
                             f"(> {LIMIT_S:.0f} s).")
                print(f"  {stop_note}", flush=True)
                break
        reps = reps_goal if n in GOALS else 1
        samples = []
        for r in range(reps):
            res = amble_once(n, check=(n in check_n and r == 0), timeout_s=LIMIT_S * 1.5 if n > 20 else 180.0)
            if res is None:
                break
            samples.append(res)
        if not samples:
            stop_note = f"amble n = {n} stopped after {LIMIT_S * 1.5:.0f} s."
            print(f"  {stop_note}", flush=True)
            break
        if any(s.get("runtime_compiles") for s in samples):
            raise RuntimeError(f"n = {n}: a cold build compiled the runtime: no seeded object matched "
                               "its key and capacity")
        amble_stats[n] = Stats.of([s["total_s"] for s in samples])
        # report the breakdown of the median run
        amble_res[n] = sorted(samples, key=lambda s: s["total_s"])[len(samples) // 2]
        if "vs_peer_rel" in samples[0]:
            checks[n] = {k: samples[0][k] for k in ("vs_peer_rel", "vs_newton_euler_rel")}
        print(f"  n={n:>2}: {amble_stats[n].median:.3f} s (min {amble_stats[n].min:.3f}, {len(samples)} run(s)), "
              f"ops {amble_res[n]['count_ops']}", flush=True)

    print("derive: peer sympy LagrangesMethod + lambdify(cse=True) ...", flush=True)
    peer: dict[int, dict[str, Any] | None] = {}
    peer_limit = 30.0 if quick else LIMIT_S
    for n in ns:
        res = sympy_chain.run_with_timeout(n, timeout_s=peer_limit)
        peer[n] = res
        if res is None:
            print(f"  n={n:>2}: killed after {peer_limit:.0f} s; stopping the peer", flush=True)
            break
        print(f"  n={n:>2}: {res['total_s']:.3f} s, ops(cse) {res['count_ops_cse']}", flush=True)
        if res["total_s"] > peer_limit:
            break

    rows = []
    for n in sorted(amble_res):
        a, st = amble_res[n], amble_stats[n]
        p = peer.get(n)
        if n in peer and p is None:
            p_cells = [f"> {peer_limit:.0f} (killed)", "", "", "", f"> {peer_limit / st.median:.0f}×"]
        elif p is None:
            p_cells = ["— (peer stopped)"] + [""] * 4
        else:
            p_cells = [sec(p["total_s"]), sec(p["derive_s"]), sec(p["compile_s"]), str(p["count_ops_cse"]),
                       ratio(p["total_s"], st.median)]
        total = sec(st.median) + (f" (min {sec(st.min)}, {st.n} runs)" if st.n > 1 else "")
        rows.append([str(n), total, sec(a["derive_s"]), sec(a["codegen_s"]), sec(a["compile_s"]),
                     str(a["count_ops"]), *p_cells])
    caps = tuple(sorted({8, 16} if max(amble_res, default=2) <= 8 else {8, 16, 32, 64}))
    rows.append(["runtime, once per machine", "", "", "", row_text(caps), "", "", "", "", "", ""])
    header = ["n", "amble total s", "derive", "codegen", "C compile", "amble ops (CSE)",
              "SymPy total s", "SymPy derive", "lambdify", "SymPy ops (CSE)", "SymPy / amble"]
    reps_note = (f"n = 6 and 20: median of {reps_goal} fresh processes (min in brackets); other n: one run. "
                 if reps_goal > 1 else "One run per n (quick mode). ")
    md = [
        "Cold derive + code generation + C compile of an n-link planar pendulum chain (point masses at "
        "the link ends, absolute angles, all masses/lengths/g as run-time parameters). Each amble run is "
        "a fresh Python process with a fresh `AMBLE_CACHE_DIR`. " + SECTION_NOTE + " *total* = writing the Model + "
        "`amble.backend.kernels.compiled` (derive, codegen, compile with the default flags of the machine table, "
        "load), imports excluded on both sides. "
        + reps_note
        + "SymPy peer: `LagrangesMethod` + `lambdify(cse=True)` in a fresh process per n, one run each, "
        f"stopped at the first n past {peer_limit:.0f} s. Ops: arithmetic operations with common "
        "subexpressions shared (amble: M, h, Γ; SymPy: mass matrix and forcing).",
        "",
        table(header, rows),
    ]
    if stop_note:
        md += ["", stop_note]
    if checks:
        check_rows = [[str(n), sci(c["vs_peer_rel"]), sci(c["vs_newton_euler_rel"])] for n, c in sorted(checks.items())]
        md += ["", "Correctness of the compiled q̈ at a random state (max |Δq̈| / max(1, max |q̈|)):", "",
               table(["n", "amble vs SymPy peer", "amble vs Newton–Euler"], check_rows)]
    goals = []
    for n, lim in GOALS.items():
        st = amble_stats.get(n)
        goals.append(Goal(f"derive + compile, n = {n} (cold)", f"≤ {lim:g} s",
                          "not run" if st is None else f"{st.median:.2f} s (min {st.min:.2f})",
                          None if st is None else st.median <= lim))
    if checks:
        worst = max(max(c.values()) for c in checks.values())
        goals.append(Goal("compiled q̈ = peer's and Newton–Euler's", "rel. diff ≤ 1e-10", sci(worst), worst <= 1e-10))
    data = {"amble": amble_res, "amble_stats": {n: vars(s) for n, s in amble_stats.items()}, "peer": peer,
            "checks": checks}
    return Section("Derivation: n-link pendulum chain", "\n".join(md), goals, data)


def main(argv: Sequence[str] | None = None) -> None:
    """Worker entry point (the suite runs ``python -m benchmarks.bench_derive --worker N``)."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--worker", type=int, required=True, help="chain size n to build in this process")
    ap.add_argument("--check", action="store_true", help="also check the compiled q̈")
    args = ap.parse_args(argv)
    emit_result(worker(args.worker, args.check))


if __name__ == "__main__":
    main()
