"""A walker whose feet take turns as the base of a rigid-body tree (a URDF robot).

Each stance is a mode: the same tree rooted at that foot, the foot attached to the ground by a
pivot joint at its contact point (``Model.from_urdf(..., base=foot, base_joint=Joint("spherical"),
pivot=sole)``). At a footfall the swing foot's contact point strikes the ground (a derived
plastic impact), the frame moves to it, and the other mode takes over. The joints keep their
coordinates — a re-rooted tree traverses the same joints, with the same angles — so the
relabelling only gives the new base joint's coordinates: the orientation of the new stance foot,
read from its rotation ``R`` (world axes) in the old mode.

* a ``spherical`` base, ``R = Rz(yaw) Ry(pitch) Rx(roll)``: ``yaw = atan2(R₁₀, R₀₀)``,
  ``pitch = atan2(−R₂₀, √(R₂₁² + R₂₂²))``, ``roll = atan2(R₂₁, R₂₂)`` (the base's Euler angles
  are singular at pitch = ±π/2, which a stance foot does not reach);
* a ``revolute`` base about a unit axis ``a``: ``θ = atan2(a·w, (tr R − 1)/2)`` with
  ``[w]ₓ = (R − Rᵀ)/2`` — exact when the foot turns about that axis only (a planar walker).

A fixed rotation of the base joint's frame (``rpy``) or after it (``post_rotation``) is taken out
first: ``R = R_o J(q) R_post``.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import sympy as sp

from ..errors import ModelError
from .contact import heel_strike, height_above_slope
from .dag import dag_subs
from .hybrid import Guard
from .model import Model
from .sparse_algebra import _mat3, _matmul, rpy_matrix
from .tree import RigidTree
from .walker import Walker


def _base_chain(model: Model) -> list:
    """The bodies from the world to the tree's base link (one, or a composite joint's frames)."""
    tree = model.tree
    if not isinstance(tree, RigidTree):
        raise ModelError(f"model {model.name!r}: a stance foot needs a rigid-body tree (Model.from_urdf)")
    roots = [b for b in tree.bodies if b.parent is None]
    if len(roots) != 1:
        raise ModelError(f"model {model.name!r}: expected one base link, found {len(roots)}")
    chain = roots
    while chain[-1].name not in tree.com_points:
        chain.append(next(b for b in tree.bodies if b.parent is chain[-1]))
    return chain


def _atan2(y: sp.Expr, x: sp.Expr) -> sp.Expr:
    # unevaluated: sympy would ask for the signs of a tree's shared graphs (minutes)
    return sp.atan2(y, x, evaluate=False)


def base_relabel(source: Model, target: Model) -> dict[sp.Symbol, sp.Expr]:
    """The coordinates of ``target``'s base joint as expressions of ``source``'s coordinates:
    the orientation that ``target``'s base link has in ``source`` (module docstring). Both
    models are trees over the same links (the base link may be a massless frame that ``source``
    merged into the body it hangs from); the base joint is ``revolute`` or ``spherical``,
    centred at the origin."""
    chain = _base_chain(target)
    link = chain[-1].name
    ts = source.tree
    # the link is a body of the source's tree, or a massless frame merged into one (a foot frame
    # on a fixed joint below the shin: its rotation is the body's times the frame's)
    frame = getattr(ts, "link_frames", {}).get(link) if isinstance(ts, RigidTree) else None
    if not isinstance(ts, RigidTree) or (link not in ts.com_points and (frame is None or frame[0] is None)):
        raise ModelError(f"model {source.name!r}: no link {link!r} (the base of {target.name!r})")
    first, last = chain[0].joint, chain[-1].joint
    if any(float(v) != 0.0 for v in first.xyz):
        raise ModelError(f"model {target.name!r}: the base joint must sit at the origin (the stance foot's "
                         f"contact), got xyz={tuple(first.xyz)}")
    kinds = [b.joint.type for b in chain]
    axes = [tuple(np.round(np.asarray(b.joint.axis, float), 12)) for b in chain]
    Ro = _mat3(first.rotation) if first.rotation is not None else _mat3(rpy_matrix(first.rpy))
    Rp = _mat3(last.post_rotation) if last.post_rotation is not None else sp.eye(3)
    if link in ts.com_points:
        R = ts.defs.expand(ts[link].R)
    else:
        body, Rf, _ = frame
        R = _matmul(ts.defs.expand(ts[body].R), _mat3(Rf))
    Q = R if Ro == sp.eye(3) else _matmul(Ro.T, R)
    Q = Q if Rp == sp.eye(3) else _matmul(Q, Rp.T)
    if kinds == ["revolute"]:
        a = sp.Matrix(chain[0].joint.axis)
        w = sp.Matrix([Q[2, 1] - Q[1, 2], Q[0, 2] - Q[2, 0], Q[1, 0] - Q[0, 1]]) / 2
        angles = [_atan2((a.T * w)[0, 0], (Q[0, 0] + Q[1, 1] + Q[2, 2] - 1) / 2)]
    elif kinds == ["revolute"] * 3 and axes == [(0, 0, 1), (0, 1, 0), (1, 0, 0)]:
        angles = [_atan2(Q[1, 0], Q[0, 0]), _atan2(-Q[2, 0], sp.sqrt(Q[2, 1] ** 2 + Q[2, 2] ** 2)),
                  _atan2(Q[2, 1], Q[2, 2])]
    else:
        raise ModelError(f"model {target.name!r}: a stance foot's base joint must be revolute or spherical, "
                         f"got {' + '.join(kinds)}")
    return {b.coordinate: e for b, e in zip(chain, angles)}


def _check_pivot(model: Model, point: str) -> None:
    """``point`` is the model's origin in every pose (the base pivots there), checked at one pose."""
    if point not in model.points:
        raise ModelError(f"model {model.name!r}: no point named {point!r}")
    rng = np.random.default_rng(0)
    at = {q: sp.Float(v) for q, v in zip(model.q, rng.uniform(-1.0, 1.0, len(model.q)))}
    at.update({p: sp.Float(v) for p, v in model.params.items()})
    pos = [complex(e) for e in dag_subs(model.points[point], at)]
    if max(abs(v) for v in pos) > 1e-9:
        raise ModelError(f"model {model.name!r}: the base does not pivot at {point!r} (give "
                         f"Model.from_urdf(..., pivot={point!r}))")


