"""C code generation: a hybrid system's kernels as one translation unit.

Every kernel is emitted from sympy expressions after common-subexpression elimination, with
coordinates read from the state array ``x`` (``x[i]`` = qᵢ, ``x[n+i]`` = q̇ᵢ) and parameters
from ``p`` — parameters are run-time inputs, so changing a mass or a slope recompiles nothing.
Nothing symbolic is derived here: the equations of motion come from
:mod:`amble.derivation.equations`, impact and lock maps from :mod:`amble.derivation.impact`, and
the interface codes from :func:`amble.backend.abi.c_header`. The generated unit includes
``hybrid.c``, the integrator and event loop, so the whole walking step is compiled together and
the right-hand side is inlined into the integrator.
"""

from __future__ import annotations

from dataclasses import replace

import sympy as sp

from ..derivation.equations import derive
from ..derivation.impact import impulse_data
from ..derivation.switching import switching_surfaces
from ..modelling.hybrid import Explicit, HybridSystem, target_exprs
from ..modelling.model import t
from . import abi
from .codegen_support import ModeInfo
from .codegen_support import Printer as _Printer
from .codegen_support import block as _block
from .codegen_support import bool_expr as _bool_block
from .codegen_support import symbol_names as _names
from .variational_codegen import reset_jacobian_code, rhs_jacobian_code, surfaces_gradient_code


