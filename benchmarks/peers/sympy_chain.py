"""Symbolic derivation cost of an n-link planar pendulum with ``sympy.physics.mechanics``.

The chain: point mass ``m_i`` at the end of each massless link of length
``l_i``; absolute angles ``q_i`` measured from the downward vertical; gravity
``g``.  Masses, lengths and ``g`` stay symbolic.  The equations of motion
``M(q) qdd = forcing(q, qd)`` are formed with ``LagrangesMethod`` and compiled
with ``sympy.lambdify(..., cse=True)``.

Each ``n`` is measured in a fresh interpreter (:func:`run_with_timeout`) so
SymPy's caches from smaller chains do not help larger ones, and a run that
exceeds the time budget is killed.

Run ``python -m benchmarks.peers.sympy_chain [--max-n N]`` for a small table.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import sympy as sp
from sympy.physics.mechanics import (
    LagrangesMethod,
    Lagrangian,
    Particle,
    Point,
    ReferenceFrame,
    dynamicsymbols,
)

#: Repository root (``benchmarks/peers/sympy_chain.py`` -> root).
REPO_ROOT: Path = Path(__file__).resolve().parents[2]

#: Marker that precedes the JSON result printed by a worker process.
_RESULT_TAG = "SYMPY_CHAIN_RESULT "


def derive(n: int) -> dict[str, Any]:
    """Form the chain's Lagrange equations symbolically.

    Returns ``q``, ``qd`` (dynamicsymbols), ``m``, ``l`` (symbol tuples), ``g``,
    ``mass_matrix`` (``n x n``) and ``forcing`` (``n x 1``), with
    ``mass_matrix * qdd = forcing``.
    """
    q = dynamicsymbols(f"q1:{n + 1}")
    qd = dynamicsymbols(f"q1:{n + 1}", 1)
    m = sp.symbols(f"m1:{n + 1}")
    l = sp.symbols(f"l1:{n + 1}")
    g = sp.Symbol("g")
    frame = ReferenceFrame("N")
    origin = Point("O")
    origin.set_vel(frame, 0)
    prev = origin
    particles = []
    for i in range(n):
        p = prev.locatenew(f"P{i + 1}", l[i] * (sp.sin(q[i]) * frame.x - sp.cos(q[i]) * frame.y))
        p.set_vel(frame, p.pos_from(origin).dt(frame))
        particle = Particle(f"pa{i + 1}", p, m[i])
        particle.potential_energy = m[i] * g * p.pos_from(origin).dot(frame.y)
        particles.append(particle)
        prev = p
    lagrangian = Lagrangian(frame, *particles)
    lm = LagrangesMethod(lagrangian, q)
    lm.form_lagranges_equations()
    return {
        "q": q,
        "qd": qd,
        "m": m,
        "l": l,
        "g": g,
        "mass_matrix": lm.mass_matrix,
        "forcing": lm.forcing,
    }


def compile_equations(sym: dict[str, Any]) -> Callable[..., list[np.ndarray]]:
    """``lambdify`` mass matrix and forcing together with ``cse=True``.

    The returned function is ``f(q, qd, m, l, g) -> [M, forcing]``.
    """
    args = (sym["q"], sym["qd"], sym["m"], sym["l"], sym["g"])
    return sp.lambdify(args, [sym["mass_matrix"], sym["forcing"]], modules="numpy", cse=True)


def newton_euler_qdd(
    q: np.ndarray, qd: np.ndarray, m: np.ndarray, l: np.ndarray, g: float
) -> np.ndarray:
    """Joint accelerations of the chain from Newton's law for each point mass.

    Unknowns are ``qdd`` and the link tensions ``T``.  With ``e_k = (sin q_k,
    -cos q_k)`` (link direction) and ``t_k = (cos q_k, sin q_k)``, mass ``i``
    has acceleration ``a_i = sum_{k<=i} l_k (qdd_k t_k - qd_k^2 e_k)`` and
    obeys ``m_i a_i = -T_i e_i + T_{i+1} e_{i+1} - m_i g y_hat`` (``T_{n+1}=0``):
    a ``2n x 2n`` linear system, independent of any Lagrangian.
    """
    n = len(q)
    e = np.stack([np.sin(q), -np.cos(q)], axis=1)
    t = np.stack([np.cos(q), np.sin(q)], axis=1)
    a = np.zeros((2 * n, 2 * n))
    b = np.zeros(2 * n)
    for i in range(n):
        for c in range(2):
            r = 2 * i + c
            for k in range(i + 1):
                a[r, k] = m[i] * l[k] * t[k, c]
                b[r] += m[i] * l[k] * qd[k] ** 2 * e[k, c]
            a[r, n + i] = e[i, c]
            if i + 1 < n:
                a[r, n + i + 1] = -e[i + 1, c]
            b[r] += -m[i] * g if c == 1 else 0.0
    return np.linalg.solve(a, b)[:n]


def check(fun: Callable[..., list[np.ndarray]], n: int, seed: int = 0) -> float:
    """Max relative error of compiled ``qdd`` vs :func:`newton_euler_qdd` at a random state."""
    rng = np.random.default_rng(seed)
    q = rng.uniform(-np.pi, np.pi, n)
    qd = rng.normal(0.0, 2.0, n)
    m = rng.uniform(0.5, 2.0, n)
    l = rng.uniform(0.5, 1.5, n)
    g = 9.81
    mass, forcing = fun(q, qd, m, l, g)
    qdd = np.linalg.solve(np.asarray(mass, dtype=float), np.asarray(forcing, dtype=float).ravel())
    ref = newton_euler_qdd(q, qd, m, l, g)
    return float(np.max(np.abs(qdd - ref)) / max(1.0, float(np.max(np.abs(ref)))))


def derive_and_compile(n: int) -> dict[str, Any]:
    """Derive and compile the n-link chain in this process, with timings.

    Returns a dict with keys ``n``, ``derive_s`` (frames/points/particles through
    ``form_lagranges_equations`` and ``mass_matrix``/``forcing``), ``compile_s``
    (``lambdify(..., cse=True)``), ``total_s`` (derive + compile), ``count_ops``
    (``count_ops(M) + count_ops(forcing)``), ``count_ops_cse`` (ops of the
    ``sympy.cse`` replacements + reduced expressions), ``cse_subexpressions``,
    ``qdd_check_rel_err`` (vs Newton's law at a random state) and
    ``sympy_version``.
    """
    t0 = time.perf_counter()
    sym = derive(n)
    t1 = time.perf_counter()
    fun = compile_equations(sym)
    t2 = time.perf_counter()
    mass, forcing = sym["mass_matrix"], sym["forcing"]
    ops = int(sp.count_ops(mass) + sp.count_ops(forcing))
    replacements, reduced = sp.cse([mass, forcing])
    ops_cse = int(
        sum(sp.count_ops(rhs) for _, rhs in replacements)
        + sum(sp.count_ops(expr) for expr in reduced)
    )
    return {
        "n": n,
        "derive_s": t1 - t0,
        "compile_s": t2 - t1,
        "total_s": t2 - t0,
        "count_ops": ops,
        "count_ops_cse": ops_cse,
        "cse_subexpressions": len(replacements),
        "qdd_check_rel_err": check(fun, n),
        "sympy_version": sp.__version__,
    }


def run_with_timeout(n: int, timeout_s: float = 60.0) -> dict[str, Any] | None:
    """Run :func:`derive_and_compile` for ``n`` in a fresh Python process.

    The child is killed once it has run ``timeout_s`` seconds; ``None`` is then
    returned.  Otherwise the child's result dict is returned, with the extra
    key ``process_wall_s`` (wall time of the whole child, interpreter start-up
    and imports included).  A crashing child raises ``RuntimeError``.
    """
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(
        [str(REPO_ROOT)] + ([env["PYTHONPATH"]] if env.get("PYTHONPATH") else [])
    )
    cmd = [sys.executable, "-m", "benchmarks.peers.sympy_chain", "--worker", str(n)]
    t0 = time.perf_counter()
    try:
        proc = subprocess.run(
            cmd, cwd=REPO_ROOT, env=env, capture_output=True, text=True, timeout=timeout_s
        )
    except subprocess.TimeoutExpired:
        return None
    wall = time.perf_counter() - t0
    for line in reversed(proc.stdout.splitlines()):
        if line.startswith(_RESULT_TAG):
            result = json.loads(line[len(_RESULT_TAG) :])
            result["process_wall_s"] = wall
            return result
    raise RuntimeError(
        f"sympy_chain worker for n={n} failed (exit {proc.returncode}):\n{proc.stderr[-2000:]}"
    )


def main(argv: Sequence[str] | None = None) -> None:
    """Print derive/compile times for n = 2..max_n (stop at the first timeout)."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--max-n", type=int, default=10, help="largest chain (default 10)")
    ap.add_argument("--min-n", type=int, default=2, help="smallest chain (default 2)")
    ap.add_argument("--timeout", type=float, default=60.0, help="seconds per n (default 60)")
    ap.add_argument("--worker", type=int, default=None, help=argparse.SUPPRESS)
    args = ap.parse_args(argv)

    if args.worker is not None:
        print(_RESULT_TAG + json.dumps(derive_and_compile(args.worker)), flush=True)
        return

    print(f"sympy {sp.__version__}: LagrangesMethod + lambdify(cse=True), fresh process per n")
    print(
        f"{'n':>3} {'derive s':>9} {'compile s':>9} {'total s':>8} "
        f"{'ops':>8} {'ops(cse)':>9} {'qdd err':>9}"
    )
    for n in range(args.min_n, args.max_n + 1):
        res = run_with_timeout(n, args.timeout)
        if res is None:
            print(f"{n:>3}  timed out after {args.timeout:.0f} s; stopping")
            break
        print(
            f"{n:>3} {res['derive_s']:>9.3f} {res['compile_s']:>9.3f} {res['total_s']:>8.3f} "
            f"{res['count_ops']:>8d} {res['count_ops_cse']:>9d} "
            f"{res['qdd_check_rel_err']:>9.1e}"
        )


if __name__ == "__main__":
    main()
