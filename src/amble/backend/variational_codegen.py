"""C code of the derivatives a sensitivity run needs, by forward-mode differentiation of the
generated programs (:mod:`amble.backend.tangents`):

* per mode, ``rhs_tan_k(t, x, p, S, dx, KS)``: the right-hand side and ``KS = (∂f/∂x) S + ∂f/∂p``
  for a sensitivity matrix ``S``. With ``x = (q, q̇)`` and ``M q̈ = F = Γ − h``, the tangent of
  the acceleration solves ``M q̈' = F' − M' q̈`` with the factor of ``M`` already at hand, so
  ``M⁻¹`` is never formed;
* per mode, ``surfaces_grad_k(t, x, p, G)``: ``∂s/∂(x, p)`` of its guards then switching surfaces;
* per transition, ``reset_jac_i(t, x, p, D)``: ``∂Δ/∂(x, p, t)`` of its reset. An impulsive reset
  (Impact, Lock) solves ``Mₑ v⁺ − Jᵀλ = Mₑ v⁻, J v⁺ = 0``; its tangent solves the same KKT
  system with the right-hand side ``(Mₑ' (v⁻ − v⁺) + J'ᵀλ + Mₑ v⁻', −J' v⁺)``, and the
  relabelled state ``(q_new(q), T(q) v⁺)`` follows by the chain rule.

Layout shared with ``_c/sensitivity.h``: a sensitivity row has ``SC = NXMAX + NPARAM`` columns,
state columns ``0 … nx−1`` and parameter ``j`` at ``NXMAX + j``; a reset Jacobian row has one
more, ``∂/∂t`` at column ``SC``.
"""

from __future__ import annotations

from dataclasses import replace

import sympy as sp

from ..derivation.impact import impulse_data
from ..modelling.hybrid import target_exprs
from ..modelling.model import Model, t
from .codegen_support import ModeInfo, symbol_names
from .tangents import jacobian_block


def _param_symbols(model: Model, params: list[str]) -> list[sp.Symbol]:
    """The mode's symbol of each system parameter (None where the mode lacks it)."""
    own = {str(s): s for s in model.params}
    return [own.get(name) for name in params]


def _inputs(model: Model, params: list[str], with_time: bool) -> tuple[list[sp.Symbol], list[str]]:
    """Differentiation variables (state, parameters, optionally time) and their C columns."""
    nx = 2 * len(model.q)
    psyms = _param_symbols(model, params)
    inputs = [*model.q, *model.qd, *[s if s is not None else sp.Dummy() for s in psyms]]
    cols = [str(i) for i in range(nx)] + [f"NXMAX + {j}" for j in range(len(params))]
    if with_time:
        inputs.append(t)
        cols.append("SC")
    return inputs, cols


def _defs(mi: ModeInfo) -> tuple[list, sp.Matrix, sp.Matrix]:
    eq = mi.equations
    return eq.compact if eq.compact is not None else ([], eq.M, eq.h)