def generate(system: HybridSystem) -> tuple[str, dict]:
    """Generate the C source of a system; returns (source, metadata for the loader)."""
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

    out: list[str] = []
    w = out.append
    w('#include "amble_core.h"\n')
    w(abi.c_header())
    w(f"#define NMODES {len(modes)}\n#define NXMAX {max(nx)}\n#define NTR {ntr}\n")
    w(f"#define NPOINTS {len(points)}\n#define NPARAM {max(len(params), 1)}\n")
    w("#define SC (NXMAX + NPARAM)\n")  # columns of a sensitivity row: state, then parameters
    w(f"static const int MODE_NX[NMODES] = {{{', '.join(map(str, nx))}}};\n")
    w(f"static const int MODE_NTR[NMODES] = {{{', '.join(str(len(trs_by_mode[m])) for m in modes)}}};\n")
    w(f"static const int MODE_TR0[NMODES] = {{{', '.join(map(str, tr0))}}};\n")
    w(f"#define NSWMAX {max(len(v) for v in switches.values())}\n")
    w(f"static const int MODE_NSW[NMODES] = {{{', '.join(str(len(switches[m])) for m in modes)}}};\n")
    w(f"static const int MODE_SW0[NMODES] = {{{', '.join(map(str, sw0))}}};\n")
    arr = lambda vals: ", ".join(map(str, vals)) if vals else "0"
    w(f"static const int TR_DIR[NTR > 0 ? NTR : 1] = {{{arr([tr.guard.direction for tr in order])}}};\n")
    w(f"static const int TR_TERMINAL[NTR > 0 ? NTR : 1] = {{{arr([int(tr.terminal is not None) for tr in order])}}};\n")
    w(f"static const int TR_STEP[NTR > 0 ? NTR : 1] = {{{arr([int(tr.step) for tr in order])}}};\n")
    # the transition taken instead of a zeno end when this one's firings accumulate (-1: none)
    index = {tr.name: j for j, tr in enumerate(order)}
    w(f"static const int TR_REST[NTR > 0 ? NTR : 1] = {{{arr([index.get(tr.rest, -1) for tr in order])}}};\n\n")

    for name, mi in modes.items():
        m, eq, k = mi.model, mi.equations, mi.index
        n = len(m.q)
        nm = _names(m, params)
        # a rigid-body tree's M and h come with their intermediate quantities (Equations.compact)
        defs, eqM, eqh = eq.compact if eq.compact is not None else ((), eq.M, eq.h)
        nm = {**nm, **{s: f"k_{i}" for i, (s, _) in enumerate(defs)}}
        pr = _Printer(nm)
        prelude = "\n".join(f"    const double {nm[s]} = {pr.doprint(e)};" for s, e in defs)
        # right-hand side: q̈ = M⁻¹ (Γ − h)
        tg = [f"M[{i * n + j}]" for i in range(n) for j in range(i + 1)]
        ex = [eqM[i, j] for i in range(n) for j in range(i + 1)]
        tg += [f"f[{i}]" for i in range(n)]
        ex += [eq.closed_loop_force[i] - eqh[i] for i in range(n)]
        w(f"static int rhs_{k}(double t, const double *x, const double *p, double *dx) {{\n")
        w(f"    double M[{n * n}], f[{n}];\n    (void)t; (void)p;\n")
        w(_block(tg, ex, nm, prelude=prelude))
        w(f"    int err = amble_chol_solve({n}, M, f);\n")
        w(f"    for (int i = 0; i < {n}; ++i) {{ dx[i] = x[{n} + i]; dx[{n} + i] = f[i]; }}\n")
        w("    return err;\n}\n")
        # M, h and Γ separately (analysis and display; the integrator uses rhs above)
        tg = [f"M[{i * n + j}]" for i in range(n) for j in range(n)] + [f"h[{i}]" for i in range(n)]
        tg += [f"G[{i}]" for i in range(n)]
        ex = [eqM[i, j] for i in range(n) for j in range(n)] + list(eqh) + list(eq.closed_loop_force)
        w(f"static void dynamics_{k}(double t, const double *x, const double *p, double *M, double *h, double *G) {{\n")
        w("    (void)t; (void)p;\n")
        w(_block(tg, ex, nm, prelude=prelude))
        w("}\n")
        # guards of this mode's transitions
        trs = trs_by_mode[name]
        w(f"static void guards_{k}(double t, const double *x, const double *p, double *g) {{\n")
        w("    (void)t; (void)x; (void)p; (void)g;\n")
        w(_block([f"g[{i}]" for i in range(len(trs))], [sp.sympify(tr.guard.expr) for tr in trs], nm))
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
        w(_block([f"g[{i}]" for i in range(len(trs))], gdot, nm_d))
        w("}\n")
        # switching surfaces of the right-hand side and their rates (events without a reset)
        sws = switches[name]
        w(f"static void switches_{k}(double t, const double *x, const double *p, double *s) {{\n")
        w("    (void)t; (void)x; (void)p; (void)s;\n")
        w(_block([f"s[{i}]" for i in range(len(sws))], sws, nm))
        w("}\n")
        sdot = [sp.diff(e, t) + sum((sp.diff(e, xj) * dj for xj, dj in zip(xs, dxs)), sp.Integer(0)) for e in sws]
        w(f"static void switches_dot_{k}(double t, const double *x, const double *dx, const double *p, double *s) {{\n")
        w("    (void)t; (void)x; (void)dx; (void)p; (void)s;\n")
        w(_block([f"s[{i}]" for i in range(len(sws))], sdot, nm_d))
        w("}\n")
        # energies
        if eq.K is not None:
            e_ex = [eq.K, eq.V]
        else:
            e_ex = [eq.energy, sp.Integer(0)]
        w(f"static void energy_{k}(double t, const double *x, const double *p, double *out) {{\n")
        w("    (void)t; (void)p;\n")
        w(_block(["out[0]", "out[1]"], e_ex, nm))
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
        w(_block(tg, ex, nm))
        w("}\n\n")

    # transitions: enabling conditions and resets
    for i, tr in enumerate(order):
        src = modes[tr.source]
        nm = _names(src.model, params)
        cond = "1" if tr.guard.enabled is None else _bool_block(sp.sympify(tr.guard.enabled), nm)
        w(f"static int enabled_{i}(double t, const double *x, const double *p) {{\n")
        w(f"    (void)t; (void)x; (void)p;\n    return ({cond}) ? 1 : 0;\n}}\n")
        w(_reset_code(i, tr, src, modes, nm, params))

    # derivatives for sensitivity runs: flow Jacobians, surface gradients, reset Jacobians. Their
    # straight-line code is an order of magnitude longer than the right-hand side's, and GCC's
    # optimiser is superlinear in the length of a basic block (humanoid-3d: 8 s → 63 s at -O2);
    # unoptimised they compile in seconds and cost a sensitivity run about 2× more
    w("#if defined(__GNUC__) && !defined(__clang__)\n#pragma GCC push_options\n#pragma GCC optimize (\"O0\")\n#endif\n")
    for name, mi in modes.items():
        nm = _names(mi.model, params)
        surf = [sp.sympify(tr.guard.expr) for tr in trs_by_mode[name]] + list(switches[name])
        w(rhs_jacobian_code(mi, nm, params))
        w(surfaces_gradient_code(mi, surf, nm, params))
    for i, tr in enumerate(order):
        w(reset_jacobian_code(i, tr, modes[tr.source], modes, _names(modes[tr.source].model, params), params))
    w("#if defined(__GNUC__) && !defined(__clang__)\n#pragma GCC pop_options\n#endif\n")

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
    dispatch("guards(int mode, double t, const double *x, const double *p, double *g)", "void",
             "guards_{}(t, x, p, g)", mode_list, "mode")
    dispatch("guards_dot(int mode, double t, const double *x, const double *dx, const double *p, double *g)",
             "void", "guards_dot_{}(t, x, dx, p, g)", mode_list, "mode")
    dispatch("switches(int mode, double t, const double *x, const double *p, double *s)", "void",
             "switches_{}(t, x, p, s)", mode_list, "mode")
    dispatch("switches_dot(int mode, double t, const double *x, const double *dx, const double *p, double *s)",
             "void", "switches_dot_{}(t, x, dx, p, s)", mode_list, "mode")
    dispatch("dynamics(int mode, double t, const double *x, const double *p, double *M, double *h, double *G)",
             "void", "dynamics_{}(t, x, p, M, h, G)", mode_list, "mode")
    dispatch("energy(int mode, double t, const double *x, const double *p, double *out)", "void",
             "energy_{}(t, x, p, out)", mode_list, "mode")
    dispatch("kinematics(int mode, double t, const double *x, const double *p, double *pos, double *vel)",
             "void", "kinematics_{}(t, x, p, pos, vel)", mode_list, "mode")
    dispatch("rhs_jac(int mode, double t, const double *x, const double *p, double *dx, double *J)", "int",
             "rhs_jac_{}(t, x, p, dx, J)", mode_list, "mode")
    dispatch("rhs_jacp(int mode, double t, const double *x, const double *p, double *J)", "int",
             "rhs_jacp_{}(t, x, p, J)", mode_list, "mode")
    dispatch("surfaces_grad(int mode, double t, const double *x, const double *p, double *G)", "void",
             "surfaces_grad_{}(t, x, p, G)", mode_list, "mode")
    dispatch("reset_jac(int tr, double t, const double *x, const double *p, double *D)", "int",
             "reset_jac_{}(t, x, p, D)", [tr.name for tr in order], "tr")
    dispatch("enabled(int tr, double t, const double *x, const double *p)", "int",
             "enabled_{}(t, x, p)", [tr.name for tr in order], "tr")
    dispatch("reset(int tr, double t, const double *x, const double *p, double *xout, int *target)", "int",
             "reset_{}(t, x, p, xout, target)", [tr.name for tr in order], "tr")
    w('\n#include "hybrid.c"\n')

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
    }
    return "".join(out), meta


