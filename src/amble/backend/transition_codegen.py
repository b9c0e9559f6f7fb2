"""C code of a system's transitions: the enabling condition of each guard (``enabled_i``) and
its reset (``reset_i``: a written-out target state, or the impulse of an impact or a lock solved
by ``amble_impulse``).

Apart from :mod:`amble.backend.codegen`, which assembles the translation unit: a reset is the one
kernel that reads the derived impact data (:mod:`amble.derivation.impact`), and a large one is
compiled in a unit of its own.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import sympy as sp
from sympy.core.relational import Relational

from ..derivation.impact import impulse_data
from ..modelling.hybrid import target_exprs
from .codegen_support import ModeInfo
from .codegen_support import block as _block
from .codegen_support import bool_expr as _bool_block
from .dynamics_codegen import _defs_code
from .hoist import Hoister
from .units import UNIT_BEGIN, UNIT_END

#: Characters of a reset's body above which it is compiled in the unit of its own (units.split_units).
OWN_UNIT_CHARS = 40_000


def _enabled_code(enabled: Any, nm: dict) -> str:
    """The body of an enabling condition: the two sides of each comparison computed with shared
    subexpressions first (a rigid-body tree's positions are shared graphs, which printed as one
    expression would be written out at every use), then the condition of those values."""
    head = "    (void)t; (void)x; (void)p;\n"
    if enabled is None:
        return head + "    return 1;\n}\n"
    sides: list[sp.Expr] = []

    def split(c: Any) -> Any:
        if isinstance(c, (sp.And, sp.Or, sp.Not, sp.Xor)):
            return c.func(*[split(a) for a in c.args])
        if isinstance(c, Relational):
            sides.extend([c.lhs, c.rhs])
            syms = [sp.Symbol(f"e_{len(sides) - 2}", real=True), sp.Symbol(f"e_{len(sides) - 1}", real=True)]
            return c.func(*syms, evaluate=False)
        return c

    cond = split(sp.sympify(enabled))
    if not sides:
        return head + f"    return ({_bool_block(cond, nm)}) ? 1 : 0;\n}}\n"
    names = {**nm, **{sp.Symbol(f"e_{j}", real=True): f"e[{j}]" for j in range(len(sides))}}
    body = f"    double e[{len(sides)}];\n" + _block([f"e[{j}]" for j in range(len(sides))], sides, nm)
    return head + body + f"    return ({_bool_block(cond, names)}) ? 1 : 0;\n}}\n"


def _reset_code(i: int, tr, src: ModeInfo, modes: dict[str, ModeInfo], nm: dict, params: list[str],
                hoist: Hoister) -> str:
    head = f"static int reset_{i}(double t, const double *x, const double *p, double *xout, int *target) {{\n"
    head += "    (void)t; (void)x; (void)p; (void)xout;\n"
    if tr.reset is None:
        return head + f"    *target = {src.index};\n    return 0;\n}}\n"
    dst = modes[tr.target]
    m, eq = src.model, src.equations
    n, nd = len(m.q), len(dst.model.q)
    what = f"reset of transition {tr.name!r}"
    body = f"    *target = {dst.index};\n"
    reset = tr.reset
    if reset.written is not None:  # written out: the target state as given
        q_to, qd_to = reset.written
        qn = target_exprs(dst.model, q_to, what, source=m)
        vn = target_exprs(dst.model, qd_to, what, velocities=True, source=m)
        body += f"    double y[{2 * nd}];\n"
        body += _block([f"y[{j}]" for j in range(2 * nd)], hoist(qn + vn), {**nm, **hoist.names})
        body += f"    for (int j = 0; j < {2 * nd}; ++j) xout[j] = y[j];\n    return 0;\n"
        return head + body + "}\n"
    prelude = ""
    compact = eq.compact is not None  # a rigid-body tree: M with its named intermediate quantities
    if compact:
        eq = replace(eq, M=eq.compact[1])
    imp = impulse_data(m, eq, reset, dst.model, what, compact=compact)  # Impact or Lock (validated when declared)
    if compact:  # the impulse's named quantities: M's and those of the tree's impact blocks
        defs = list(imp.defs) or eq.compact[0]
        nm = {**nm, **{s: f"k_{i}" for i, (s, _) in enumerate(defs)}}
        prelude = _defs_code(defs, nm, hoist)
    Me, Jc, qn, dq = imp.Me, imp.Jc, imp.q_new, imp.velocity_map
    ne, nc = Me.shape[0], Jc.shape[0]
    body += f"    double Me[{ne * ne}], Jc[{nc * ne}], v[{ne}], qn[{nd}], T[{nd * n}];\n"
    tg = [f"Me[{a * ne + b}]" for a in range(ne) for b in range(ne)]
    ex = [Me[a, b] for a in range(ne) for b in range(ne)]
    tg += [f"Jc[{a * ne + b}]" for a in range(nc) for b in range(ne)]
    ex += [Jc[a, b] for a in range(nc) for b in range(ne)]
    tg += [f"qn[{a}]" for a in range(nd)]
    ex += qn
    tg += [f"T[{a * n + b}]" for a in range(nd) for b in range(n)]
    ex += [dq[a, b] for a in range(nd) for b in range(n)]
    body += _block(tg, hoist(ex), {**nm, **hoist.names}, prelude=prelude)
    body += f"    for (int j = 0; j < {ne}; ++j) v[j] = j < {n} ? x[{n} + j] : 0.0;\n"
    body += f"    int err = amble_impulse({ne}, {nc}, Me, Jc, v);\n    if (err) return err;\n"
    body += f"    for (int a = 0; a < {nd}; ++a) {{\n        double s = 0.0;\n"
    body += f"        for (int b = 0; b < {n}; ++b) s += T[a * {n} + b] * v[b];\n"
    body += f"        xout[a] = qn[a];\n        xout[{nd} + a] = s;\n    }}\n    return 0;\n"
    if len(body) <= OWN_UNIT_CHARS:
        return head + body + "}\n"
    # a tree's impact map repeats M's named quantities: as large as mh_k, compiled beside it in the
    # other unit (the 12-DOF walker: 9.4 s + 3.4 s of gcc become 5.8 s + 6.0 s on two cores)
    return UNIT_BEGIN + "AMBLE_HIDDEN " + head.removeprefix("static ") + body + "}\n" + UNIT_END
