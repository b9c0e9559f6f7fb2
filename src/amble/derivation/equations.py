"""Equations of motion from the Lagrangian: ``M(q) q̈ + h(q, q̇, t) = Γ(q, q̇, t)``.

From ``L(q, q̇, t)`` (thesis Eq. 3–5) the Euler–Lagrange equations
``d/dt ∂L/∂q̇ − ∂L/∂q = Γ`` expand, with ``p = ∂L/∂q̇``, into

* ``M = ∂p/∂q̇``                     (the mass matrix, symmetric positive definite),
* ``h = (∂p/∂q) q̇ + ∂p/∂t − ∂L/∂q``  (Coriolis/centrifugal ``C q̇`` plus gravity ``G = ∂V/∂q``).

Nothing is expanded or simplified: sympy differentiates the unexpanded energy, and common
subexpressions are shared when code is generated. The size of the result therefore grows
polynomially with the number of coordinates (see :meth:`Equations.count_ops`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property, lru_cache
from typing import Any

import sympy as sp

from ..errors import ModelError
from ..modelling.model import Model, t
from .holonomic import Holonomic, holonomic_terms, refuse_constrained
from .hzd import hzd_law
from .tree import tree_dynamics


@dataclass
class Equations:
    """Derived equations of one model. All entries are sympy expressions in q, q̇, t, params."""

    model: Model
    M: sp.Matrix
    h: sp.Matrix
    Gamma: sp.Matrix
    K: sp.Expr | None
    V: sp.Expr | None
    energy: sp.Expr
    _qdd: list[sp.Symbol] = field(default_factory=list)
    #: the same ``M`` and ``h`` written with named intermediate quantities (a rigid-body tree's
    #: recursion): ``(definitions, M, h)``, definitions as ``(symbol, expression)`` in order —
    #: code generation prints these instead of searching the expanded ones for common parts
    compact: tuple[list[tuple[sp.Symbol, sp.Expr]], sp.Matrix, sp.Matrix] | None = None
    #: the input matrix (n × nu; ``∂on_j/∂q`` per column) and the input symbols, in declaration order
    B: sp.Matrix | None = None
    inputs: list[sp.Symbol] = field(default_factory=list)
    #: the closed-loop law of every input (nu × 1, zero where none; ``M`` and ``h`` substituted)
    u: sp.Matrix | None = None
    #: the mode's holonomic constraints ``φ``, ``J = ∂φ/∂q``, ``γ = −J̇ q̇`` (None: unconstrained);
    #: the motion is then ``M q̈ + h = Γ + Jᵀλ``, ``J q̈ = γ`` (:mod:`amble.derivation.holonomic`)
    holonomic: Holonomic | None = None

    @cached_property
    def closed_loop_force(self) -> sp.Matrix:
        """``Γ + B u(q, q̇, t)``: the generalized force the compiled right-hand side uses
        (``Gamma`` stays the passive force)."""
        if self.B is None or self.B.cols == 0 or self.u is None:
            return self.Gamma
        return self.Gamma + self.B * self.u

    @property
    def q(self) -> list[sp.Symbol]:
        return self.model.q

    @property
    def qd(self) -> list[sp.Symbol]:
        return self.model.qd

    @property
    def qdd(self) -> list[sp.Symbol]:
        """Acceleration symbols ``<coordinate>_ddot`` (for display of the residual form)."""
        if not self._qdd:
            self._qdd = [sp.Symbol(f"{s}_ddot", real=True) for s in self.model.q]
        return self._qdd

    @property
    def G(self) -> sp.Matrix:
        """Gravity (potential) term ``∂V/∂q``; with ``L`` given outright, ``h`` at ``q̇ = 0``."""
        if self.V is not None:
            return sp.Matrix([self.model.diff(self.V, qi) for qi in self.q])
        return self.h.subs({v: 0 for v in self.qd})

    @property
    def coriolis(self) -> sp.Matrix:
        """The velocity-dependent part of the bias: ``C(q, q̇) q̇ = h − G``."""
        return self.h - self.G

    def residual(self) -> sp.Matrix:
        """``M q̈ + h − Γ``: the Euler–Lagrange residual d/dt ∂L/∂q̇ − ∂L/∂q − Γ."""
        return self.M * sp.Matrix(self.qdd) + self.h - self.Gamma

    def expanded(self, expr: Any) -> Any:
        """``expr`` with the named intermediate quantities of ``compact`` substituted (last first),
        an expression of the state, time and parameters only."""
        if self.compact is None:
            return expr
        for s, e in reversed(self.compact[0]):
            expr = expr.xreplace({s: e})
        return expr

    def count_ops(self) -> int:
        """Arithmetic operations needed to evaluate M, h and Γ with common subexpressions shared."""
        if self.compact is not None:
            defs, M, h = self.compact
            return int(sum(sp.count_ops(e) for _, e in defs)) + count_ops_cse([*M, *h, *self.Gamma])
        return count_ops_cse([*self.M, *self.h, *self.Gamma])

    def latex(self, display: bool = False) -> str:
        """LaTeX of ``M(q) q̈ + h(q, q̇) = Γ`` with the matrices written out, entries tidied as
        :func:`tidy` does for the plain-text display and names typeset by :func:`latex_names`."""
        names = latex_names(self.model)
        names.update({a: sp.Symbol(_typeset(str(s), self.model, "ddot")) for s, a in zip(self.q, self.qdd)})
        m = latex_matrix(self.M, names)
        qdd = sp.latex(sp.Matrix(self.qdd).subs(names))
        h = latex_matrix(self.h, names)
        g = latex_matrix(self.Gamma, names)
        body = f"{m}\\,{qdd} + {h} = {g}"
        return f"$${body}$$" if display else body

    def _repr_latex_(self) -> str:
        """Jupyter shows ``derive(model)`` as the typeset equations."""
        return self.latex(display=True)


TIDY_OPS = 60  # entries up to this many operations are tidied for display (trigsimp costs seconds beyond)


def tidy(expr: sp.Expr) -> sp.Expr:
    """An entry as displayed: small ones tidied with ``trigsimp`` (``sin² + cos²`` → 1), large ones
    as derived. Display only — the compiled code is generated from the unexpanded expressions."""
    return _tidy(sp.sympify(expr))


@lru_cache(maxsize=4096)
def _tidy(expr: sp.Expr) -> sp.Expr:
    # cached: the same entries recur across modes and in the impact maps (M inside M_e)
    return sp.trigsimp(expr) if sp.count_ops(expr) <= TIDY_OPS else expr


def latex_matrix(matrix: sp.Matrix, names: dict) -> str:
    """LaTeX of a matrix with every entry tidied (:func:`tidy`) and its symbols renamed."""
    return sp.latex(matrix.applyfunc(tidy).subs(names))


_GREEK = {"alpha", "beta", "gamma", "delta", "epsilon", "zeta", "eta", "theta", "iota", "kappa", "lambda",
          "mu", "nu", "xi", "pi", "rho", "sigma", "tau", "upsilon", "phi", "chi", "psi", "omega",
          "Gamma", "Delta", "Theta", "Lambda", "Xi", "Pi", "Sigma", "Upsilon", "Phi", "Psi", "Omega"}
_ANGLE_UNITS = {"", "rad", "deg", "°"}


def latex_names(model: Model) -> dict[sp.Symbol, sp.Symbol]:
    """Typeset names of a model's coordinates, velocities and parameters, as symbols to substitute.

    A name is split at its first ``_`` into a base and a subscript. A base that names a Greek letter
    is that letter (``theta_1`` → ``\\theta_{1}``), a one-letter base stays (``x_stance`` →
    ``x_{\\mathrm{stance}}``). A coordinate with a longer base becomes ``\\theta`` (angle or no
    declared unit) or ``q`` (another unit) subscripted with its whole name: ``stance`` →
    ``\\theta_{\\mathrm{stance}}``, its velocity ``\\dot{\\theta}_{\\mathrm{stance}}``. A parameter
    with a longer base is set upright: ``slope`` → ``\\mathrm{slope}``."""
    out: dict[sp.Symbol, sp.Symbol] = {}
    for s, v in zip(model.q, model.qd):
        out[s] = sp.Symbol(_typeset(str(s), model, ""))
        out[v] = sp.Symbol(_typeset(str(s), model, "dot"))
    for p in model.params:
        out[p] = sp.Symbol(_typeset(str(p), None, ""))
    return out


def _sub(text: str) -> str:
    return text if len(text) == 1 or text.isdigit() else r"\mathrm{" + text.replace("_", r"\_") + "}"


def _typeset(name: str, model: Model | None, accent: str) -> str:
    base, _, sub = name.partition("_")
    if not sub and len(base) > 1 and base[0].isalpha() and base[1:].isdigit():  # a1 → a_{1}
        base, sub = base[0], base[1:]
    if base in _GREEK or len(base) == 1:
        head = ("\\" + base) if base in _GREEK else base
    elif model is not None:  # a coordinate: a letter with the whole name as subscript
        head = r"\theta" if model.unit(name) in _ANGLE_UNITS else "q"
        sub = name
    else:
        return _sub(name)
    if accent:
        head = f"\\{accent}{{{head}}}"
    return f"{head}_{{{_sub(sub)}}}" if sub else head


def derive(model: Model, control: bool = True) -> Equations:
    """Derive ``M``, ``h`` and ``Γ`` of a model from its Lagrangian (no simplification).

    ``control=False`` leaves out the HZD feedback law of a model with virtual constraints (its
    symbolic derivation is most of the time for RABBIT); ``u`` is then the declared control law
    without it. An optimisation that treats the inputs as unknowns needs only ``M``, ``h``, ``Γ``, ``B``.

    Point masses take the Jacobian route, which needs no derivative of the (large) kinetic
    energy: with ``vᵢ = Jᵢ q̇`` and the convective acceleration ``aᵢ = (∂vᵢ/∂q) q̇``,
    ``M = Σ mᵢ JᵢᵀJᵢ`` and ``h = Σ mᵢ Jᵢᵀaᵢ + ∂V/∂q``. So does a body's rotational inertia
    (``body_inertia``), in Kane's form: with its body-axes angular velocity ``ω = J_ω q̇`` and
    ``α = (∂ω/∂q) q̇``, ``M += J_ωᵀ I J_ω`` and ``h += J_ωᵀ (I α + ω × I ω)`` (Euler's equations in
    body axes). Every other energy term (added terms, or ``K``/``V``/``L`` given outright) goes
    through the general Euler–Lagrange expansion above. Both routes give the same equations. The bodies of a
    rigid-body tree (``model.rigid_tree()``) take a third route, by recursion over the tree
    (:mod:`amble.derivation.tree`: composite rigid bodies for ``M``, Newton–Euler for ``h``).
    """
    model.validate()
    q, qd = model.q, model.qd
    n = len(q)
    M = sp.zeros(n, n)
    h = sp.zeros(n, 1)
    Mt = ht = None
    given_l = model._l_override is not None
    if given_l:
        _add_lagrangian_terms(model.L, q, qd, M, h)
    else:
        if model._k_override is not None:
            _add_lagrangian_terms(model._k_override, q, qd, M, h)
        else:
            if model.tree is not None:
                Mt, ht = tree_dynamics(model.tree, model.gravity_vector)
            _add_point_masses(model, M, h)
            extra = sum(_add_spins(model, M, h), sp.Integer(0))
            if extra != 0:
                _add_lagrangian_terms(extra, q, qd, M, h)
        V = _potential_outside_tree(model) if model._k_override is None else model.V
        for i in range(n):
            h[i] += model.diff(V, q[i])
    K = None if given_l else model.K
    V = None if given_l else model.V
    if given_l:
        lag = model.L
        energy = sum((v * sp.diff(lag, v) for v in qd), sp.Integer(0)) - lag
    else:
        # E = K + V is what is conserved when Γ = 0 and nothing depends on t explicitly.
        energy = K + V
    compact = None
    if Mt is not None:
        defs = model.tree.defs
        compact = (defs.needed([*Mt, *ht]), M + Mt, h + ht)
        M, h = M + defs.expand(Mt), h + defs.expand(ht)
    B, Gamma = model.input_matrix(), model.generalized_force
    if model.held:
        M, h, Gamma, B, compact = _hold(model, M, h, Gamma, B, compact)
    u = model.control_law
    if model.derived_placeholders and u.rows:
        subs = {s: (M if kind == "M" else h)[i, j] for s, (kind, i, j) in model.derived_placeholders.items()}
        u = u.xreplace(subs)
    if model.virtual is not None and control:  # the HZD law, as named intermediate quantities after the tree's
        refuse_constrained(model, "the HZD input–output linearising law")
        defs, Mc, hc = compact if compact is not None else ([], M, h)
        hdefs, u = hzd_law(model, Mc, hc, model.generalized_force, B)
        if model.saturated:
            u = sp.Matrix([e if a.limit is None else sp.Max(-a.limit, sp.Min(a.limit, e))
                           for e, a in zip(u, model.actuators)])
        compact = ([*defs, *hdefs], Mc, hc)
    return Equations(model=model, M=M, h=h, Gamma=Gamma, K=K, V=V, energy=energy,
                     compact=compact, B=B, inputs=model.inputs, u=u, holonomic=holonomic_terms(model))


def _hold(model: Model, M: sp.Matrix, h: sp.Matrix, Gamma: sp.Matrix, B: sp.Matrix, compact: Any
          ) -> tuple[sp.Matrix, sp.Matrix, sp.Matrix, sp.Matrix, Any]:
    """The equations with each held coordinate's row replaced by ``q̈ᵢ = 0`` (``Model.hold``).

    Its column of ``M`` multiplies ``q̈ᵢ = 0`` in the other rows and is cleared with the row, so
    ``M`` stays symmetric (the compiled code factors it as such); its terms in ``h`` of the other
    rows are those of a constant with zero velocity."""
    if model.virtual is not None:
        raise ModelError(f"model {model.name!r}: held coordinates and virtual constraints cannot be combined")
    idx = [model.q.index(qi) for qi in model.held]

    def held(Mx: sp.Matrix, hx: sp.Matrix) -> tuple[sp.Matrix, sp.Matrix]:
        Mx, hx = Mx.copy(), hx.copy()
        for i in idx:
            Mx[i, :] = sp.zeros(1, Mx.cols)
            Mx[:, i] = sp.zeros(Mx.rows, 1)
            Mx[i, i] = sp.Integer(1)
            hx[i] = sp.Integer(0)
        return Mx, hx

    M, h = held(M, h)
    Gamma, B = Gamma.copy(), B.copy()
    for i in idx:
        Gamma[i] = sp.Integer(0)
        if B.cols:
            B[i, :] = sp.zeros(1, B.cols)
    if compact is not None:
        compact = (compact[0], *held(compact[1], compact[2]))
    return M, h, Gamma, B, compact


def _add_point_masses(model: Model, M: sp.Matrix, h: sp.Matrix) -> None:
    q, qd = model.q, model.qd
    qd_vec = sp.Matrix(qd)
    n = len(q)
    for name, m in model.masses.items():
        if model.tree is not None and name in model.tree.com_points:
            continue  # the tree's bodies are in tree_dynamics
        pos = model.points[name]
        J = model.jacobian(pos)
        if t in pos.free_symbols:
            raise ModelError(f"model {model.name!r}: point mass {name!r} moves explicitly with t")
        v = J * qd_vec
        a = sp.zeros(pos.rows, 1)
        for k in range(n):
            dv = v.applyfunc(lambda e, qk=q[k]: model.diff(e, qk))
            if any(e != 0 for e in dv):
                a += dv * qd[k]
        for i in range(n):
            for j in range(i, n):
                mij = m * (J[:, i].T * J[:, j])[0, 0]
                if mij != 0:
                    M[i, j] += mij
                    if j != i:
                        M[j, i] += mij
            hi = m * (J[:, i].T * a)[0, 0]
            if hi != 0:
                h[i] += hi


def _add_spins(model: Model, M: sp.Matrix, h: sp.Matrix) -> list[sp.Expr]:
    """Add the rotational inertia of ``body_inertia`` bodies to M and h by Kane's form (see
    :func:`derive`) and return the kinetic terms left for the Euler–Lagrange expansion: the
    Lagrangian route differentiates ½ ωᵀ I ω three times over, and its expression swells with the
    depth of a chain (a 7-link chain written so took most of a minute to derive)."""
    q, qd = model.q, model.qd
    rest = list(model._k_terms)
    for w, Im, term in getattr(model, "_spins", ()):
        Jw = w.jacobian(qd)
        # ω = Rᵀ Ṙ of a rotation R(q) is linear in q̇ with no other term; an inertia that moves
        # with q or t, or a rotation prescribed in t, takes the general route
        if Im.free_symbols & {t, *q, *qd} or Jw.free_symbols & {t, *qd} or t in w.free_symbols or term not in rest:
            continue
        rest.remove(term)
        alpha = sp.zeros(3, 1)
        for qk, vk in zip(q, qd):
            dw = w.applyfunc(lambda e, qk=qk: model.diff(e, qk))
            if any(e != 0 for e in dw):
                alpha += dw * vk
        Iw = Im * w
        torque = Im * alpha + w.cross(Iw)
        JI = Jw.T * Im
        for i in range(len(q)):
            for j in range(i, len(q)):
                mij = (JI[i, :] * Jw[:, j])[0, 0]
                if mij != 0:
                    M[i, j] += mij
                    if j != i:
                        M[j, i] += mij
            hi = (Jw[:, i].T * torque)[0, 0]
            if hi != 0:
                h[i] += hi
    return rest


def _potential_outside_tree(model: Model) -> sp.Expr:
    """``V`` without the gravity of the tree's bodies (which ``tree_dynamics`` includes in h)."""
    if model.tree is None or model._v_override is not None:
        return model.V
    gvec = model.gravity_vector
    v = sp.Integer(0)
    for name, m in model.masses.items():
        if name not in model.tree.com_points:
            v += -m * (gvec.T * model.points[name])[0, 0]
    return v + sum(model._v_terms, sp.Integer(0))


def _add_lagrangian_terms(lag: sp.Expr, q: list, qd: list, M: sp.Matrix, h: sp.Matrix) -> None:
    """Add the Euler–Lagrange terms of ``lag`` (a part of L) to M and h, in place."""
    n = len(q)
    p = [sp.diff(lag, v) for v in qd]
    for i in range(n):
        for j in range(i, n):
            mij = sp.diff(p[i], qd[j])
            if mij != 0:
                M[i, j] += mij
                if j != i:
                    M[j, i] += mij
        hi = sp.diff(p[i], t) - sp.diff(lag, q[i])
        for j in range(n):
            d = sp.diff(p[i], q[j])
            if d != 0:
                hi += d * qd[j]
        h[i] += hi


def count_ops_cse(exprs: list[sp.Expr]) -> int:
    """Operation count of a list of expressions after common-subexpression elimination."""
    repl, reduced = sp.cse(exprs, order="none")
    return int(sum(sp.count_ops(e) for _, e in repl) + sum(sp.count_ops(e) for e in reduced))