def _flow_jacobian_code(mi: ModeInfo, names: dict[sp.Symbol, str], params: list[str], of_params: bool) -> str:
    """The flow Jacobian's acceleration rows with respect to the state (``rhs_jac_k``: also the
    right-hand side, and the position rows) or to the parameters (``rhs_jacp_k``). Two kernels,
    because a fixed-point search needs only the first and parameters touch most of the program."""
    m, eq, k = mi.model, mi.equations, mi.index
    n = len(m.q)
    defs, M, h = _defs(mi)
    hol = eq.holonomic
    if of_params:
        inputs = [s if s is not None else sp.Dummy() for s in _param_symbols(m, params)]
        col = "NXMAX + v"
    else:
        inputs = [*m.q, *m.qd]
        col = "v"
    nv = max(len(inputs), 1)
    low = [(i, j) for i in range(n) for j in range(i + 1)]
    exprs = [M[i, j] for i, j in low] + [eq.closed_loop_force[i] - h[i] for i in range(n)]
    vt = [f"M[{i * n + j}]" for i, j in low] + [f"f[{i}]" for i in range(n)]
    rows = [("dM", i * n + j) for i, j in low] + [("dF", i) for i in range(n)]
    if hol is not None:  # J and γ of the constraints, and their tangents
        mc = hol.J.rows
        exprs += [hol.J[a, b] for a in range(mc) for b in range(n)] + list(hol.gamma)
        vt += [f"Jh[{a * n + b}]" for a in range(mc) for b in range(n)] + [f"gam[{a}]" for a in range(mc)]
        rows += [("dJ", a * n + b) for a in range(mc) for b in range(n)] + [("dG", a) for a in range(mc)]

    def target(o: int, v: int) -> str:
        return f"{rows[o][0]}[{rows[o][1] * nv + v}]"

    if of_params:
        code = f"static int rhs_jacp_{k}(double t, const double *x, const double *p, double *J) {{\n"
    else:
        code = f"static int rhs_jac_{k}(double t, const double *x, const double *p, double *dx, double *J) {{\n"
    code += f"    double M[{n * n}], f[{n}], dM[{n * n * nv}], dF[{n * nv}];\n    (void)t; (void)p;\n"
    code += "    memset(dM, 0, sizeof dM);\n    memset(dF, 0, sizeof dF);\n"
    if hol is not None:
        code += (f"    double Jh[{mc * n}], gam[{mc}], lam[{mc}], dJ[{mc * n * nv}], dG[{mc * nv}];\n"
                 "    memset(dJ, 0, sizeof dJ);\n    memset(dG, 0, sizeof dG);\n")
    code += jacobian_block(exprs, vt, target, inputs, names, defs=defs)
    code += _acceleration_tangent_code(n, len(inputs), nv, None if hol is None else mc)
    code += f"    for (int i = 0; i < {n}; ++i) {{\n"
    if of_params:
        code += (f"        for (int v = 0; v < {len(inputs)}; ++v) {{\n"
                 f"            J[i * SC + {col}] = 0.0;\n"
                 f"            J[({n} + i) * SC + {col}] = dF[i * {nv} + v];\n        }}\n")
    else:
        code += f"        dx[i] = x[{n} + i];\n        dx[{n} + i] = f[i];\n"
        code += (f"        for (int v = 0; v < {2 * n}; ++v) {{\n"
                 f"            J[i * SC + v] = v == {n} + i;\n"
                 f"            J[({n} + i) * SC + v] = dF[i * {nv} + v];\n        }}\n")
    code += "    }\n    return 0;\n}\n"
    return code


def _acceleration_tangent_code(n: int, ni: int, nv: int, mc: int | None) -> str:
    """C statements leaving ``f = q̈`` and ``dF`` = its tangents (``ni`` directions, ``nv`` columns)
    from ``M``, ``f = F``, ``dM``, ``dF``: ``M q̈' = F' − M' q̈``, solved with the factor of ``M``
    (``M⁻¹`` is never formed). With ``mc`` holonomic constraints (``Jh``, ``gam``, ``dJ``, ``dG``)
    the constrained system ``M q̈ = F + Jᵀλ``, ``J q̈ = γ`` and its tangent
    ``M q̈' = F' − M' q̈ + J'ᵀλ + Jᵀλ'``, ``J q̈' = γ' − J' q̈`` (``amble_holonomic_tangent``)."""
    if mc is None:
        code = f"    if (amble_chol_factor({n}, M)) return AMBLE_ERR_SINGULAR_MASS;\n"
        code += f"    amble_chol_apply({n}, M, f, 1);\n"
    else:
        code = f"    int err = amble_holonomic_solve({n}, {mc}, M, Jh, gam, f, lam);\n    if (err) return err;\n"
    # ∂q̈ = M⁻¹ (∂F − ∂M q̈), ∂M symmetric (its lower triangle was differentiated)
    code += f"    for (int i = 0; i < {n}; ++i)\n        for (int v = 0; v < {ni}; ++v) {{\n"
    code += f"            double r = dF[i * {nv} + v];\n"
    code += (f"            for (int l = 0; l < {n}; ++l)\n"
             f"                r -= dM[(l <= i ? i * {n} + l : l * {n} + i) * {nv} + v] * f[l];\n")
    if mc is not None:
        code += f"            for (int c = 0; c < {mc}; ++c) r += dJ[(c * {n} + i) * {nv} + v] * lam[c];\n"
    code += f"            dF[i * {nv} + v] = r;\n        }}\n"
    if mc is None:
        return code + f"    amble_chol_apply_rows({n}, M, dF, {nv});\n"
    code += f"    for (int c = 0; c < {mc}; ++c)\n        for (int v = 0; v < {ni}; ++v) {{\n"
    code += f"            double r = dG[c * {nv} + v];\n"
    code += f"            for (int l = 0; l < {n}; ++l) r -= dJ[(c * {n} + l) * {nv} + v] * f[l];\n"
    code += f"            dG[c * {nv} + v] = r;\n        }}\n"
    return code + f"    err = amble_holonomic_tangent({n}, {mc}, {nv}, M, Jh, dF, dG);\n    if (err) return err;\n"


