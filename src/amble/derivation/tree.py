"""Equations of motion of a rigid-body tree by recursion: ``M`` by the composite-rigid-body
algorithm, ``h`` by recursive Newton–Euler with ``q̈ = 0`` (gravity included).

Everything is written in spatial vectors (Featherstone) expressed in each **body's own frame**
at its origin. In that frame a body's spatial inertia is a constant (its mass, first moment
``m c`` and rotational inertia about the origin: numbers or parameters), and a joint's motion
subspace ``Sᵢ`` is a constant too (``(a, o × a)`` for a revolute joint about the axis ``a``
through the point ``o``, ``(0, a)`` for a prismatic one). What depends on q is only the transform
from each parent to its child, ``Xᵢ(qᵢ)`` — a rotation about one axis and a constant offset, so
sparse for axes along x, y or z. The recursions are unrolled symbolically:

* CRBA: composite inertias ``Iᶜ_parent += Xᵢᵀ Iᶜᵢ Xᵢ`` from the leaves; the column of body ``i``
  is ``F = Iᶜᵢ Sᵢ`` carried towards the root by ``F ← Xⱼᵀ F``, ``M_ij = S_jᵀ F`` on the way.
* RNEA: ``Vᵢ = Xᵢ V_parent + Sᵢ q̇ᵢ``, ``Aᵢ = Xᵢ A_parent + Vᵢ × Sᵢ q̇ᵢ`` from ``A_base = −g``;
  ``Fᵢ = Iᵢ Aᵢ + Vᵢ ×* Iᵢ Vᵢ``, added to the parent's as ``Xᵢᵀ Fᵢ``; ``hᵢ = Sᵢᵀ Fᵢ``.
* A mimic joint (angle ``k·a + c`` of a coordinate ``a``) has the subspace ``k Sᵢ`` per unit of
  ``ȧ`` and adds its terms to ``a``'s row and column: the reduced ``Gᵀ M G``, ``Gᵀ h`` (``G``
  constant, so no ``Ġ q̇`` term), without the joints' full equations.

Why body frames (measured on the 7-link spatial chain, axes cycling y, x, z; full inertia
tensors): the same recursions written in world coordinates need every body's world rotation
``Rᵢ`` and its rotated inertia ``Rᵢ Iᵢ Rᵢᵀ`` — dense products that grow with depth — and
generated about twice the operations of the body-frame form. No expression is differentiated and
every quantity is built once from its parent's (or its children's), so the result is a DAG whose
size grows with the number of bodies times the depth (the entries of ``M``) and is linear
otherwise; each intermediate is named (:class:`~amble.modelling.defs.Defs`), and the code
generator emits the names as shared subexpressions. Exact zeros of sparse constants vanish.
"""

from __future__ import annotations

import sympy as sp

from ..modelling.constrained_tree import ConstrainedTree
from ..modelling.defs import Defs
from ..modelling.sparse_algebra import _cross, _dot, _matmul
from ..modelling.tree import RigidTree


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


class _Transform:
    """The placement of a child frame in its parent's: ``x_parent = E x_child + r``.

    ``motion`` carries a motion vector (velocity) from the parent's frame and origin to the
    child's; ``force`` carries a force back (moment about the child's origin → the parent's)."""

    __slots__ = ("E", "ET", "r")

    def __init__(self, E: sp.Matrix, r: sp.Matrix) -> None:
        self.E, self.ET, self.r = E, E.T, r

    def motion(self, m: _Spatial, d: Defs) -> _Spatial:
        return _Spatial(d.vec(_matmul(self.ET, m.w)), d.vec(_matmul(self.ET, m.v + _cross(m.w, self.r))))

    def force(self, f: _Spatial, d: Defs) -> _Spatial:
        lin = d.vec(_matmul(self.E, f.v))
        return _Spatial(d.vec(_matmul(self.E, f.w) + _cross(self.r, lin)), lin)


class _Inertia:
    """Spatial inertia about a frame's origin in its axes: mass ``m``, first moment ``h = m c``
    and ``I = I_c + m (|c|² 1 − c cᵀ)`` (rotational inertia about the origin)."""

    __slots__ = ("m", "h", "I")

    def __init__(self, m: sp.Expr, h: sp.Matrix, I: sp.Matrix) -> None:
        self.m, self.h, self.I = m, h, I

    def to_parent(self, X: _Transform, d: Defs) -> _Inertia:
        """``Xᵀ I X``: the same inertia about the parent's origin, in the parent's axes.

        With ``h' = E h`` and ``r`` the child's origin: ``I_parent = E I Eᵀ + 2 (h'·r) 1 − h' rᵀ
        − r h'ᵀ + m (|r|² 1 − r rᵀ)`` (the parallel-axis rule for a first moment about a point)."""
        hr = d.vec(_matmul(X.E, self.h))
        IE = d.vec(_matmul(self.I, X.ET))
        r, m = X.r, self.m
        two_hr, rr = d(2 * _dot(hr, r)), d(_dot(r, r))
        I = sp.zeros(3, 3)
        for i in range(3):
            for j in range(i, 3):
                e = sp.Add(*[X.E[i, k] * IE[k, j] for k in range(3) if X.E[i, k] != 0 and IE[k, j] != 0])
                e += (two_hr + m * rr if i == j else 0) - hr[i] * r[j] - r[i] * hr[j] - m * r[i] * r[j]
                I[i, j] = I[j, i] = d(e)
        return _Inertia(m, d.vec(hr + r * m), I)

    def add(self, o: _Inertia, d: Defs) -> _Inertia:
        return _Inertia(d(self.m + o.m), d.vec(self.h + o.h), d.vec(self.I + o.I))

    def apply(self, s: _Spatial, d: Defs) -> _Spatial:
        """The spatial momentum (force) ``I s``: ``(I w + h × v, m v − h × w)``."""
        return _Spatial(d.vec(_matmul(self.I, s.w) + _cross(self.h, s.v)), d.vec(s.v * self.m - _cross(self.h, s.w)))


