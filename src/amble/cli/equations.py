"""``amble equations``: the derived equations of motion of every mode, and every transition with
its guard and, for an impact or a joint lock, the derived impulsive map in matrix form
(``M_e``, ``J``, the relabelling and the velocity map) — as text, LaTeX, or JSON (with ``--latex``,
the JSON carries the LaTeX too)."""

from __future__ import annotations

import argparse
from typing import Any

import sympy as sp

from ..derivation.equations import derive, latex_names, tidy
from ..derivation.impact import impulse_data
from ..modelling.hybrid import Explicit, Impact, Lock, ResetVisitor, target_exprs
from .args import load_model, robot_options

_DIRECTION = {-1: "falling through 0", 1: "rising through 0", 0: "crossing 0"}

#: an entry is simplified for display only if it has at most this many operations as derived
#: (the expansion below grows with the square of a product's factors)
SIMPLIFY_OPS = 300
#: seconds one entry may take to simplify, and all entries of one command together; past them
#: the entry is shown as :func:`~amble.derivation.equations.tidy` leaves it
ENTRY_SECONDS, TOTAL_SECONDS = 2.0, 30.0


class _Timeout(Exception):
    pass


class _Budget:
    """Wall-clock budget of the display simplification (per entry and in total). The per-entry
    limit interrupts SymPy with ``SIGALRM``, available in the main thread of a POSIX process only;
    elsewhere only the size limit and the total apply."""

    def __init__(self) -> None:
        self.left = TOTAL_SECONDS

    def run(self, fn: Any, expr: sp.Expr) -> sp.Expr | None:
        import signal
        import threading
        import time

        if self.left <= 0:
            return None
        timed = hasattr(signal, "setitimer") and threading.current_thread() is threading.main_thread()
        t0 = time.perf_counter()
        old = None
        if timed:
            def _stop(signum: int, frame: Any) -> None:
                raise _Timeout

            old = signal.signal(signal.SIGALRM, _stop)
            signal.setitimer(signal.ITIMER_REAL, min(ENTRY_SECONDS, self.left))
        try:
            return fn(expr)
        except (_Timeout, RecursionError, sp.PolynomialError, TypeError, ValueError, NotImplementedError):
            return None  # SymPy gave up or the clock ran out: show the entry as tidied
        finally:
            if timed:
                signal.setitimer(signal.ITIMER_REAL, 0)
                signal.signal(signal.SIGALRM, old)
            self.left -= time.perf_counter() - t0


_BUDGET = _Budget()
_SHOWN: dict[sp.Expr, sp.Expr] = {}


def _sin2(e: sp.Expr) -> sp.Expr:
    """``sin²x → 1 − cos²x`` (then ``a² sin²x + a² cos²x`` cancels to ``a²`` on expansion)."""
    return e.replace(lambda t: t.is_Pow and t.exp == 2 and isinstance(t.base, sp.sin),
                     lambda t: 1 - sp.cos(t.base.args[0]) ** 2)


def _pythagoras(node: sp.Expr) -> sp.Expr:
    """One sum with ``sin² + cos²`` cancelled and the result factored, if that is shorter."""
    if not node.is_Add or not node.has(sp.sin) or sp.count_ops(node) > SIMPLIFY_OPS // 2:
        return node
    e = sp.expand(node)
    e2 = _sin2(e)
    if e2 == e:
        return node
    e = sp.expand(e2)
    best = min((sp.factor_terms(e), sp.factor(e)), key=sp.count_ops)
    return best if sp.count_ops(best) < sp.count_ops(node) else node