def rhs_jacobian_code(mi: ModeInfo, names: dict[sp.Symbol, str], params: list[str]) -> str:
    """``rhs_jac_k(t, x, p, dx, J)``: ``dx = f`` and the state columns of ``J = ∂f/∂x``;
    ``rhs_jacp_k(t, x, p, J)``: its parameter columns ``∂f/∂p`` (rows of ``SC``)."""
    return _flow_jacobian_code(mi, names, params, False) + _flow_jacobian_code(mi, names, params, True)


def surfaces_gradient_code(mi: ModeInfo, surfaces: list[sp.Expr], names: dict[sp.Symbol, str],
                           params: list[str]) -> str:
    """``surfaces_grad_k``: ``∂s/∂(x, p)`` of the mode's guards then switching surfaces, one row
    of ``SC`` each."""
    m, k = mi.model, mi.index
    inputs, cols = _inputs(m, params, with_time=False)
    code = f"static void surfaces_grad_{k}(double t, const double *x, const double *p, double *G) {{\n"
    code += "    (void)t; (void)x; (void)p;\n"
    code += f"    for (int i = 0; i < {len(surfaces)} * SC; ++i) G[i] = 0.0;\n"
    code += jacobian_block(surfaces, [None] * len(surfaces), lambda o, i: f"G[{o} * SC + {cols[i]}]", inputs, names)
    return code + "}\n"