def _mode_switches(mi: ModeInfo) -> list[sp.Expr]:
    """Switching surfaces of a mode's right-hand side (forces, controllers, the mass matrix)."""
    eq, m = mi.equations, mi.model
    exprs = [*eq.closed_loop_force, *eq.h, *eq.M]
    return switching_surfaces(exprs, [*m.q, *m.qd, t])


def _reset_code(i: int, tr, src: ModeInfo, modes: dict[str, ModeInfo], nm: dict, params: list[str]) -> str:
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
    if isinstance(reset, Explicit):
        qn = target_exprs(dst.model, reset.q, what, source=m)
        vn = target_exprs(dst.model, reset.qd, what, velocities=True, source=m)
        body += f"    double y[{2 * nd}];\n"
        body += _block([f"y[{j}]" for j in range(2 * nd)], qn + vn, nm)
        body += f"    for (int j = 0; j < {2 * nd}; ++j) xout[j] = y[j];\n    return 0;\n"
        return head + body + "}\n"
    prelude = ""
    if eq.compact is not None:  # a rigid-body tree: M with its named intermediate quantities
        defs, Mc, _ = eq.compact
        eq = replace(eq, M=Mc)
        nm = {**nm, **{s: f"k_{i}" for i, (s, _) in enumerate(defs)}}
        pr = _Printer(nm)
        prelude = "\n".join(f"    const double {nm[s]} = {pr.doprint(e)};" for s, e in defs)
    imp = impulse_data(m, eq, reset, dst.model, what)  # Impact or Lock (validated when declared)
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
    body += _block(tg, ex, nm, prelude=prelude)
    body += f"    for (int j = 0; j < {ne}; ++j) v[j] = j < {n} ? x[{n} + j] : 0.0;\n"
    body += f"    int err = amble_impulse({ne}, {nc}, Me, Jc, v);\n    if (err) return err;\n"
    body += f"    for (int a = 0; a < {nd}; ++a) {{\n        double s = 0.0;\n"
    body += f"        for (int b = 0; b < {n}; ++b) s += T[a * {n} + b] * v[b];\n"
    body += f"        xout[a] = qn[a];\n        xout[{nd} + a] = s;\n    }}\n    return 0;\n"
    return head + body + "}\n"
