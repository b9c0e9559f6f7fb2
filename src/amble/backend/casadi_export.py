"""SymPy → CasADi: amble's derived expressions as CasADi symbolic graphs (for NLP solvers).

The same expressions that :mod:`amble.backend.codegen` prints as C are rebuilt here, node by
node, as CasADi ``SX`` graphs: a sympy subexpression shared in the tree becomes one shared CasADi
node (the translation is memoised on the sympy node), so nothing is expanded and CasADi's
algorithmic differentiation gives exact, sparse first and second derivatives. Nothing is
re-derived: the mass matrix, bias, generalized force, impact data and guards come from
:mod:`amble.derivation` as they are.

CasADi is imported when a translation is first asked for, never by ``import amble`` (its import
costs about 0.5 s); a missing CasADi is a :class:`~amble.errors.ModelError` saying how to install it.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass
from functools import lru_cache
from typing import Any

import sympy as sp

from ..errors import ModelError
from ..modelling.text import expr_of


def casadi_module() -> Any:
    """The ``casadi`` module, or a :class:`ModelError` naming the install command."""
    try:
        import casadi
    except ImportError:  # pragma: no cover - casadi is installed with the 'optimise' extra
        raise ModelError("gait optimisation needs CasADi: pip install 'amble[optimise]' (or pip install casadi)"
                         ) from None
    return casadi


_UNARY = {
    sp.sin: "sin", sp.cos: "cos", sp.tan: "tan", sp.asin: "asin", sp.acos: "acos", sp.atan: "atan",
    sp.sinh: "sinh", sp.cosh: "cosh", sp.tanh: "tanh", sp.exp: "exp", sp.log: "log", sp.Abs: "fabs",
    sp.sign: "sign", sp.floor: "floor", sp.ceiling: "ceil", sp.erf: "erf",
}


class CasadiTranslator:
    """Translate sympy expressions into CasADi ``SX`` given the values of their symbols.

    ``symbols`` maps each sympy symbol that may occur to a CasADi scalar (an ``SX`` or ``MX``
    entry, or a number). Translations are memoised per sympy node for the life of the translator,
    so expressions that share subexpressions (``M`` inside ``M_e``, a guard built from a point)
    share CasADi nodes too. An unknown symbol or function is a :class:`ModelError`.
    """

    def __init__(self, symbols: Mapping[sp.Symbol, Any]) -> None:
        self.ca = casadi_module()
        self.symbols: dict[sp.Basic, Any] = dict(symbols)
        self._memo: dict[sp.Basic, Any] = {}

    def define(self, definitions: Iterable[tuple[sp.Symbol, sp.Expr]]) -> None:
        """Bind named intermediate quantities (e.g. :attr:`Equations.compact`), in order."""
        for s, e in definitions:
            self.symbols[s] = self(e)

    def matrix(self, m: Any) -> Any:
        """A sympy matrix (or sequence) as a CasADi matrix of the same shape (a sequence: a column)."""
        M = sp.Matrix(m)
        out = self.ca.SX.zeros(M.rows, M.cols) if not self._is_mx() else self.ca.MX.zeros(M.rows, M.cols)
        for i in range(M.rows):
            for j in range(M.cols):
                out[i, j] = self(M[i, j])
        return out

    def _is_mx(self) -> bool:
        return any(isinstance(v, self.ca.MX) for v in self.symbols.values())

    def __call__(self, expr: Any) -> Any:
        e = sp.sympify(expr)
        # a post-order walk with an explicit stack: deep expression trees must not hit the recursion limit
        memo, stack = self._memo, [(e, False)]
        while stack:
            node, ready = stack.pop()
            if node in memo:
                continue
            if node in self.symbols:
                memo[node] = self.symbols[node]
                continue
            if ready or not node.args or node.is_Number:
                memo[node] = self._node(node)
                continue
            stack.append((node, True))
            stack.extend((a, False) for a in _children(node) if a not in memo)
        return memo[e]

    def _node(self, e: sp.Basic) -> Any:
        ca, memo = self.ca, self._memo
        if e.is_Number or e in (sp.pi, sp.E) or e.is_NumberSymbol:
            if e.is_infinite or e is sp.nan:
                raise ModelError(f"cannot hand a non-finite number to the solver: {e}")
            return float(e)
        if e is sp.true:
            return 1.0
        if e is sp.false:
            return 0.0
        if isinstance(e, sp.Symbol):
            raise ModelError(f"symbol {e} has no value in the optimisation problem (not a coordinate, "
                             "velocity, input or parameter)")
        if isinstance(e, sp.Piecewise):
            out = float("nan")  # no branch holds: not a number, as in the generated C
            for val, cond in reversed(e.args):
                out = memo[val] if cond is sp.true else ca.if_else(memo[cond], memo[val], out)
            return out
        args = [memo[a] for a in e.args]
        for kind, op in _operations(ca):
            if isinstance(e, kind):
                return op(e, args)
        raise ModelError(f"no CasADi translation for {type(e).__name__} in {e}")


def _power(ca: Any, e: sp.Pow, args: list[Any]) -> Any:
    x = e.args[1]
    if x == sp.Rational(1, 2):
        return ca.sqrt(args[0])
    if x.is_Integer:
        k = int(x)
        return args[0] ** k if k > 0 else 1.0 / (args[0] ** (-k)) if k < 0 else 1.0
    return args[0] ** args[1]


@lru_cache(maxsize=4)
def _operations(ca: Any) -> tuple[tuple[type, Callable[[Any, list[Any]], Any]], ...]:
    """How each compound sympy node becomes CasADi, given its children's values (checked in this
    order: ``isinstance``, so a subclass finds its base's row)."""
    rows: list[tuple[type, Callable[[Any, list[Any]], Any]]] = [
        (sp.Add, lambda e, a: _fold(lambda u, v: u + v, a)),
        (sp.Mul, lambda e, a: _fold(lambda u, v: u * v, a)),
        (sp.Pow, lambda e, a: _power(ca, e, a)),
    ]
    unary = {f: getattr(ca, name) for f, name in _UNARY.items()}
    rows += [(f, lambda e, a, fn=fn: fn(a[0])) for f, fn in unary.items()]
    rows += [
        (sp.atan2, lambda e, a: ca.atan2(a[0], a[1])),
        (sp.Max, lambda e, a: _fold(ca.fmax, a)),
        (sp.Min, lambda e, a: _fold(ca.fmin, a)),
        (sp.Heaviside, lambda e, a: ca.if_else(a[0] > 0, 1.0, ca.if_else(a[0] < 0, 0.0, 0.5))),
    ]
    rel = {sp.StrictGreaterThan: ca.gt, sp.GreaterThan: ca.ge, sp.StrictLessThan: ca.lt,
           sp.LessThan: ca.le, sp.Equality: ca.eq, sp.Unequality: ca.ne}
    rows += [(r, lambda e, a, fn=f: fn(a[0], a[1])) for r, f in rel.items()]
    rows += [
        (sp.And, lambda e, a: _fold(ca.logic_and, a)),
        (sp.Or, lambda e, a: _fold(ca.logic_or, a)),
        (sp.Not, lambda e, a: ca.logic_not(a[0])),
    ]
    return tuple(rows)


