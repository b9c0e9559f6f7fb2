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

import sympy as sp

from ..errors import ModelError
from ..modelling.model import Model, t
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

    def count_ops(self) -> int:
        """Arithmetic operations needed to evaluate M, h and Γ with common subexpressions shared."""
        if self.compact is not None:
            defs, M, h = self.compact
            return int(sum(sp.count_ops(e) for _, e in defs)) + count_ops_cse([*M, *h, *self.Gamma])
        return count_ops_cse([*self.M, *self.h, *self.Gamma])

    def latex(self, display: bool = False) -> str:
        """LaTeX of ``M(q) q̈ + h(q, q̇) = Γ`` with the matrices written out."""
        names = {s: sp.Symbol(_latex_name(str(s))) for s in self.q}
        names.update({v: sp.Symbol(r"\dot{" + _latex_name(str(s)) + "}") for s, v in zip(self.q, self.qd)})
        names.update({a: sp.Symbol(r"\ddot{" + _latex_name(str(s)) + "}") for s, a in zip(self.q, self.qdd)})
        m = sp.latex(self.M.subs(names))
        qdd = sp.latex(sp.Matrix(self.qdd).subs(names))
        h = sp.latex(self.h.subs(names))
        g = sp.latex(self.Gamma.subs(names))
        body = f"{m}\\,{qdd} + {h} = {g}"
        return f"$${body}$$" if display else body

    def _repr_latex_(self) -> str:
        """Jupyter shows ``derive(model)`` as the typeset equations."""
        return self.latex(display=True)


def _latex_name(name: str) -> str:
    greek = {"theta", "phi", "psi", "alpha", "beta", "gamma", "tau", "omega"}
    base, _, sub = name.partition("_")
    base_tex = "\\" + base if base in greek else base
    return f"{base_tex}_{{{sub}}}" if sub else base_tex


def derive(model: Model) -> Equations:
    """Derive ``M``, ``h`` and ``Γ`` of a model from its Lagrangian (no simplification).

    Point masses take the Jacobian route, which needs no derivative of the (large) kinetic
    energy: with ``vᵢ = Jᵢ q̇`` and the convective acceleration ``aᵢ = (∂vᵢ/∂q) q̇``,
    ``M = Σ mᵢ JᵢᵀJᵢ`` and ``h = Σ mᵢ Jᵢᵀaᵢ + ∂V/∂q``. Every other energy term (rotational
    inertia, added terms, or ``K``/``V``/``L`` given outright) goes through the general
    Euler–Lagrange expansion above. Both routes give the same equations. The bodies of a
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
            extra = sum(model._k_terms, sp.Integer(0))
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
    return Equations(model=model, M=M, h=h, Gamma=model.generalized_force, K=K, V=V, energy=energy,
                     compact=compact)


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
