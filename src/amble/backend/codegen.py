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

import sympy as sp

from ..derivation.equations import derive
from ..derivation.switching import switching_surfaces
from ..modelling.hybrid import HybridSystem
from ..modelling.model import t
from . import abi
from .codegen_support import ModeInfo
from .codegen_support import block as _block
from .codegen_support import symbol_names as _names
from .dynamics_codegen import _defs_code, _dynamics_code
from .hoist import Hoister
from .runtime import CAPACITY_MACRO, TAIL, capacity
from .transition_codegen import _enabled_code, _reset_code
from .variational_codegen import derivative_kernels, derivative_stubs


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


def _mode_switches(mi: ModeInfo) -> list[sp.Expr]:
    """Switching surfaces of a mode's right-hand side (forces, controllers, the mass matrix)."""
    eq, m = mi.equations, mi.model
    exprs = [*eq.closed_loop_force, *eq.h, *eq.M]
    if eq.holonomic is not None:  # a constraint written with Abs or Piecewise switches the flow too
        exprs += [*eq.holonomic.J, *eq.holonomic.gamma]
    return switching_surfaces(exprs, [*m.q, *m.qd, t])