def _collected(expr: sp.Expr) -> sp.Expr:
    """The entry expanded, ``sin²`` cancelled, products of sines and cosines folded into sines and
    cosines of sums and differences (``sin a cos b − cos a sin b = sin(a − b)``), then collected
    by the squared velocities and by the trigonometric factors, each coefficient factored."""
    from sympy.simplify.fu import TR10i

    e = sp.expand(_sin2(sp.expand(expr)))
    rates = sorted((v for v in e.free_symbols if str(v).endswith("_dot")), key=sp.default_sort_key)
    # folding trigonometric products pairs terms (quadratic in their number): per coefficient of
    # the velocity products it pairs only terms that can fold together
    out = sp.Integer(0)
    for k, c in sp.collect(e, [v ** 2 for v in rates] + rates, evaluate=False).items():
        c = TR10i(c)
        trig = sorted(c.atoms(sp.sin, sp.cos), key=sp.default_sort_key)
        out += k * (sp.collect(sp.expand(c), trig, func=sp.factor) if trig else sp.factor(c))
    return out


def show(expr: Any) -> sp.Expr:
    """An entry as ``amble equations`` shows it: the shortest of :func:`tidy`'s form, the form
    with every ``sin² + cos²`` cancelled inside its sums, and the collected form
    (:func:`_collected`), within a time budget. Display only: the compiled code is generated from
    the expressions as derived, and the simplified entry is the same function."""
    expr = sp.sympify(expr)
    hit = _SHOWN.get(expr)
    if hit is not None:
        return hit
    best = tidy(expr)
    if isinstance(expr, sp.core.relational.Relational):  # an enabling condition: each side
        best = expr.func(show(expr.lhs), show(expr.rhs))
        _SHOWN[expr] = best
        return best
    if not isinstance(expr, sp.Expr) or isinstance(expr, (sp.Piecewise, sp.logic.boolalg.Boolean)):
        return best  # other conditions and piecewise laws: shown as tidied
    if expr.has(sp.sin, sp.cos) and sp.count_ops(expr) <= SIMPLIFY_OPS:
        for fn in (lambda e: e.replace(lambda n: n.is_Add, _pythagoras), _collected):
            cand = _BUDGET.run(fn, expr)
            if cand is not None and sp.count_ops(cand) < sp.count_ops(best):
                best = cand
    _SHOWN[expr] = best
    return best


def _text(expr: Any) -> str:
    return sp.sstr(show(expr))


def _latex(matrix: sp.Matrix, names: dict) -> str:
    """LaTeX of a matrix of shown entries (:func:`show`) with typeset names."""
    return sp.latex(matrix.applyfunc(show).subs(names))


def _rows(matrix: sp.Matrix) -> list[list[str]]:
    return [[_text(matrix[i, j]) for j in range(matrix.cols)] for i in range(matrix.rows)]


def _guard(tr, names: dict) -> dict[str, Any]:
    g = tr.guard
    out = {"expr": _text(g.expr), "direction": g.direction, "when": _DIRECTION.get(g.direction, str(g.direction)),
           "enabled": None if g.enabled is None else _text(g.enabled)}
    out["latex"] = sp.latex(show(g.expr).subs(names))
    if getattr(tr, "forced", False):  # a contact's rest transition: no crossing of its own
        out.update(expr="none", latex=r"\text{none}",
                   when="taken when the contact's impacts accumulate or one leaves no normal velocity")
    return out


def _reset(system, tr, cache: dict) -> dict[str, Any] | None:
    """The derived (or written-out) reset of a transition, in matrix form."""
    reset = tr.reset
    if reset is None:
        return None
    src, dst = system.modes[tr.source], system.modes[tr.target]
    return {"type": type(reset).__name__, **reset.accept(_ResetDisplay(src, dst, cache[tr.source], tr.name))}


