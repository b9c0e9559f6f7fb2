"""Sparse symbolic algebra in 3D for the recursions of a rigid-body tree: vectors and 3×3 matrices
from numbers or expressions (integral floats as exact integers), products, dot and cross products
that skip zero terms, and rotations (URDF roll-pitch-yaw, Rodrigues about a unit axis).

Apart from :mod:`amble.modelling.tree`: the tree's kinematics, the stance-feet walker and the
tree's dynamics and impacts (:mod:`amble.derivation.tree`, :mod:`amble.derivation.tree_impact`)
build their expressions with the same products, which keep constant rotations sparse.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
import sympy as sp


def rpy_matrix(rpy: Sequence[float]) -> np.ndarray:
    """Rotation of URDF roll-pitch-yaw angles: ``Rz(yaw) Ry(pitch) Rx(roll)``."""
    r, p, y = (float(a) for a in rpy)
    cr, sr, cp, sp_, cy, sy = np.cos(r), np.sin(r), np.cos(p), np.sin(p), np.cos(y), np.sin(y)
    rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    ry = np.array([[cp, 0, sp_], [0, 1, 0], [-sp_, 0, cp]])
    rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    return rz @ ry @ rx


def _num(x: Any) -> sp.Expr:
    """A number or expression as sympy; integral floats become exact integers (sparser trees)."""
    if isinstance(x, sp.Basic):
        return x
    v = float(x)
    if v == 0.0:
        return sp.Integer(0)
    if v.is_integer() and abs(v) < 2**31:
        return sp.Integer(int(v))
    return sp.Float(v, 17)


def _vec(xs: Any) -> sp.Matrix:
    return sp.Matrix([_num(x) for x in xs])


def _mat3(xs: Any) -> sp.Matrix:
    if isinstance(xs, sp.MatrixBase):
        return sp.Matrix(xs)
    a = np.asarray(xs, dtype=object)
    return sp.Matrix(3, 3, [_num(v) for v in a.reshape(-1)])


def _rotation(axis: sp.Matrix, c: sp.Expr, s: sp.Expr) -> sp.Matrix:
    """Rodrigues' rotation about a unit axis, by cos ``c`` and sin ``s`` (sparse for x, y, z)."""
    x, y, z = axis
    C = 1 - c
    return sp.Matrix([
        [c + x * x * C, x * y * C - z * s, x * z * C + y * s],
        [y * x * C + z * s, c + y * y * C, y * z * C - x * s],
        [z * x * C - y * s, z * y * C + x * s, c + z * z * C],
    ])



def _matmul(A: sp.Matrix, B: sp.Matrix) -> sp.Matrix:
    """Product that skips zero terms (constant rotations are sparse)."""
    out = sp.zeros(A.rows, B.cols)
    for i in range(A.rows):
        for k in range(B.cols):
            out[i, k] = sp.Add(*[A[i, j] * B[j, k] for j in range(A.cols) if A[i, j] != 0 and B[j, k] != 0])
    return out


def _dot(a: sp.Matrix, b: sp.Matrix) -> sp.Expr:
    """Dot product that skips zero terms."""
    return sp.Add(*[x * y for x, y in zip(a, b) if x != 0 and y != 0])


def _cross(a: sp.Matrix, b: sp.Matrix) -> sp.Matrix:
    """Cross product that skips zero terms."""
    def term(i: int, j: int) -> sp.Expr:
        return a[i] * b[j] if a[i] != 0 and b[j] != 0 else sp.Integer(0)

    return sp.Matrix([term(1, 2) - term(2, 1), term(2, 0) - term(0, 2), term(0, 1) - term(1, 0)])


def _mul_add(A: sp.Matrix, x: sp.Matrix, y: sp.Matrix) -> sp.Matrix:
    return _matmul(A, x) + y