def reset_jacobian_code(i: int, tr, src: ModeInfo, modes: dict[str, ModeInfo], names: dict[sp.Symbol, str],
                        params: list[str]) -> str:
    """``reset_jac_i``: ``∂Δ/∂(x, p, t)`` of transition ``i``'s reset, rows of ``SC + 1``."""
    head = f"static int reset_jac_{i}(double t, const double *x, const double *p, double *D) {{\n"
    head += "    (void)t; (void)x; (void)p;\n"
    m = src.model
    n = len(m.q)
    if tr.reset is None:  # identity
        body = (f"    for (int a = 0; a < {2 * n}; ++a) {{\n"
                "        for (int j = 0; j <= SC; ++j) D[a * (SC + 1) + j] = 0.0;\n")
        body += "        D[a * (SC + 1) + a] = 1.0;\n    }\n    return 0;\n"
        return head + body + "}\n"
    dst = modes[tr.target]
    nd = len(dst.model.q)
    what = f"reset of transition {tr.name!r}"
    inputs, cols = _inputs(m, params, with_time=True)
    clear = f"    for (int a = 0; a < {2 * nd} * (SC + 1); ++a) D[a] = 0.0;\n"
    if tr.reset.written is not None:  # written out: the Jacobian of the given target state
        q_to, qd_to = tr.reset.written
        exprs = target_exprs(dst.model, q_to, what, source=m)
        exprs += target_exprs(dst.model, qd_to, what, velocities=True, source=m)
        code = jacobian_block(exprs, [None] * len(exprs), lambda o, j: f"D[{o} * (SC + 1) + {cols[j]}]", inputs, names)
        return head + clear + code + "    return 0;\n}\n"
    defs, Mc, _ = _defs(src)
    imp = impulse_data(m, replace(src.equations, M=Mc), tr.reset, dst.model, what,
                       compact=src.equations.compact is not None)
    defs = list(imp.defs) or defs  # a tree's impact blocks name quantities of their own
    Me, Jc, qn, T = imp.Me, imp.Jc, imp.q_new, imp.velocity_map
    ne, nc = Me.shape[0], Jc.shape[0]
    nk = ne + nc
    nv = len(inputs)
    # value target, derivative target (row index into a per-variable array) per entry
    ent = [(f"Me[{a * ne + b}]", ("dMe", a * ne + b), Me[a, b]) for a in range(ne) for b in range(ne)]
    ent += [(f"Jc[{a * ne + b}]", ("dJc", a * ne + b), Jc[a, b]) for a in range(nc) for b in range(ne)]
    ent += [(None, ("dqn", a), qn[a]) for a in range(nd)]
    ent += [(f"T[{a * n + b}]", ("dT", a * n + b), T[a, b]) for a in range(nd) for b in range(n)]
    code = head + clear
    code += f"    double Me[{ne * ne}], Jc[{nc * ne}], T[{nd * n}], u[{ne}], lam[{nc}];\n"
    code += f"    double dMe[{ne * ne * nv}], dJc[{nc * ne * nv}], dqn[{nd * nv}], dT[{nd * n * nv}], B[{nk * nv}];\n"
    code += "    memset(dMe, 0, sizeof dMe);\n    memset(dJc, 0, sizeof dJc);\n"
    code += "    memset(dqn, 0, sizeof dqn);\n    memset(dT, 0, sizeof dT);\n"
    code += jacobian_block([e for _, _, e in ent], [v for v, _, _ in ent],
                           lambda o, j: f"{ent[o][1][0]}[{ent[o][1][1] * nv + j}]", inputs, names, defs=defs)
    code += f"    for (int j = 0; j < {ne}; ++j) u[j] = j < {n} ? x[{n} + j] : 0.0;\n"
    code += f"    int err = amble_impulse_lambda({ne}, {nc}, Me, Jc, u, lam);\n    if (err) return err;\n"
    # the KKT right-hand side of each variable: (Mₑ' (v⁻ − v⁺) + J'ᵀλ + Mₑ ∂v⁻, −J' v⁺)
    code += f"    for (int v = 0; v < {nv}; ++v) {{\n"
    code += f"        for (int a = 0; a < {ne}; ++a) {{\n"
    code += f"            double r = (v >= {n} && v < {2 * n}) ? Me[a * {ne} + v - {n}] : 0.0;\n"
    code += (f"            for (int b = 0; b < {ne}; ++b)\n"
             f"                r += dMe[(a * {ne} + b) * {nv} + v] * ((b < {n} ? x[{n} + b] : 0.0) - u[b]);\n")
    code += f"            for (int q = 0; q < {nc}; ++q) r += dJc[(q * {ne} + a) * {nv} + v] * lam[q];\n"
    code += f"            B[a * {nv} + v] = r;\n        }}\n"
    code += f"        for (int q = 0; q < {nc}; ++q) {{\n            double r = 0.0;\n"
    code += f"            for (int b = 0; b < {ne}; ++b) r -= dJc[(q * {ne} + b) * {nv} + v] * u[b];\n"
    code += f"            B[({ne} + q) * {nv} + v] = r;\n        }}\n    }}\n"
    code += f"    err = amble_kkt_solve_columns({ne}, {nc}, Me, Jc, B, {nv});\n    if (err) return err;\n"
    code += f"    static const int col[{nv}] = {{{', '.join(cols)}}};\n"
    code += f"    for (int v = 0; v < {nv}; ++v)\n        for (int a = 0; a < {nd}; ++a) {{\n"
    code += (f"            double s = 0.0;\n            for (int b = 0; b < {n}; ++b)\n"
             f"                s += dT[(a * {n} + b) * {nv} + v] * u[b] + T[a * {n} + b] * B[b * {nv} + v];\n")
    code += f"            D[a * (SC + 1) + col[v]] = dqn[a * {nv} + v];\n"
    code += f"            D[({nd} + a) * (SC + 1) + col[v]] = s;\n        }}\n    return 0;\n}}\n"
    return code