def _children(e: sp.Basic) -> tuple:
    if isinstance(e, sp.Piecewise):  # its arguments are (value, condition) pairs
        return tuple(x for pair in e.args for x in pair)
    return e.args


def _fold(f: Any, args: list[Any]) -> Any:
    out = args[0]
    for a in args[1:]:
        out = f(out, a)
    return out


# ---------------------------------------------------------------------- one walking step
@dataclass
class StepFunctions:
    """CasADi functions of one step of a walker (one mode, one footfall transition back to it).

    Arguments: ``q``, ``qd``, ``a`` (accelerations), ``u`` (inputs), ``t`` (s), ``p`` (parameters
    in :attr:`param_names` order); ``qe`` is the extended post-impact velocity (``n`` coordinate
    rates then the ``dims`` base-velocity components), ``lam`` the impact impulse (N·s, world frame).

    * ``dynamics(q, qd, a, u, t, p)``: the residual ``M a + h − Γ − B u`` (N·m or N, ``n``);
    * ``contact(q, qd, a, p)``: the ground's force on the stance foot (N, world frame), from the
      rate of the total linear momentum: ``Σ mᵢ p̈ᵢ − mₜ g``;
    * ``impact(q, qd, qe, lam, p)``: ``M_e (qe − (q̇, 0)) − Jᵀλ`` and ``J qe`` (both zero at the
      derived plastic impact);
    * ``relabel(q, qe, p)``: the post-impact state of the next step, ``(r(q), (∂r/∂q) qe[:n])``;
    * ``guard(q, qd, p)``: the footfall's witness (m); ``enabled(q, qd, p)``: its enabling
      conditions as values that must be ≥ 0 (empty without one);
    * ``distance(q, p)``: how far the impacting point is ahead of the stance foot along the slope (m);
    * ``normal(p)``: the slope's unit normal; ``actuator_rates(q, qd, p)``: ``Bᵀ q̇`` (rad/s or m/s);
    * ``input_matrix(q, p)``: ``B`` (``n × nu``); ``phase(q, p)``: the phase variable ``θ`` of the
      gait's virtual constraints;
    * ``weight(p)``: ``mₜ |g|`` (N), the scale of the cost of transport;
    * ``outputs(q, p)``: the quantities held by a gait's virtual constraints (see the field).
    """

    n: int
    nu: int
    dims: int
    state_names: list[str]
    input_names: list[str]
    param_names: list[str]
    weight: Any
    dynamics: Any
    contact: Any
    impact: Any
    relabel: Any
    guard: Any
    enabled: Any
    distance: Any
    normal: Any
    actuator_rates: Any
    input_matrix: Any
    phase: Any
    phase_text: str
    integrand: Any = None
    #: ``outputs(q, p)``: the quantities the virtual constraints of a gait hold on Bézier
    #: polynomials — the model's declared outputs ``h₀(q)`` when it has virtual constraints
    #: (:meth:`Model.virtual_constraints`), else the actuated quantities ``Bᵀq``; with their texts
    outputs: Any = None
    output_texts: list[str] | None = None
    #: the names of the model's virtual-constraint parameters: ``alpha`` (rows of Bézier
    #: coefficient names), ``phase_start``, ``phase_end``, ``degree`` (None without them)
    virtual: dict[str, Any] | None = None


