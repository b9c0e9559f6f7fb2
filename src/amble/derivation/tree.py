"""Equations of motion of a rigid-body tree by recursion: ``M`` by the composite-rigid-body
algorithm, ``h`` by recursive Newton–Euler with ``q̈ = 0`` (gravity included).

Everything is written in spatial vectors (Featherstone) expressed in the world frame at the world
origin, so no frame transformations between bodies are needed: a joint's motion subspace is
``Sᵢ = (zᵢ, aᵢ × zᵢ)`` for a revolute joint about axis ``zᵢ`` through the point ``aᵢ``, and
``(0, zᵢ)`` for a prismatic one; a body's spatial inertia is its mass ``m``, first moment
``m c`` and rotational inertia about the origin. With the world-frame kinematics of
:mod:`amble.modelling.tree` (each body's from its parent's only), the recursions are unrolled
symbolically:

* CRBA: composite inertias ``Iᶜᵢ = Iᵢ + Σ_children Iᶜ``; ``M_ij = S_jᵀ Iᶜᵢ Sᵢ`` for ``j`` an
  ancestor of ``i`` (or ``i``), zero otherwise.
* RNEA: ``Vᵢ = V_parent + Sᵢ q̇ᵢ``, ``Aᵢ = A_parent + Vᵢ × Sᵢ q̇ᵢ`` from ``A_base = −g``;
  ``Fᵢ = Iᵢ Aᵢ + Vᵢ ×* Iᵢ Vᵢ``, summed towards the root; ``hᵢ = Sᵢᵀ Fᵢ``.

No expression is differentiated and every quantity is built once from its parent's (or its
children's), so the result is a DAG whose size grows polynomially with the number of bodies;
common subexpressions are shared when code is generated. Sparse constants (axes along x, y, z;
zero offsets) stay exact zeros and vanish.
"""

from __future__ import annotations

import sympy as sp

from ..modelling.tree import Body, Defs, RigidTree, _matmul


class _Spatial:
    """A spatial vector: angular part ``w`` and linear part ``v`` (3×1 matrices)."""

    __slots__ = ("w", "v")

    def __init__(self, w: sp.Matrix, v: sp.Matrix) -> None:
        self.w, self.v = w, v

    def named(self, d: Defs) -> _Spatial:
        return _Spatial(d.vec(self.w), d.vec(self.v))

    def __add__(self, o: _Spatial) -> _Spatial:
        return _Spatial(self.w + o.w, self.v + o.v)

    def scale(self, s: sp.Expr) -> _Spatial:
        return _Spatial(self.w * s, self.v * s)

    def dot(self, o: _Spatial) -> sp.Expr:
        return _dot(self.w, o.w) + _dot(self.v, o.v)

    def cross_motion(self, o: _Spatial) -> _Spatial:
        return _Spatial(_cross(self.w, o.w), _cross(self.w, o.v) + _cross(self.v, o.w))

    def cross_force(self, f: _Spatial) -> _Spatial:
        return _Spatial(_cross(self.w, f.w) + _cross(self.v, f.v), _cross(self.w, f.v))


class _Inertia:
    """Spatial inertia about the world origin: mass ``m``, first moment ``h = m c``, and
    ``I = I_c + m (|c|² 1 − c cᵀ)`` (rotational inertia about the origin), world axes."""

    __slots__ = ("m", "h", "I")

    def __init__(self, m: sp.Expr, h: sp.Matrix, I: sp.Matrix) -> None:
        self.m, self.h, self.I = m, h, I

    @classmethod
    def of(cls, b: Body, d: Defs) -> _Inertia:
        c = d.vec(b.p + _matmul(b.R, b.com))
        Ic = d.vec(_matmul(b.R, d.vec(_matmul(b.inertia, b.R.T))))
        cc = d(_dot(c, c))
        I = sp.Matrix(3, 3, lambda i, j: Ic[i, j] + b.mass * ((cc if i == j else 0) - c[i] * c[j]))
        return cls(b.mass, d.vec(c * b.mass), d.vec(I))

    def add(self, o: _Inertia, d: Defs) -> _Inertia:
        return _Inertia(d(self.m + o.m), d.vec(self.h + o.h), d.vec(self.I + o.I))

    def apply(self, s: _Spatial, d: Defs) -> _Spatial:
        """The spatial momentum (force) ``I s``: ``(I w + h × v, m v − h × w)``."""
        return _Spatial(d.vec(_matmul(self.I, s.w) + _cross(self.h, s.v)), d.vec(s.v * self.m - _cross(self.h, s.w)))


