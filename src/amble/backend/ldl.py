"""C code of the LDLᵀ solve of a generated right-hand side: ``M q̈ = Γ − h`` for the symmetric
positive definite mass matrix, written out statement by statement for small systems.

No square root, one division per pivot, every index a constant; structural zeros of M (entries
zero whatever the state) are eliminated in a minimum-degree order when that makes fewer factor
entries, and no product with an always-zero factor entry is written; the factor of a leading
block of M that depends on parameters only is computed once per call with the other hoisted
values (:mod:`amble.backend.hoist`).
"""

from __future__ import annotations

import sympy as sp

from .codegen_support import Printer
from .hoist import Hoister

#: Largest system whose LDLᵀ solve is written out statement by statement; larger ones call the
#: loop in ``amble_core.h`` (unrolled code grows as n³/6 and so does its compile time).
UNROLL_MAX = 12


def ldl_order(n: int, nonzero: set[tuple[int, int]]) -> list[int]:
    """Elimination order of an LDLᵀ factorisation with the structural zeros ``nonzero`` (the
    (i, j), i > j, of entries that may be non-zero): greedy minimum degree, kept only if it
    makes fewer factor entries than the natural order (dense matrices keep theirs)."""
    def fill(order: list[int]) -> int:
        adj = {v: {u for (a, b) in nonzero for u in (a, b) if v in (a, b) and u != v} for v in range(n)}
        total = 0
        for i, v in enumerate(order):
            later = adj[v] & set(order[i + 1:])
            total += len(later)
            for u in later:
                adj[u] |= later - {u}
        return total

    adj = {v: {u for (a, b) in nonzero for u in (a, b) if v in (a, b) and u != v} for v in range(n)}
    left, order = set(range(n)), []
    while left:
        v = min(left, key=lambda u: (len(adj[u] & left), u))
        order.append(v)
        left.discard(v)
        nb = adj[v] & left
        for u in nb:
            adj[u] |= nb - {u}
    natural = list(range(n))
    return order if fill(order) < fill(natural) else natural


def ldl_solve_code(n: int, a: str, b: str, indent: str = "    ", known: dict[str, str] | None = None,
                   order: list[int] | None = None, nonzero: set[tuple[int, int]] | None = None) -> str:
    """C statements solving ``a x = b`` in place for a symmetric positive definite ``a`` (row-major
    n × n, lower triangle read and overwritten by the unit lower factor L; ``b`` overwritten by x),
    returning ``AMBLE_ERR_SINGULAR_MASS`` from the enclosing function if a pivot is not positive or
    the pivots spread by more than 1e14 (the same test as ``amble_ldl_solve``: cond(A) is at least
    max D / min D). LDLᵀ needs no square root; up to :data:`UNROLL_MAX` the loops are unrolled so
    every index is a constant.

    ``order``: the elimination order (:func:`ldl_order`; default natural) and ``nonzero``: the
    structural non-zeros (i, j), i > j, of ``a`` (default all) — products with entries of L that
    are zero whatever the state are not written. ``known``: C expressions, in elimination order,
    of pivots ``d{j}``, their reciprocals ``r{j}``, ``u{i}_{j}`` = L_ij d_j and factor entries
    ``L{i}_{j}`` computed elsewhere (the hoisted factor of a parameter-only leading block,
    :func:`constant_pivots`)."""
    if n > UNROLL_MAX:
        return f"{indent}if (amble_ldl_solve({n}, {a}, {b})) return AMBLE_ERR_SINGULAR_MASS;\n"
    kn = known or {}
    P = order or list(range(n))
    # entries of L (elimination order) that may be non-zero: those of a, and their fill-in
    orig = {(max(i, j), min(i, j)) for i, j in nonzero} if nonzero is not None else None
    nz = [[orig is None or (max(P[i], P[j]), min(P[i], P[j])) in orig for j in range(n)] for i in range(n)]
    for j in range(n):
        for i in range(j + 1, n):
            nz[i][j] = nz[i][j] or any(nz[i][k] and nz[j][k] for k in range(j))

    def A(i: int, j: int) -> str:  # a read of the lower triangle, in elimination order
        r, c = max(P[i], P[j]), min(P[i], P[j])
        return f"{a}[{r * n + c}]"

    B = lambda i: f"{b}[{P[i]}]"
    L: list[str] = []
    w = L.append
    w(f"{indent}{{\n")
    ind = indent + "    "
    for j in range(n):
        ks = [k for k in range(j) if nz[j][k]]
        # u_k = L[j,k] D_k (k < j) are reused by every row below j
        for k in ks:
            w(f"{ind}const double u{j}_{k} = {kn.get(f'u{j}_{k}', f'{A(j, k)} * d{k}')};")
        s = " - ".join([A(j, j)] + [f"{A(j, k)} * u{j}_{k}" for k in ks])
        w(f"{ind}const double d{j} = {kn.get(f'd{j}', s)};")
        if f"d{j}" not in kn:  # a hoisted pivot is tested too, below, with the spread
            w(f"{ind}if (!(d{j} > 0.0)) return AMBLE_ERR_SINGULAR_MASS;")
        w(f"{ind}const double r{j} = {kn.get(f'r{j}', f'1.0 / d{j}')};")  # one division per pivot, none in the solve
        for i in range(j + 1, n):
            if not nz[i][j]:
                continue
            if f"L{i}_{j}" in kn:
                w(f"{ind}{A(i, j)} = {kn[f'L{i}_{j}']};")
                continue
            s = " - ".join([A(i, j)] + [f"{A(i, k)} * u{j}_{k}" for k in ks if nz[i][k]])
            w(f"{ind}{A(i, j)} = ({s}) * r{j};")
    hoisted = [j for j in range(n) if f"d{j}" in kn]
    if hoisted:
        w(f"{ind}if (!({' && '.join(f'd{j} > 0.0' for j in hoisted)})) return AMBLE_ERR_SINGULAR_MASS;")
    if n > 1:
        w(f"{ind}double dmin = d0, dmax = d0;")
        for j in range(1, n):
            # comparisons, not fmin/fmax: those are library calls at -O2 (NaN rules)
            w(f"{ind}if (d{j} < dmin) dmin = d{j};")
            w(f"{ind}if (d{j} > dmax) dmax = d{j};")
        w(f"{ind}if (dmax > 1e14 * dmin) return AMBLE_ERR_SINGULAR_MASS;")
    for i in range(1, n):  # L y = b
        terms = [f"{A(i, k)} * {B(k)}" for k in range(i) if nz[i][k]]
        if terms:
            w(f"{ind}{B(i)} -= " + " + ".join(terms) + ";")
    for i in range(n):  # D z = y
        w(f"{ind}{B(i)} *= r{i};")
    for i in range(n - 2, -1, -1):  # Lᵀ x = z
        terms = [f"{A(k, i)} * {B(k)}" for k in range(i + 1, n) if nz[k][i]]
        if terms:
            w(f"{ind}{B(i)} -= " + " + ".join(terms) + ";")
    w(f"{indent}}}")
    return "\n".join(L) + "\n"