class _ResetDisplay(ResetVisitor[dict[str, Any]]):
    """A reset as the ``equations`` command shows it: matrices as text and as LaTeX."""

    def __init__(self, src: Any, dst: Any, equations: Any, name: str) -> None:
        self.src, self.dst, self.equations, self.what = src, dst, equations, f"transition {name!r}"
        self.names = latex_names(src)

    def impact(self, reset: Impact) -> dict[str, Any]:
        return {"point": reset.point, **self.impulsive(reset)}

    def lock(self, reset: Lock) -> dict[str, Any]:
        return {"constraint": _text(reset.constraint), **self.impulsive(reset)}

    def impulsive(self, reset: Impact | Lock) -> dict[str, Any]:
        src, dst, names = self.src, self.dst, self.names
        data = impulse_data(src, self.equations, reset, dst, what=self.what)
        n = len(src.q)
        base = [f"base_{axis}_dot" for axis in "xyz"[: data.Me.rows - n]]
        return {
            "form": "M_e (qd_e+ - qd_e-) = J^T lambda,  J qd_e+ = 0,  qd_new = (dr/dq) qd+",
            "extended_velocities": [str(v) for v in src.qd] + base,
            "Me": _rows(data.Me), "J": _rows(data.Jc),
            "relabel": {str(d): _text(e) for d, e in zip(dst.q, data.q_new)},
            "velocity_map": _rows(data.velocity_map),
            "latex": {"Me": _latex(data.Me, names), "J": _latex(data.Jc, names),
                      "relabel": _latex(sp.Matrix(data.q_new), names),
                      "velocity_map": _latex(data.velocity_map, names)},
        }

    def explicit(self, reset: Explicit) -> dict[str, Any]:
        src, dst, names = self.src, self.dst, self.names
        q_new = target_exprs(dst, reset.q, self.what, source=src)
        qd_new = target_exprs(dst, reset.qd, self.what, velocities=True, source=src)
        return {"relabel": {str(d): _text(e) for d, e in zip(dst.q, q_new)},
                "velocities": {str(d): _text(e) for d, e in zip(dst.qd, qd_new)},
                "latex": {"relabel": _latex(sp.Matrix(q_new), names),
                          "velocities": _latex(sp.Matrix(qd_new), names)}}


def _mode_latex(model: Any, eq: Any) -> dict[str, str]:
    """The LaTeX of one mode's ``M(q) q̈ + h(q, q̇) = Γ``, piece by piece (entries :func:`show`n)."""
    names = latex_names(model)
    qdd = [sp.Symbol(str(names[v]).replace(r"\dot{", r"\ddot{", 1)) for v in model.qd]
    out = {"M": _latex(eq.M, names), "h": _latex(eq.h, names), "Gamma": _latex(eq.Gamma, names),
           "q": sp.latex(sp.Matrix(model.q).subs(names)), "qdd": sp.latex(sp.Matrix(qdd))}
    if eq.inputs:
        out["B"] = _latex(eq.B, names)
    return out