_SIGNATURES = (
    ("int", "rhs_jac(int mode, double t, const double *x, const double *p, double *dx, double *J)",
     "mode", "rhs_jac_{}(t, x, p, dx, J)"),
    ("int", "rhs_jacp(int mode, double t, const double *x, const double *p, double *J)", "mode",
     "rhs_jacp_{}(t, x, p, J)"),
    ("void", "surfaces_grad(int mode, double t, const double *x, const double *p, double *G)", "mode",
     "surfaces_grad_{}(t, x, p, G)"),
    ("int", "reset_jac(int tr, double t, const double *x, const double *p, double *D)", "tr",
     "reset_jac_{}(t, x, p, D)"),
)


def derivative_kernels(modes: dict[str, ModeInfo], order: list, trs_by_mode: dict[str, list],
                       switches: dict[str, list[sp.Expr]], params: list[str]) -> str:
    """All derivative kernels of a system and their dispatchers (``rhs_jac``, ``rhs_jacp``,
    ``surfaces_grad``, ``reset_jac``)."""
    kernels = []
    for name, mi in modes.items():
        nm = symbol_names(mi.model, params)
        surf = [sp.sympify(tr.guard.expr) for tr in trs_by_mode[name]] + list(switches[name])
        kernels.append(rhs_jacobian_code(mi, nm, params))
        kernels.append(surfaces_gradient_code(mi, surf, nm, params))
    for i, tr in enumerate(order):
        kernels.append(reset_jacobian_code(i, tr, modes[tr.source], modes, symbol_names(modes[tr.source].model, params),
                                           params))
    out = [_unoptimised("".join(kernels))]
    counts = {"mode": len(modes), "tr": len(order)}
    for ret, sig, key, call in _SIGNATURES:
        ret_kw, brk = ("return ", "") if ret != "void" else ("", " break;")
        cases = "".join(f"    case {j}: {ret_kw}{call.format(j)};{brk}\n" for j in range(counts[key]))
        out.append(f"static {ret} {sig} {{\n    switch ({key}) {{\n{cases}    }}\n"
                   + ("    return -1;\n" if ret != "void" else "") + "}\n")
    return "".join(out)


#: Derivative kernels of up to this many characters of C are compiled with the unit's flags
#: (``-O2``); longer ones unoptimised. Their straight-line code is an order of magnitude longer
#: than the right-hand side's and GCC's optimiser is superlinear in the length of a basic block.
#: Measured (``gcc -O2`` of the whole unit, seconds, idle machine; the characters are those of
#: the kernels): compass gait (36 k) 1.1 at O0 / 1.4 optimised, kneed biped (150 k) 2.2 / 2.9,
#: humanoid-2d (195 k) 2.8 / 3.7, kuo-3d (310 k) 3.5 / 9.3, humanoid-3d (643 k) 7 / 21 at O1 and
#: 63 at O2. Optimised, the kernels make a sensitivity run of the compass gait or the kneed biped
#: about 1.5× faster: worth a second of build below the limit, not a minute above it.
OPTIMISE_LIMIT = 250_000


def _unoptimised(code: str) -> str:
    """``code`` as it is below :data:`OPTIMISE_LIMIT` characters, else wrapped so that GCC
    compiles it at ``-O0``."""
    if len(code) <= OPTIMISE_LIMIT:
        return code
    return ("#if defined(__GNUC__) && !defined(__clang__)\n#pragma GCC push_options\n"
            "#pragma GCC optimize (\"O0\")\n#endif\n" + code
            + "#if defined(__GNUC__) && !defined(__clang__)\n#pragma GCC pop_options\n#endif\n")


def derivative_stubs() -> str:
    """Stand-ins of the derivative kernels in a library built without them: they report
    ``AMBLE_ERR_NO_DERIVATIVES`` (the Python side asks for the library with them first)."""
    out = []
    for ret, sig, _, _ in _SIGNATURES:
        args = [a.split()[-1].lstrip("*") for a in sig[sig.index("(") + 1 : -1].split(",")]
        body = "".join(f"(void){a}; " for a in args)
        out.append(f"static {ret} {sig} {{ {body}{'return AMBLE_ERR_NO_DERIVATIVES; ' if ret != 'void' else ''}}}\n")
    return "".join(out)
