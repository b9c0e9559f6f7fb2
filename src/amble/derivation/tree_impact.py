"""The ingredients of a plastic impact of a rigid-body tree, by recursion over the tree instead
of a sum over its bodies.

The impact of a point with the ground extends the model by its base position ``b``
(:mod:`amble.derivation.impact`): ``M_e = [[M, S], [Sᵀ, mₜ 1]]`` and the impacting point's
``J = [J_c, 1]``. ``M`` is the tree's (composite rigid bodies, :mod:`amble.derivation.tree`);
the other blocks come from the same recursion:

* ``Sᵀ`` (3 × n) maps ``q̇`` to the linear momentum of all bodies. Its column ``j`` is the linear
  momentum of the subtree of joint ``j`` moving with ``q̇ⱼ = 1``: the linear part of
  ``Iᶜⱼ Sⱼ`` (the composite inertia of that subtree times the joint's motion subspace, which
  the CRBA forms anyway), rotated from body ``j``'s axes to the world's;
* ``mₜ`` is the composite mass at the root;
* ``J_c`` (3 × n) is the geometric Jacobian of the point: ``zⱼ × (p − oⱼ)`` for a revolute joint
  ``j`` between the point's body and the base (axis ``zⱼ`` through ``oⱼ``, world), ``zⱼ`` for a
  prismatic one.

Every quantity is a named intermediate of the tree's :class:`~amble.modelling.defs.Defs`, built
from quantities the kinematics and the CRBA have named already, so the blocks cost a few
products per joint. The sum over bodies, ``S = Σ mᵢ Jᵢᵀ`` with each ``Jᵢ`` differentiated from a
position, grows with the number of bodies times the depth of the tree and took minutes for a
15-coordinate walker.
"""

from __future__ import annotations

import sympy as sp

from ..modelling.sparse_algebra import _cross, _matmul
from ..modelling.tree import RigidTree
from .tree import _Inertia, _Spatial, _Transform


def tree_impact_terms(tree: RigidTree, point: str) -> tuple[sp.Matrix, sp.Expr, sp.Matrix]:
    """``(Sᵀ, mₜ, J_c)`` of the tree's bodies for an impact of the named ``point`` (a point
    defined on a body of the tree): ``Sᵀ`` and ``J_c`` are 3 × n over all model coordinates,
    in the intermediate symbols of ``tree.defs`` (kg·m/s and m per unit of q̇, world axes)."""
    model = tree.model
    n = len(model.q)
    d = tree.defs
    bodies = tree.bodies
    X: dict[str, _Transform] = {}
    for b in bodies:
        E, r = tree.local_transform(b)
        X[b.name] = _Transform(d.vec(E), d.vec(r))
    # composite inertias from the leaves, as in the CRBA (the same expressions: the same names)
    comp = {b.name: _Inertia(*tree.body_inertia(b)) for b in bodies}
    for b in reversed(bodies):
        if b.parent is not None:
            comp[b.parent.name] = comp[b.parent.name].add(comp[b.name].to_parent(X[b.name], d), d)
    ST = sp.zeros(3, n)
    for b in bodies:
        if b.moving:
            F = comp[b.name].apply(_Spatial(*tree.local_subspace(b)), d)
            ST[:, b.index] = d.vec(ST[:, b.index] + _matmul(b.R, F.v))  # += : a mimic shares its column
    mt = d(sp.Add(*[comp[b.name].m for b in bodies if b.parent is None]))
    body, r = tree.point_frames[point]
    p = d.vec(body.p + r)
    Jc = sp.zeros(3, n)
    a = body
    while a is not None:
        if a.moving:
            col = a.axis_w if a.joint.type == "prismatic" else d.vec(_cross(a.axis_w, p - a.axis_point))
            Jc[:, a.index] = d.vec(Jc[:, a.index] + col * a.multiplier)  # a mimic: k times, in its coordinate's column
        a = a.parent
    return ST, mt, Jc
