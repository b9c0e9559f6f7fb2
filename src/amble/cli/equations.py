"""``amble equations``: the derived equations of motion of every mode, and every transition with
its guard and, for an impact or a joint lock, the derived impulsive map in matrix form
(``M_e``, ``J``, the relabelling and the velocity map) — as text, LaTeX, or JSON (with ``--latex``,
the JSON carries the LaTeX too)."""

from __future__ import annotations

import argparse
from typing import Any

import sympy as sp

from ..derivation.equations import derive, latex_matrix, latex_names, tidy
from ..derivation.impact import impulse_data
from ..modelling.hybrid import Explicit, Impact, Lock, ResetVisitor, target_exprs
from .args import load_model, robot_options

_DIRECTION = {-1: "falling through 0", 1: "rising through 0", 0: "crossing 0"}


def _text(expr: Any) -> str:
    return sp.sstr(tidy(expr))


def _rows(matrix: sp.Matrix) -> list[list[str]]:
    return [[_text(matrix[i, j]) for j in range(matrix.cols)] for i in range(matrix.rows)]


def _guard(tr, names: dict) -> dict[str, Any]:
    g = tr.guard
    out = {"expr": _text(g.expr), "direction": g.direction, "when": _DIRECTION.get(g.direction, str(g.direction)),
           "enabled": None if g.enabled is None else _text(g.enabled)}
    out["latex"] = sp.latex(tidy(g.expr).subs(names))
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
            "latex": {"Me": latex_matrix(data.Me, names), "J": latex_matrix(data.Jc, names),
                      "relabel": latex_matrix(sp.Matrix(data.q_new), names),
                      "velocity_map": latex_matrix(data.velocity_map, names)},
        }

    def explicit(self, reset: Explicit) -> dict[str, Any]:
        src, dst, names = self.src, self.dst, self.names
        q_new = target_exprs(dst, reset.q, self.what, source=src)
        qd_new = target_exprs(dst, reset.qd, self.what, velocities=True, source=src)
        return {"relabel": {str(d): _text(e) for d, e in zip(dst.q, q_new)},
                "velocities": {str(d): _text(e) for d, e in zip(dst.qd, qd_new)},
                "latex": {"relabel": latex_matrix(sp.Matrix(q_new), names),
                          "velocities": latex_matrix(sp.Matrix(qd_new), names)}}


def cmd_equations(args: argparse.Namespace) -> dict[str, Any]:
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
        if args.latex:
            entry["latex"] = eq.latex()
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
    if not args.json:
        _print(out, args.latex)
    return out


def _print(out: dict[str, Any], latex: bool) -> None:
    for mname, e in out["modes"].items():
        print(f"mode {mname}: q = ({', '.join(e['coordinates'])})")
        if latex:
            print(e["latex"])
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