def cmd_equations(args: argparse.Namespace) -> dict[str, Any]:
    if getattr(args, "standalone", False):
        args.latex = True
    s = load_model(args.model, **robot_options(args))
    out: dict[str, Any] = {"model": args.model, "modes": {}}
    derived = {}
    for mname, m in s.modes.items():
        eq = derived[mname] = derive(m)
        entry = {
            "coordinates": [str(q) for q in m.q],
            "velocities": [str(v) for v in m.qd],
            "parameters": {str(k): v for k, v in m.params.items()},
            "mass_matrix": _rows(eq.M),
            "bias": [_text(e) for e in eq.h],
            "generalized_force": [_text(e) for e in eq.Gamma],
            "gravity_vector": [sp.sstr(e) for e in m.gravity_vector],
            "operation_count": eq.count_ops(),
        }
        if eq.inputs:  # an actuated mode: the inputs, B, and how each is controlled
            entry["inputs"] = [str(u) for u in eq.inputs]
            entry["input_matrix"] = _rows(eq.B)
            entry["input_limits"] = m.input_limits
            entry["control"] = ("hybrid zero dynamics" if m.virtual is not None else
                                [_text(e) for e in m.control_law])
        if eq.holonomic is not None:  # held by φ(q) = 0: M q̈ + h = Γ + Jᵀλ
            entry["constraints"] = {n: _text(e) for n, e in zip(eq.holonomic.names, eq.holonomic.phi)}
        if args.latex:
            entry["latex_parts"] = _mode_latex(m, eq)
            parts = entry["latex_parts"]
            entry["latex"] = f"{parts['M']}\\,{parts['qdd']} + {parts['h']} = {parts['Gamma']}"
        out["modes"][mname] = entry
    first = next(iter(out["modes"].values()))
    out.update({k: first[k] for k in ("coordinates", "parameters", "mass_matrix", "bias", "gravity_vector")})
    out["transitions"] = []
    for tr in s.transitions:
        reset = _reset(s, tr, derived)
        guard = _guard(tr, latex_names(s.modes[tr.source]))
        if not args.latex:
            guard.pop("latex")
            if reset:
                reset.pop("latex")
        out["transitions"].append({"name": tr.name, "source": tr.source, "target": tr.target,
                                   "reset": reset["type"] if reset else None, "terminal": tr.terminal,
                                   "guard": guard["expr"], "guard_detail": guard, "map": reset})
    if getattr(args, "standalone", False):
        out["document"] = standalone(out)
    if not args.json:
        if getattr(args, "standalone", False):
            print(out["document"], end="")
        else:
            _print(out, args.latex)
    return out


def _print(out: dict[str, Any], latex: bool) -> None:
    for mname, e in out["modes"].items():
        print(f"mode {mname}: q = ({', '.join(e['coordinates'])})")
        if latex:
            for label, line in _latex_lines(e["latex_parts"]):
                print(f"  {label} = {line}")
        else:
            for i, row in enumerate(e["mass_matrix"]):
                print(f"  M[{i}] = [{', '.join(row)}]")
            for i, b in enumerate(e["bias"]):
                print(f"  h[{i}] = {b}")
            if any(g != "0" for g in e["generalized_force"]):
                for i, g in enumerate(e["generalized_force"]):
                    print(f"  Gamma[{i}] = {g}")
            if "inputs" in e:
                print(f"  inputs u = ({', '.join(e['inputs'])}), B = {e['input_matrix']}")
                print(f"  control: {e['control']}")
        for name, phi in e.get("constraints", {}).items():
            print(f"  constraint {name}: {phi} = 0  (M q̈ + h = Γ + Jᵀλ)")
        print(f"  operations (shared subexpressions): {e['operation_count']}")
    for tr in out["transitions"]:
        g = tr["guard_detail"]
        print(f"transition {tr['name']}: {tr['source']} -> {tr['target']} ({tr['reset'] or tr['terminal']})")
        print(f"  guard: {g['latex'] if latex else g['expr']}, {g['when']}"
              + (f", when {g['enabled']}" if g["enabled"] else ""))
        r = tr["map"]
        if r is None:
            continue
        if "Me" in r:
            what = f"impact of {r['point']}" if "point" in r else f"lock {r['constraint']} = 0"
            print(f"  {what}: {r['form']}")
            print(f"    qd_e = ({', '.join(r['extended_velocities'])})")
            if latex:
                for k in ("Me", "J", "relabel", "velocity_map"):
                    print(f"    {k} = {r['latex'][k]}")
                continue
            for i, row in enumerate(r["Me"]):
                print(f"    M_e[{i}] = [{', '.join(row)}]")
            for i, row in enumerate(r["J"]):
                print(f"    J[{i}] = [{', '.join(row)}]")
            print("    relabel: " + ", ".join(f"{k} <- {v}" for k, v in r["relabel"].items()))
            for i, row in enumerate(r["velocity_map"]):
                print(f"    dr/dq[{i}] = [{', '.join(row)}]")
        else:
            if latex:
                print(f"    q <- {r['latex']['relabel']}\n    qd <- {r['latex']['velocities']}")
                continue
            print("    q: " + ", ".join(f"{k} <- {v}" for k, v in r["relabel"].items()))
            print("    qd: " + ", ".join(f"{k} <- {v}" for k, v in r["velocities"].items()))


