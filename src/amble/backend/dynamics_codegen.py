"""C code of a mode's equations of motion: ``mh_k`` (the lower triangle of ``M``, ``h`` and ``Γ``),
``rhs_k`` (``q̈`` by an unrolled LDLᵀ solve, or the KKT system of holonomic constraints in
``accel_k``), ``constraint_forces_k`` and ``dynamics_k``, and the statements of a rigid-body
tree's named intermediate quantities.

Apart from :mod:`amble.backend.codegen`, which assembles the translation unit: this is the
largest part of most units and of their compile time, and the choices made here (what is inlined,
what goes into a unit of its own, the elimination order) are about the right-hand side alone.
"""

from __future__ import annotations

from typing import Any

import sympy as sp

from ..derivation.holonomic import Holonomic
from .codegen_support import Printer as _Printer
from .codegen_support import block as _block
from .codegen_support import count_ops
from .hoist import Hoister
from .ldl import UNROLL_MAX, constant_pivots, ldl_order, ldl_solve_code
from .trig import pythagoras
from .units import UNIT_BEGIN, UNIT_END

#: Largest ``mh_k`` (operations of M, h, Γ) that is forced inline into ``rhs_k`` and ``dynamics_k``.
INLINE_OPS = 400


def _dynamics_code(k: int, n: int, M: sp.Matrix, h: sp.Matrix, Gamma: sp.Matrix, nm: dict[sp.Symbol, str],
                   prelude: str, hoist: Hoister, prelude_ops: int = 0, hol: Holonomic | None = None,
                   shared: bool = False) -> str:
    """``mh_k`` (the lower triangle of M, h and Γ — emitted once: for a large tree it is most of
    the unit and of the compile time), and the two kernels that use it: ``rhs_k`` (q̈ = M⁻¹ (Γ − h)
    by an LDLᵀ solve) and ``dynamics_k`` (full M, h, Γ for analysis and display). Parameter-only
    subexpressions are read from the prelude (``hoist``), and so are the pivots and multipliers of
    a leading block of M that depends on parameters only (the compass gait's M₀₀). A mode with
    holonomic constraints (``hol``) solves its KKT system instead (:func:`_holonomic_code`)."""
    tg = [f"M[{i * n + j}]" for i in range(n) for j in range(i + 1)] + [f"h[{i}]" for i in range(n)]
    tg += [f"G[{i}]" for i in range(n)]
    ex = [M[i, j] for i in range(n) for j in range(i + 1)] + list(h) + list(Gamma)
    ex = pythagoras(ex)  # a·sin²u + a·cos²u = a: Lagrangian mass matrices are full of it
    # common factors out of sums, m·l·(cos a cos b + sin a sin b) instead of m·(l cos a cos b + l sin a
    # sin b): the parameter part becomes one hoisted value (compass gait: −2 % instructions per walk);
    # small models only, where M and h are inlined into the right-hand side and factoring is cheap
    if count_ops(ex) <= INLINE_OPS:
        ex = [sp.factor_terms(e) for e in ex]
    low = lambda i, j: ex[max(i, j) * (max(i, j) + 1) // 2 + min(i, j)]  # M[i, j] of the lower triangle
    nonzero = {(i, j) for i in range(n) for j in range(i) if low(i, j) != 0}
    if not hoist.enabled:  # the code of before (benchmarks): a dense solve in the natural order
        nonzero = {(i, j) for i in range(n) for j in range(i)}
    order = ldl_order(n, nonzero) if n <= UNROLL_MAX else list(range(n))
    known = constant_pivots(sp.Matrix(n, n, lambda i, j: low(order[i], order[j])), nm, hoist)
    ex = hoist(ex)
    # small kernels are inlined into both callers (a call costs as much as their body); large ones
    # are compiled once, in a unit of their own compiled beside the rest (units.split_units). A
    # tree's M and h are names (its size is in the prelude): inlined into rhs_k, its q̈ is faster
    # (the humanoid's 10.8 µs against 14.3 µs out of line), so rhs_k keeps an inlined copy and
    # dynamics_k calls one in its own unit (both copies in one unit: 22 s of gcc instead of 11)
    ops = count_ops(ex)
    sig = "(double t, const double *x, const double *p, double *M, double *h, double *G)"
    body = "    (void)t; (void)x; (void)p;\n" + _block(tg, ex, {**nm, **hoist.names}, prelude=prelude) + "}\n"
    inlined, own = f"static AMBLE_INLINE void mh_{k}{sig} {{\n" + body, f"AMBLE_HIDDEN void mh_{k}_out{sig} {{\n" + body
    if prelude_ops + ops <= INLINE_OPS:
        out, dyn = [inlined], f"mh_{k}"
    elif ops <= INLINE_OPS:
        out, dyn = [inlined, UNIT_BEGIN, own, UNIT_END], f"mh_{k}_out"
    else:
        out, dyn = [UNIT_BEGIN, own, UNIT_END], f"mh_{k}_out"
    rhs_mh = f"mh_{k}" if out[0] is inlined else dyn
    if hol is not None:
        out.append(_holonomic_code(k, n, rhs_mh, hol, nm, hoist, shared))
    else:
        out += [f"static int rhs_{k}(double t, const double *x, const double *p, double *dx) {{\n",
                f"    double M[{n * n}], h[{n}], f[{n}];\n",
                f"    {rhs_mh}(t, x, p, M, h, f);\n",
                f"    for (int i = 0; i < {n}; ++i) f[i] -= h[i];\n",
                ldl_solve_code(n, "M", "f", known=known, order=order, nonzero=nonzero),
                f"    for (int i = 0; i < {n}; ++i) {{ dx[i] = x[{n} + i]; dx[{n} + i] = f[i]; }}\n",
                "    return 0;\n}\n",
                f"static int constraint_forces_{k}(double t, const double *x, const double *p, double *lam) {{\n",
                "    (void)t; (void)x; (void)p; (void)lam;\n    return 0;\n}\n"]
    out += [f"static void dynamics_{k}{sig} {{\n",
            f"    {dyn}(t, x, p, M, h, G);\n",
            f"    for (int i = 0; i < {n}; ++i)\n",
            f"        for (int j = 0; j < i; ++j) M[j * {n} + i] = M[i * {n} + j];\n",
            "}\n"]
    return "".join(out)


def _holonomic_code(k: int, n: int, mh: str, hol: Holonomic, nm: dict[sp.Symbol, str], hoist: Hoister,
                    shared: bool) -> str:
    """``accel_k`` (q̈ and λ of ``M q̈ = Γ − h + Jᵀλ``, ``J q̈ = γ``, by ``amble_holonomic_solve``:
    the Cholesky factor of M, then the m × m system of λ), and the two kernels that use it:
    ``rhs_k`` and ``constraint_forces_k`` (λ, :mod:`amble.derivation.holonomic`)."""
    m = hol.J.rows
    tg = [f"J[{a * n + b}]" for a in range(m) for b in range(n)] + [f"gam[{a}]" for a in range(m)]
    ex = [hol.J[a, b] for a in range(m) for b in range(n)] + list(hol.gamma)
    body = _block(tg, hoist(ex), {**nm, **hoist.names}, shared=shared)
    return "".join([
        f"static int accel_{k}(double t, const double *x, const double *p, double *f, double *lam) {{\n",
        f"    double M[{n * n}], h[{n}], J[{m * n}], gam[{m}];\n",
        f"    {mh}(t, x, p, M, h, f);\n",
        f"    for (int i = 0; i < {n}; ++i) f[i] -= h[i];\n",
        body,
        f"    return amble_holonomic_solve({n}, {m}, M, J, gam, f, lam);\n}}\n",
        f"static int rhs_{k}(double t, const double *x, const double *p, double *dx) {{\n",
        f"    double f[{n}], lam[{m}];\n",
        f"    const int err = accel_{k}(t, x, p, f, lam);\n    if (err) return err;\n",
        f"    for (int i = 0; i < {n}; ++i) {{ dx[i] = x[{n} + i]; dx[{n} + i] = f[i]; }}\n",
        "    return 0;\n}\n",
        f"static int constraint_forces_{k}(double t, const double *x, const double *p, double *lam) {{\n",
        f"    double f[{n}];\n    return accel_{k}(t, x, p, f, lam);\n}}\n"])


def _defs_code(defs: Any, nm: dict[sp.Symbol, str], hoist: Hoister) -> str:
    """Statements of a rigid-body tree's named intermediate quantities (``k_i``), hoisted."""
    rhs = hoist([e for _, e in defs])
    pr = _Printer({**nm, **hoist.names})
    return "\n".join(f"    const double {nm[s]} = {pr.doprint(e)};" for (s, _), e in zip(defs, rhs))