def _dot(a: sp.Matrix, b: sp.Matrix) -> sp.Expr:
    return sp.Add(*[x * y for x, y in zip(a, b) if x != 0 and y != 0])


def _cross(a: sp.Matrix, b: sp.Matrix) -> sp.Matrix:
    def term(i: int, j: int) -> sp.Expr:
        return a[i] * b[j] if a[i] != 0 and b[j] != 0 else sp.Integer(0)

    return sp.Matrix([term(1, 2) - term(2, 1), term(2, 0) - term(0, 2), term(0, 1) - term(1, 0)])


def _subspace(b: Body, d: Defs) -> _Spatial:
    z = b.axis_w
    if b.joint.type == "prismatic":
        return _Spatial(sp.zeros(3, 1), z)
    return _Spatial(z, d.vec(_cross(b.axis_point, z)))


def tree_dynamics(tree: RigidTree, gravity: sp.Matrix) -> tuple[sp.Matrix, sp.Matrix]:
    """``M`` (n × n, over all model coordinates) and ``h`` (n × 1) of the tree's bodies, in the
    intermediate symbols of ``tree.defs`` (``tree.defs.expand`` gives them in q, q̇, parameters)."""
    model = tree.model
    n = len(model.q)
    bodies = tree.bodies
    d = tree.defs
    S = {b.name: _subspace(b, d) for b in bodies if b.moving}
    inertia = {b.name: _Inertia.of(b, d) for b in bodies}
    children: dict[str, list[Body]] = {b.name: [] for b in bodies}
    for b in bodies:
        if b.parent is not None:
            children[b.parent.name].append(b)

    # ---- CRBA: composite inertias from the leaves (bodies are in topological order)
    comp = dict(inertia)
    for b in reversed(bodies):
        if b.parent is not None:
            comp[b.parent.name] = comp[b.parent.name].add(comp[b.name], d)
    M = sp.zeros(n, n)
    for b in bodies:
        if not b.moving:
            continue
        F = comp[b.name].apply(S[b.name], d)
        i = b.index
        M[i, i] = d(S[b.name].dot(F))
        a = b.parent
        while a is not None:
            if a.moving:
                M[i, a.index] = M[a.index, i] = d(S[a.name].dot(F))
            a = a.parent

    # ---- RNEA with q̈ = 0: velocities and accelerations out, forces back
    zero = sp.zeros(3, 1)
    V: dict[str, _Spatial] = {}
    A: dict[str, _Spatial] = {}
    F: dict[str, _Spatial] = {}
    base_A = _Spatial(zero, -gravity)
    for b in bodies:
        v0 = V[b.parent.name] if b.parent is not None else _Spatial(zero, zero)
        a0 = A[b.parent.name] if b.parent is not None else base_A
        if b.moving:
            sq = S[b.name].scale(model.dot(b.coordinate)).named(d)
            vb = (v0 + sq).named(d)
            ab = (a0 + vb.cross_motion(sq)).named(d)
        else:
            vb, ab = v0, a0
        V[b.name], A[b.name] = vb, ab
        I = inertia[b.name]
        F[b.name] = (I.apply(ab, d) + vb.cross_force(I.apply(vb, d))).named(d)
    h = sp.zeros(n, 1)
    for b in reversed(bodies):
        f = F[b.name]
        if b.moving:
            h[b.index] = d(S[b.name].dot(f))
        if b.parent is not None:
            F[b.parent.name] = (F[b.parent.name] + f).named(d)
    return M, h