def stance_feet_walker(name: str, modes: Mapping[str, Model], feet: Mapping[str, str], hip: str,
                       slope: Any = 0.0, max_step_time: float = 5.0,
                       start: Sequence[float] | None = None, doc: str = "") -> Walker:
    """A walker with one mode per stance foot: ``modes`` maps a mode name to the model rooted at
    that foot, ``feet`` each mode to its stance foot's contact point (where its base pivots).
    In each mode the other mode's foot strikes the slope ahead of the stance foot (transition
    ``heel_strike_<mode>`` into that mode, a derived plastic impact and :func:`base_relabel`);
    the hip reaching the ground is a fall. ``start``: the default initial state of the first mode."""
    names = list(modes)
    if len(names) != 2 or set(feet) != set(names):
        raise ModelError(f"walker {name!r}: give two modes and the stance foot of each, got modes "
                         f"{names} and feet {sorted(feet)}")
    for mode in names:
        _check_pivot(modes[mode], feet[mode])
    w = Walker(name, dict(modes), hip=hip, slope=slope, max_step_time=max_step_time, doc=doc)
    for a, b in (names, names[::-1]):
        guard, reset = heel_strike(modes[a], feet[b], slope, base_relabel(modes[a], modes[b]), stance=feet[a])
        w.transition(f"heel_strike_{b}", a, guard, reset, target=b, step=True)
    w.terminal("hip_on_ground", names, lambda m: Guard(height_above_slope(m, hip, slope), -1), status="fell")
    if start is not None:
        w.default_start[names[0]] = list(start)
    return w
