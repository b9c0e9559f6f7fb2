"""C code generation: a hybrid system's kernels as one translation unit.

Every kernel is emitted from sympy expressions after common-subexpression elimination, with
coordinates read from the state array ``x`` (``x[i]`` = qᵢ, ``x[n+i]`` = q̇ᵢ) and parameters
from ``p`` — parameters are run-time inputs, so changing a mass or a slope recompiles nothing.
Nothing symbolic is derived here: the equations of motion come from
:mod:`amble.derivation.equations`, impact and lock maps from :mod:`amble.derivation.impact`, and
the interface codes from :func:`amble.backend.abi.c_header`. The generated unit ends with
``model_tail.h``: the model's sizes and kernels as hidden symbols for the shared runtime (the
event loop, compiled once: :mod:`amble.backend.runtime`) and the DOP853 step, compiled here so
that the right-hand side is inlined into the integrator.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import sympy as sp
from sympy.core.relational import Relational

from ..derivation.equations import derive
from ..derivation.holonomic import Holonomic
from ..derivation.impact import impulse_data
from ..derivation.switching import switching_surfaces
from ..modelling.hybrid import HybridSystem, target_exprs
from ..modelling.model import t
from . import abi
from .codegen_support import ModeInfo, count_ops
from .codegen_support import Printer as _Printer
from .codegen_support import block as _block
from .codegen_support import bool_expr as _bool_block
from .codegen_support import symbol_names as _names
from .hoist import Hoister
from .ldl import UNROLL_MAX, constant_pivots, ldl_order, ldl_solve_code
from .runtime import CAPACITY_MACRO, TAIL, capacity
from .trig import pythagoras
from .units import UNIT_BEGIN, UNIT_END
from .variational_codegen import derivative_kernels, derivative_stubs


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


#: Largest ``mh_k`` (operations of M, h, Γ) that is forced inline into ``rhs_k`` and ``dynamics_k``.
INLINE_OPS = 400
#: Characters of a reset's body above which it is compiled in the unit of its own (units.split_units).
OWN_UNIT_CHARS = 40_000

def generate(system: HybridSystem, derivatives: bool = False, hoist_params: bool = True) -> tuple[str, dict]:
    """Generate the C source of a system; returns (source, metadata for the loader). With
    ``derivatives`` also the derivative kernels of sensitivity runs and of the implicit
    integrator (several times longer than the rest: built only when asked for).
    ``hoist_params=False`` recomputes parameter-only subexpressions at every use instead of once
    per call (:mod:`amble.backend.hoist`) and solves with M as if it were dense, in the natural
    order (:mod:`amble.backend.ldl`): for benchmarks of what those save."""
    params = list(system.parameters)
    modes = {name: ModeInfo(m, derive(m), i) for i, (name, m) in enumerate(system.modes.items())}
    points = system.point_names
    nx = [2 * len(mi.model.q) for mi in modes.values()]
    trs_by_mode = {name: [tr for tr in system.transitions if tr.source == name] for name in modes}
    order = [tr for name in modes for tr in trs_by_mode[name]]
    tr0, acc = [], 0
    for name in modes:
        tr0.append(acc)
        acc += len(trs_by_mode[name])
    ntr = len(order)
    switches = {name: _mode_switches(mi) for name, mi in modes.items()}
    sw0, acc = [], 0
    for name in modes:
        sw0.append(acc)
        acc += len(switches[name])

    hoist = Hoister({s for mi in modes.values() for s in mi.model.params}, enabled=hoist_params)

    def blk(targets: list[str], exprs: list, nm: dict, prelude: str = "", shared: bool = False) -> str:
        ex = hoist(exprs)
        return _block(targets, ex, {**nm, **hoist.names}, prelude=prelude, shared=shared)

    out: list[str] = []
    w = out.append
    w('#include "amble_core.h"\n')
    w(abi.c_header())
    w(f"#define NMODES {len(modes)}\n#define NXMAX {max(nx)}\n#define NTR {ntr}\n")
    # the state capacity of the shared runtime this unit is linked with (backend/runtime.py)
    w(f"#define {CAPACITY_MACRO} {capacity(max(nx))}\n")
    if len(set(nx)) == 1:  # one state length: the integrator's loops get constant trip counts
        w(f"#define NX_FIXED {nx[0]}\n")
    w(f"#define NPOINTS {len(points)}\n#define NPARAM {max(len(params), 1)}\n")
    w("#define SC (NXMAX + NPARAM)\n")  # columns of a sensitivity row: state, then parameters
    w(_slot_map(modes, params))
    w(f"AMBLE_HIDDEN const int MODE_NX[NMODES] = {{{', '.join(map(str, nx))}}};\n")
    w(f"AMBLE_HIDDEN const int MODE_NTR[NMODES] = {{{', '.join(str(len(trs_by_mode[m])) for m in modes)}}};\n")
    w(f"AMBLE_HIDDEN const int MODE_TR0[NMODES] = {{{', '.join(map(str, tr0))}}};\n")
    w(f"#define NSWMAX {max(len(v) for v in switches.values())}\n")
    w(f"AMBLE_HIDDEN const int MODE_NSW[NMODES] = {{{', '.join(str(len(switches[m])) for m in modes)}}};\n")
    w(f"AMBLE_HIDDEN const int MODE_SW0[NMODES] = {{{', '.join(map(str, sw0))}}};\n")
    arr = lambda vals: ", ".join(map(str, vals)) if vals else "0"
    w(f"AMBLE_HIDDEN const int TR_DIR[NTR > 0 ? NTR : 1] = {{{arr([tr.guard.direction for tr in order])}}};\n")
    terminal = [int(tr.terminal is not None) for tr in order]
    w(f"AMBLE_HIDDEN const int TR_TERMINAL[NTR > 0 ? NTR : 1] = {{{arr(terminal)}}};\n")
    w(f"AMBLE_HIDDEN const int TR_STEP[NTR > 0 ? NTR : 1] = {{{arr([int(tr.step) for tr in order])}}};\n")
    # the transition taken instead of a zeno end when this one's firings accumulate (-1: none)
    index = {tr.name: j for j, tr in enumerate(order)}
    w(f"AMBLE_HIDDEN const int TR_REST[NTR > 0 ? NTR : 1] = {{{arr([index.get(tr.rest, -1) for tr in order])}}};\n\n")

    for name, mi in modes.items():
        m, eq, k = mi.model, mi.equations, mi.index
        n = len(m.q)
        nm = _names(m, params)
        # a rigid-body tree's M and h come with their intermediate quantities (Equations.compact)
        defs, eqM, eqh = eq.compact if eq.compact is not None else ((), eq.M, eq.h)
        nm = {**nm, **{s: f"k_{i}" for i, (s, _) in enumerate(defs)}}
        prelude = _defs_code(defs, nm, hoist)
        # each named quantity is at least one operation: a lower bound of the prelude's size
        w(_dynamics_code(k, n, eqM, eqh, eq.closed_loop_force, nm, prelude, hoist, len(defs), eq.holonomic,
                         m.tree is not None))
        # guards of this mode's transitions
        trs = trs_by_mode[name]
        w(f"static void guards_{k}(double t, const double *x, const double *p, double *g) {{\n")
        w("    (void)t; (void)x; (void)p; (void)g;\n")
        w(blk([f"g[{i}]" for i in range(len(trs))], [sp.sympify(tr.guard.expr) for tr in trs], nm))
        w("}\n")
        # time derivatives of the guards along the flow, ġ = ∇ₓg · ẋ + ∂g/∂t (ẋ given as dx)
        xs = [*m.q, *m.qd]
        dxs = [sp.Symbol(f"dx_{j}", real=True) for j in range(2 * n)]
        nm_d = dict(nm)
        nm_d.update({d: f"dx[{j}]" for j, d in enumerate(dxs)})
        gdot = []
        for tr in trs:
            ge = sp.sympify(tr.guard.expr)
            gdot.append(m.diff(ge, t) + sum((m.diff(ge, xj) * dj for xj, dj in zip(xs, dxs)), sp.Integer(0)))
        w(f"static void guards_dot_{k}(double t, const double *x, const double *dx, const double *p, double *g) {{\n")
        w("    (void)t; (void)x; (void)dx; (void)p; (void)g;\n")
        w(blk([f"g[{i}]" for i in range(len(trs))], gdot, nm_d))
        w("}\n")
        # switching surfaces of the right-hand side and their rates (events without a reset)
        sws = switches[name]
        w(f"static void switches_{k}(double t, const double *x, const double *p, double *s) {{\n")
        w("    (void)t; (void)x; (void)p; (void)s;\n")
        w(blk([f"s[{i}]" for i in range(len(sws))], sws, nm))
        w("}\n")
        sdot = [sp.diff(e, t) + sum((sp.diff(e, xj) * dj for xj, dj in zip(xs, dxs)), sp.Integer(0)) for e in sws]
        w(f"static void switches_dot_{k}(double t, const double *x, const double *dx, const double *p, double *s) {{\n")
        w("    (void)t; (void)x; (void)dx; (void)p; (void)s;\n")
        w(blk([f"s[{i}]" for i in range(len(sws))], sdot, nm_d))
        w("}\n")
        # energies
        if eq.K is not None:
            e_ex = [eq.K, eq.V]
        else:
            e_ex = [eq.energy, sp.Integer(0)]
        w(f"static void energy_{k}(double t, const double *x, const double *p, double *out) {{\n")
        w("    (void)t; (void)p;\n")
        w(blk(["out[0]", "out[1]"], e_ex, nm, shared=m.tree is not None))
        w("}\n")
        # kinematics of named points (3 components each; 2D models have y = 0)
        tg, ex = [], []
        for j, pname in enumerate(points):
            if pname not in m.points:
                continue
            pos = m.points[pname]
            vel = m.dt(pos)
            comps = [pos[0], 0, pos[1]] if m.dims == 2 else list(pos)
            vcomps = [vel[0], 0, vel[1]] if m.dims == 2 else list(vel)
            for c in range(3):
                tg += [f"pos[{3 * j + c}]", f"vel[{3 * j + c}]"]
                ex += [sp.sympify(comps[c]), sp.sympify(vcomps[c])]
        w(f"static void kinematics_{k}(double t, const double *x, const double *p, double *pos, double *vel) {{\n")
        w("    (void)t; (void)x; (void)p;\n")
        w(f"    for (int i = 0; i < {3 * len(points)}; ++i) {{ pos[i] = NAN; vel[i] = NAN; }}\n")
        w(blk(tg, ex, nm, shared=m.tree is not None))
        w("}\n")
        w(_rhs_surfaces_code(k, 2 * n, len(trs), len(sws)))

    # transitions: enabling conditions and resets
    for i, tr in enumerate(order):
        src = modes[tr.source]
        nm = _names(src.model, params)
        enabled = None if tr.guard.enabled is None else hoist.one(tr.guard.enabled)
        w(f"static int enabled_{i}(double t, const double *x, const double *p) {{\n")
        w(_enabled_code(enabled, {**nm, **hoist.names}))
        w(_reset_code(i, tr, src, modes, nm, params, hoist))

    # derivatives for sensitivity runs and the implicit integrator, or stubs (variational_codegen)
    if derivatives:
        w(derivative_kernels(modes, order, trs_by_mode, switches, params))
    else:
        w(derivative_stubs())

    # dispatchers
    def dispatch(sig: str, ret: str, call: str, names: list[str], key: str) -> None:
        w(f"static {ret} {sig} {{\n    switch ({key}) {{\n")
        for j, _ in enumerate(names):
            r = "return " if ret != "void" else ""
            brk = "" if ret != "void" else " break;"
            w(f"    case {j}: {r}{call.format(j)};{brk}\n")
        w("    }\n")
        if ret != "void":
            w("    return -1;\n")
        w("}\n")

    mode_list = list(modes)
    dispatch("rhs(int mode, double t, const double *x, const double *p, double *dx)", "int",
             "rhs_{}(t, x, p, dx)", mode_list, "mode")
    dispatch("rhs_surfaces(int mode, double t, const double *x, const double *p, double *dx, double *g, double *gd)",
             "int", "rhs_surfaces_{}(t, x, p, dx, g, gd)", mode_list, "mode")
    dispatch("guards(int mode, double t, const double *x, const double *p, double *g)", "void",
             "guards_{}(t, x, p, g)", mode_list, "mode")
    dispatch("guards_dot(int mode, double t, const double *x, const double *dx, const double *p, double *g)",
             "void", "guards_dot_{}(t, x, dx, p, g)", mode_list, "mode")
    dispatch("switches(int mode, double t, const double *x, const double *p, double *s)", "void",
             "switches_{}(t, x, p, s)", mode_list, "mode")
    dispatch("switches_dot(int mode, double t, const double *x, const double *dx, const double *p, double *s)",
             "void", "switches_dot_{}(t, x, dx, p, s)", mode_list, "mode")
    dispatch("constraint_forces(int mode, double t, const double *x, const double *p, double *lam)", "int",
             "constraint_forces_{}(t, x, p, lam)", mode_list, "mode")
    dispatch("dynamics(int mode, double t, const double *x, const double *p, double *M, double *h, double *G)",
             "void", "dynamics_{}(t, x, p, M, h, G)", mode_list, "mode")
    dispatch("energy(int mode, double t, const double *x, const double *p, double *out)", "void",
             "energy_{}(t, x, p, out)", mode_list, "mode")
    dispatch("kinematics(int mode, double t, const double *x, const double *p, double *pos, double *vel)",
             "void", "kinematics_{}(t, x, p, pos, vel)", mode_list, "mode")
    dispatch("enabled(int tr, double t, const double *x, const double *p)", "int",
             "enabled_{}(t, x, p)", [tr.name for tr in order], "tr")
    dispatch("reset(int tr, double t, const double *x, const double *p, double *xout, int *target)", "int",
             "reset_{}(t, x, p, xout, target)", [tr.name for tr in order], "tr")
    pnames = {s: f"p[{params.index(str(s))}]" for s in hoist.params}
    w(hoist.c_code(len(params), pnames, _block))
    w(f'\n#include "{TAIL}"\n')

    meta = {
        "name": system.name,
        "modes": mode_list,
        "nx": nx,
        "params": params,
        "param_defaults": [system.parameters[p] for p in params],
        "points": points,
        "state_names": {mn: system.modes[mn].state_names for mn in mode_list},
        "transitions": [
            {
                "name": tr.name,
                "source": tr.source,
                "target": tr.target,
                "terminal": tr.terminal,
                "step": tr.step,
                "rest": tr.rest,
                "shift": (tr.reset.shift_point if tr.reset is not None else None),
            }
            for tr in order
        ],
        "dims": system.dims,
        "switches": [{"mode": mn, "expr": str(e)} for mn in mode_list for e in switches[mn]],
        "derivatives": derivatives,
        "constraints": {mn: list(system.modes[mn].constraint_names) for mn in mode_list},
    }
    return "".join(out), meta


def _slot_map(modes: dict[str, ModeInfo], params: list[str]) -> str:
    """A comment naming what each slot of the state ``x`` and the parameters ``p`` holds: the
    kernels below read them by index."""
    def c(text: str) -> str:  # a name cannot end the comment early
        return text.replace("*/", "* /")

    lines = ["/* Slots read by the kernels of this unit (x: the state of the mode, p: the parameters;",
             " * p[NPARAM + j] are parameter-only values computed once per call, amble_params_prelude)."]
    for name, mi in modes.items():
        names = mi.model.state_names
        lines.append(f" * mode {mi.index} {c(name)!r}: " + ", ".join(f"x[{i}] {c(v)}" for i, v in enumerate(names)))
    lines.append(" * parameters: " + (", ".join(f"p[{i}] {c(v)}" for i, v in enumerate(params)) or "none"))
    return "\n".join(lines) + " */\n"


def _rhs_surfaces_code(k: int, nx: int, ntr: int, nsw: int) -> str:
    """``rhs_surfaces_k``: the right-hand side, then the mode's surfaces (guards, then switching
    surfaces) and their rates along it, at one point — the last stage of every integrator step,
    whose surfaces the event screening needs. Flattened (every kernel inlined into one body), the
    terms the kernels share, above all the sines and cosines of the coordinates, are computed once
    by the C compiler's common-subexpression elimination; each surface is the same expression as in
    ``guards_k`` (no reassociation), so the values are those of the separate kernels."""
    # the state is copied: stores through dx could otherwise alias x, and every x[i] read after
    # them would be a new value to the compiler (its sines recomputed)
    body = [f"static AMBLE_FLATTEN int rhs_surfaces_{k}(double t, const double *x0, const double *p, double *dx,"
            " double *g, double *gd) {\n",
            f"    double x[{nx}];\n",
            f"    for (int i = 0; i < {nx}; ++i) x[i] = x0[i];\n",
            f"    const int err = rhs_{k}(t, x, p, dx);\n",
            "    if (err) return err;\n"]
    if ntr:
        body += [f"    guards_{k}(t, x, p, g);\n", f"    guards_dot_{k}(t, x, dx, p, gd);\n"]
    if nsw:
        body += [f"    switches_{k}(t, x, p, g + {ntr});\n", f"    switches_dot_{k}(t, x, dx, p, gd + {ntr});\n"]
    if not ntr and not nsw:
        body.append("    (void)g; (void)gd;\n")
    return "".join(body) + "    return 0;\n}\n\n"


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


def _mode_switches(mi: ModeInfo) -> list[sp.Expr]:
    """Switching surfaces of a mode's right-hand side (forces, controllers, the mass matrix)."""
    eq, m = mi.equations, mi.model
    exprs = [*eq.closed_loop_force, *eq.h, *eq.M]
    if eq.holonomic is not None:  # a constraint written with Abs or Piecewise switches the flow too
        exprs += [*eq.holonomic.J, *eq.holonomic.gamma]
    return switching_surfaces(exprs, [*m.q, *m.qd, t])


def _defs_code(defs: Any, nm: dict[sp.Symbol, str], hoist: Hoister) -> str:
    """Statements of a rigid-body tree's named intermediate quantities (``k_i``), hoisted."""
    rhs = hoist([e for _, e in defs])
    pr = _Printer({**nm, **hoist.names})
    return "\n".join(f"    const double {nm[s]} = {pr.doprint(e)};" for (s, _), e in zip(defs, rhs))


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