def _conditions(cond: Any) -> list[sp.Expr]:
    """An enabling condition as expressions that must be ≥ 0 (``a > b`` → ``a − b``)."""
    if cond is None or cond is sp.true:
        return []
    c = sp.sympify(cond)
    if isinstance(c, sp.And):
        return [e for a in c.args for e in _conditions(a)]
    if isinstance(c, (sp.StrictGreaterThan, sp.GreaterThan)):
        return [c.lhs - c.rhs]
    if isinstance(c, (sp.StrictLessThan, sp.LessThan)):
        return [c.rhs - c.lhs]
    raise ModelError(f"enabling condition {c} is not a comparison (or a conjunction of comparisons)")


def step_functions(system: Any, integrand: Any = None, phase: Any = None, transition: str | None = None
                   ) -> StepFunctions:
    """Export one step of a walker (:class:`~amble.modelling.walker.Walker`): a stance in one mode
    ended by a footfall ``transition`` (an :class:`~amble.modelling.hybrid.Impact`) into the next
    step's mode — the same mode for a walker that relabels its legs, the other stance foot's for a
    walker whose stance feet are modes. ``transition`` (its name) may be omitted for a one-mode
    walker with one footfall. ``relabel`` gives the state in the target mode's coordinates.

    ``integrand``: an optional sympy expression in the state, the inputs and the parameters,
    exported as ``integrand(q, qd, u, t, p)``. ``phase``: an expression of the coordinates that
    grows over a step (default: the hip's distance ahead of the stance foot along the slope),
    exported as ``phase(q, p)`` with its text in :attr:`StepFunctions.phase_text`. Inputs and
    ``B`` come from the model's actuators (``Equations.B``, ``Model.inputs``); a model without
    actuators has ``nu = 0``.
    """
    from ..derivation.equations import derive
    from ..derivation.holonomic import refuse_constrained
    from ..derivation.impact import impulse_data
    from ..modelling.contact import reaction
    from ..modelling.model import t as time

    ca = casadi_module()
    tr = _footfall(system, transition)
    if tr.reset is None or tr.reset.impact_point is None:
        raise ModelError(f"system {system.name!r}: the footfall {tr.name!r} must be an Impact (derived) reset, "
                         f"not {type(tr.reset).__name__}")
    m, target = system.modes[tr.source], system.modes[tr.target]
    refuse_constrained(m, "gait optimisation")
    eq = derive(m, control=False)  # the inputs are unknowns of the problem: no feedback law
    n, d = len(m.q), m.dims
    inputs = list(getattr(m, "inputs", []) or [])
    B = getattr(eq, "B", None)
    B = sp.zeros(n, 0) if B is None or not inputs else sp.Matrix(B)
    nu = len(inputs)
    pnames = [str(s) for s in m.params]
    q, qd, a = (ca.SX.sym(k, n) for k in ("q", "qd", "a"))
    u, tt, p = ca.SX.sym("u", nu), ca.SX.sym("t"), ca.SX.sym("p", len(pnames))
    qe, lam = ca.SX.sym("qe", n + d), ca.SX.sym("lam", d)
    syms: dict[sp.Symbol, Any] = {time: tt}
    syms.update({s: q[i] for i, s in enumerate(m.q)})
    syms.update({s: qd[i] for i, s in enumerate(m.qd)})
    syms.update({s: u[i] for i, s in enumerate(inputs)})
    syms.update({s: p[i] for i, s in enumerate(m.params)})
    T = CasadiTranslator(syms)
    if eq.compact is not None:  # a rigid-body tree: M and h with their named intermediate quantities
        defs, Mc, hc = eq.compact
        T.define(defs)
    else:
        Mc, hc = eq.M, eq.h
    res = T.matrix(Mc) @ a + T.matrix(hc) - T.matrix(eq.Gamma) - (T.matrix(B) @ u if nu else 0)
    args = [q, qd, a, u, tt, p]
    dynamics = ca.Function("dynamics", args, [res], ["q", "qd", "a", "u", "t", "p"], ["residual"])
    # the ground's force on the stance foot (amble.modelling.contact.reaction), differentiated
    # by CasADi: (Σ mᵢ pᵢ)¨ − (Σ mᵢ) g
    mt = reaction.total_mass(m)
    com = T.matrix(reaction.mass_moment(m))
    vel = ca.jtimes(com, q, qd)
    acc = ca.jtimes(vel, q, qd) + ca.jtimes(vel, qd, a)
    force = acc - T(mt) * T.matrix(m.gravity_vector)
    contact = ca.Function("contact", [q, qd, a, p], [force], ["q", "qd", "a", "p"], ["force"])
    imp = impulse_data(m, eq, tr.reset, target, f"reset of transition {tr.name!r}")
    Me, Jc = T.matrix(imp.Me), T.matrix(imp.Jc)
    pre = ca.vertcat(qd, ca.SX.zeros(d))
    impact = ca.Function("impact", [q, qd, qe, lam, p], [ca.vertcat(Me @ (qe - pre) - Jc.T @ lam, Jc @ qe)],
                         ["q", "qd", "qe", "lam", "p"], ["residual"])
    post = ca.vertcat(T.matrix(imp.q_new), T.matrix(imp.velocity_map) @ qe[:n])
    relabel = ca.Function("relabel", [q, qe, p], [post], ["q", "qe", "p"], ["x_next"])
    guard = ca.Function("guard", [q, qd, p], [T(tr.guard.expr)], ["q", "qd", "p"], ["g"])
    conds = _conditions(tr.guard.enabled)
    enabled = ca.Function("enabled", [q, qd, p], [ca.vertcat(*[T(c) for c in conds]) if conds else ca.SX(0, 1)])
    slope = expr_of(getattr(system, "slope", 0), what="slope")  # text is refused, never evaluated
    nvec = [sp.sin(slope), sp.cos(slope)] if d == 2 else [sp.sin(slope), 0, sp.cos(slope)]
    dvec = [sp.cos(slope), -sp.sin(slope)] if d == 2 else [sp.cos(slope), 0, -sp.sin(slope)]
    foot = m.points[tr.reset.impact_point]
    dist = sum((dvec[i] * foot[i] for i in range(d)), sp.Integer(0))
    distance = ca.Function("distance", [q, p], [T(dist)], ["q", "p"], ["distance"])
    normal = ca.Function("normal", [p], [T.matrix(nvec)], ["p"], ["n"])
    rates = ca.Function("actuator_rates", [q, qd, p], [T.matrix(B.T * sp.Matrix(m.qd)) if nu else ca.SX(0, 1)])
    vc = getattr(m, "virtual", None)
    if phase is None and vc is not None:  # the phase of the model's own controller
        phase = vc.phase
    if phase is None:
        hip = getattr(system, "hip", None)
        point = m.points[hip] if hip is not None else foot
        phase = sum((dvec[i] * point[i] for i in range(d)), sp.Integer(0))
    phase_fn = ca.Function("phase", [q, p], [T(phase)], ["q", "p"], ["theta"])
    f_int = None
    if integrand is not None:
        f_int = ca.Function("integrand", [q, qd, u, tt, p], [T(integrand)])
    input_matrix = ca.Function("input_matrix", [q, p], [T.matrix(B) if nu else ca.SX(n, 0)], ["q", "p"], ["B"])
    weight = ca.Function("weight", [p], [T(mt) * ca.norm_2(T.matrix(m.gravity_vector))], ["p"], ["weight"])
    # the controller's outputs when the model declares virtual constraints: the collocation then
    # holds the very quantities, phase and polynomial that the compiled HZD controller drives
    out_expr = list(vc.outputs) if vc is not None else list(B.T * sp.Matrix(m.q)) if nu else []
    outputs = ca.Function("outputs", [q, p], [T.matrix(out_expr) if out_expr else ca.SX(0, 1)], ["q", "p"], ["h0"])
    virtual = None
    if vc is not None:
        virtual = {"alpha": [[str(vc.alpha[i, k]) for k in range(vc.alpha.cols)] for i in range(vc.alpha.rows)],
                   "phase_start": str(vc.phase_start), "phase_end": str(vc.phase_end), "degree": vc.degree}
    return StepFunctions(n, nu, d, m.state_names, [str(s) for s in inputs], pnames, weight, dynamics, contact,
                         impact, relabel, guard, enabled, distance, normal, rates, input_matrix, phase_fn,
                         sp.sstr(phase), f_int, outputs, _output_texts(vc, B, m.q), virtual)