def tree_dynamics(tree: RigidTree | ConstrainedTree, gravity: sp.Matrix) -> tuple[sp.Matrix, sp.Matrix]:
    """``M`` (n × n, over all model coordinates) and ``h`` (n × 1) of the tree's bodies, in the
    intermediate symbols of ``tree.defs`` (``tree.defs.expand`` gives them in q, q̇, parameters)."""
    if isinstance(tree, ConstrainedTree):
        return _projected(tree, gravity)
    model = tree.model
    n = len(model.q)
    bodies = tree.bodies
    d = tree.defs
    X: dict[str, _Transform] = {}
    S: dict[str, _Spatial] = {}
    for b in bodies:
        E, r = tree.local_transform(b)
        X[b.name] = _Transform(d.vec(E), d.vec(r))
        if b.moving:
            S[b.name] = _Spatial(*tree.local_subspace(b))
    inertia = {b.name: _Inertia(*tree.body_inertia(b)) for b in bodies}

    # ---- CRBA: composite inertias from the leaves (bodies are in topological order)
    comp = dict(inertia)
    for b in reversed(bodies):
        if b.parent is not None:
            comp[b.parent.name] = comp[b.parent.name].add(comp[b.name].to_parent(X[b.name], d), d)
    # entries (i ≤ j) as sums of terms: a mimic joint shares its coordinate with another joint, and
    # M = Gᵀ M_joints G adds the terms of every pair of joints that coordinate moves
    terms: dict[tuple[int, int], list[sp.Expr]] = {}
    for b in bodies:
        if not b.moving:
            continue
        F = comp[b.name].apply(S[b.name], d)
        i = b.index
        terms.setdefault((i, i), []).append(S[b.name].dot(F))
        c, a = b, b.parent
        while a is not None:
            F = X[c.name].force(F, d)
            if a.moving:
                e = S[a.name].dot(F)
                j = a.index
                terms.setdefault((min(i, j), max(i, j)), []).append(2 * e if i == j else e)
            c, a = a, a.parent
    M = sp.zeros(n, n)
    for (i, j), es in terms.items():
        M[i, j] = M[j, i] = d(sp.Add(*es))

    # ---- RNEA with q̈ = 0: velocities (the tree's, shared with its kinetic energy) and
    # accelerations out, forces back; gravity enters as an upward acceleration of the base
    zero = sp.zeros(3, 1)
    vel = tree.body_velocities()
    A: dict[str, _Spatial] = {}
    F: dict[str, _Spatial] = {}
    for b in bodies:
        Xb = X[b.name]
        a0 = Xb.motion(A[b.parent.name] if b.parent is not None else _Spatial(zero, -gravity), d)
        w, v, sw, sv = vel[b.name]
        vb = _Spatial(w, v)
        ab = (a0 + vb.cross_motion(_Spatial(sw, sv))).named(d) if b.moving else a0
        A[b.name] = ab
        I = inertia[b.name]
        F[b.name] = (I.apply(ab, d) + vb.cross_force(I.apply(vb, d))).named(d)
    hs: dict[int, list[sp.Expr]] = {}
    for b in reversed(bodies):
        f = F[b.name]
        if b.moving:
            hs.setdefault(b.index, []).append(S[b.name].dot(f))
        if b.parent is not None:
            F[b.parent.name] = (F[b.parent.name] + X[b.name].force(f, d)).named(d)
    h = sp.zeros(n, 1)
    for i, es in hs.items():
        h[i] = d(sp.Add(*es))
    return M, h


def _projected(tree: ConstrainedTree, gravity: sp.Matrix) -> tuple[sp.Matrix, sp.Matrix]:
    """A constrained tree's ``M = Jᵀ M_full J`` and ``h = Jᵀ (h_full + M_full J̇ q̇)`` from the source
    tree's equations, in the source's intermediate symbols with the eliminated coordinates replaced."""
    Mf, hf = (m.xreplace(tree.substitutions) for m in tree_dynamics(tree.source, gravity))
    d = tree.sync()
    J, jdqd = tree.jacobian()
    nf, n = J.shape
    nz = lambda e: e != 0  # noqa: E731
    MJ = [[d(sp.Add(*[Mf[k, l] * J[l, j] for l in range(nf) if nz(J[l, j]) and nz(Mf[k, l])])) for j in range(n)]
          for k in range(nf)]
    hb = [d(hf[k] + sp.Add(*[Mf[k, l] * jdqd[l] for l in range(nf) if nz(jdqd[l]) and nz(Mf[k, l])]))
          for k in range(nf)]
    M, h = sp.zeros(n, n), sp.zeros(n, 1)
    for i in range(n):
        for j in range(i, n):
            M[i, j] = M[j, i] = d(sp.Add(*[J[k, i] * MJ[k][j] for k in range(nf) if nz(J[k, i]) and nz(MJ[k][j])]))
        h[i] = d(sp.Add(*[J[k, i] * hb[k] for k in range(nf) if nz(J[k, i]) and nz(hb[k])]))
    return M, h