def _latex_lines(parts: dict[str, str]) -> list[tuple[str, str]]:
    """A mode's equation and its labelled pieces, as (label, LaTeX) pairs."""
    inputs = " + B u" if "B" in parts else ""
    lines = [(r"\ddot{q}", parts["qdd"]), ("M(q)", parts["M"]), (r"h(q, \dot{q})", parts["h"])]
    if parts["Gamma"] != sp.latex(sp.zeros(*_shape(parts["Gamma"]))):
        lines.append((r"\Gamma", parts["Gamma"]))
    if "B" in parts:
        lines.append(("B", parts["B"]))
    lines.append(("equation", rf"M(q)\,\ddot{{q}} + h(q, \dot{{q}}) = \Gamma{inputs}"))
    return lines


def _shape(matrix_latex: str) -> tuple[int, int]:
    body = matrix_latex.split(r"\begin{matrix}", 1)[-1].split(r"\end{matrix}", 1)[0]
    rows = body.split(r"\\")
    return len(rows), len(rows[0].split("&"))


def _tex(text: str) -> str:
    """Plain text set in LaTeX (names with underscores, arrows)."""
    table = {"\\": r"\textbackslash{}", "_": r"\_", "&": r"\&", "%": r"\%", "#": r"\#", "$": r"\$",
             "{": r"\{", "}": r"\}", "~": r"\textasciitilde{}", "^": r"\textasciicircum{}"}
    return "".join(table.get(c, c) for c in text)


_PREAMBLE = r"""\documentclass[10pt]{article}
\usepackage[landscape, margin=1.5cm]{geometry}
\usepackage{amsmath}
\setcounter{MaxMatrixCols}{64}
\allowdisplaybreaks
\begin{document}
"""


def standalone(out: dict[str, Any]) -> str:
    """A LaTeX document (``pdflatex`` compiles it as it is) of every mode's labelled equations and
    every transition's guard and map; wide matrices run past the margin rather than break."""
    doc = [_PREAMBLE, rf"\section*{{Equations of {_tex(str(out['model']))}}}", ""]
    for mname, e in out["modes"].items():
        doc += [rf"\subsection*{{Mode {_tex(mname)}}}", "",
                rf"Coordinates $q = ({', '.join(_tex(c) for c in e['coordinates'])})$.", ""]
        for label, line in _latex_lines(e["latex_parts"]):
            doc += [r"\[", line if label == "equation" else f"{label} = {line}", r"\]"]
        doc.append("")
    for tr in out["transitions"]:
        g = tr["guard_detail"]
        doc += [rf"\subsection*{{Transition {_tex(tr['name'])}: {_tex(tr['source'])} $\to$ {_tex(tr['target'])}}}",
                "", rf"Guard ${g['latex']}$, {_tex(g['when'])}"
                + (rf", when \texttt{{{_tex(g['enabled'])}}}" if g["enabled"] else "") + ".", ""]
        r = tr["map"]
        if r is None:
            continue
        if "Me" in r:
            what = f"impact of {r['point']}" if "point" in r else f"lock {r['constraint']} = 0"
            doc += [_tex(what) + r": $M_e (\dot{q}_e^+ - \dot{q}_e^-) = J^T \lambda$, $J \dot{q}_e^+ = 0$.", ""]
            keys = (("Me", "M_e"), ("J", "J"), ("relabel", r"q^+"), ("velocity_map", r"\partial r / \partial q"))
        else:
            keys = (("relabel", r"q^+"), ("velocities", r"\dot{q}^+"))
        for k, label in keys:
            doc += [r"\[", f"{label} = {r['latex'][k]}", r"\]"]
        doc.append("")
    doc.append(r"\end{document}")
    return "\n".join(doc) + "\n"