def _footfall(system: Any, name: str | None) -> Any:
    """The footfall transition of one step: ``name``'s, or a one-mode walker's only one; a
    :class:`ModelError` for a step that passes through other modes (a knee locking: one domain per
    step only) or a footfall that is not a step transition."""
    steps = [tr for tr in system.transitions if tr.step]
    if name is None:
        if len(system.modes) != 1 or len(steps) != 1:
            raise ModelError(f"system {system.name!r}: name the footfall transition of the step (modes "
                             f"{list(system.modes)}, footfall transitions {[tr.name for tr in steps]})")
        return steps[0]
    tr = next((t for t in steps if t.name == name), None)
    if tr is None:
        raise ModelError(f"system {system.name!r}: no footfall transition {name!r} (footfall transitions: "
                         f"{', '.join(t.name for t in steps) or 'none'})")
    others = [t.name for t in system.transitions
              if t.source == tr.source and not t.step and t.terminal is None and not t.forced]
    if others:
        raise ModelError(f"system {system.name!r}: gait optimisation needs one domain per step; mode "
                         f"{tr.source!r} also leaves by {', '.join(others)} before its footfall")
    return tr


def _output_texts(vc: Any, B: sp.Matrix, q: list) -> list[str]:
    """The outputs as text: the model's declared ones, else ``B_jᵀ q`` with numeric coefficients
    written as floats (``-1.0*stance + 1.0*swing``: read back by :func:`amble.parse`)."""
    if vc is not None:
        return [sp.sstr(e) for e in vc.outputs]
    coef = lambda b: sp.Float(b, 12) if b.is_number else b
    return [sp.sstr(sum((coef(B[i, j]) * q[i] for i in range(B.rows) if B[i, j] != 0), sp.Integer(0)))
            for j in range(B.cols)]