#: Largest leading block of M whose LDLᵀ factor is computed symbolically and hoisted.
CONSTANT_BLOCK_MAX = 4


def constant_pivots(M: sp.Matrix, nm: dict[sp.Symbol, str], hoist: Hoister) -> dict[str, str]:
    """C reads of the hoisted LDLᵀ quantities of the leading block of ``M`` (lower triangle used)
    that depends on parameters only: ``d{j}``, ``r{j}`` = 1/d_j, ``u{i}_{j}`` = L_ij d_j and
    ``L{i}_{j}`` for rows and columns inside the block. Empty if M₀₀ depends on the state."""
    if not hoist.enabled:
        return {}
    params = set(hoist.params)
    kc = 0
    while kc < min(M.shape[0], CONSTANT_BLOCK_MAX) and all(
            M[kc, j].free_symbols <= params for j in range(kc + 1)):
        kc += 1
    if kc == 0:
        return {}
    d: list[sp.Expr] = []
    L: dict[tuple[int, int], sp.Expr] = {}
    u: dict[tuple[int, int], sp.Expr] = {}
    out: dict[str, sp.Expr] = {}
    for j in range(kc):
        dj = M[j, j] - sum((L[j, q] * L[j, q] * d[q] for q in range(j)), sp.Integer(0))
        if dj == 0 or dj.has(sp.zoo, sp.nan, sp.oo):
            break  # structurally singular: left to the run-time factorisation, which reports it
        for q in range(j):
            u[j, q] = L[j, q] * d[q]
            out[f"u{j}_{q}"] = u[j, q]
        d.append(dj)
        out[f"d{j}"], out[f"r{j}"] = d[j], 1 / d[j]
        for i in range(j + 1, kc):
            L[i, j] = (M[i, j] - sum((L[i, q] * u[j, q] for q in range(j)), sp.Integer(0))) / d[j]
    # factor entries only for rows whose pivot is hoisted too (rows below are factored at run time)
    out.update({f"L{i}_{j}": e for (i, j), e in L.items() if i < len(d)})
    hoisted = {key: hoist.one(e) for key, e in out.items()}
    pr = Printer({**nm, **hoist.names})
    return {key: pr.doprint(h) for key, h in hoisted.items()}
