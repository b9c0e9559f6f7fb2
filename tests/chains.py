"""A shared test model: the n-link planar pendulum chain."""

import sympy as sp

from amble import Model


def pendulum_chain(n: int, name: str | None = None) -> Model:
    """n links with point masses at their ends, absolute angles from the downward vertical;
    masses ``m<i>``, lengths ``l<i>`` and ``g`` are parameters (defaults 1, 1, 9.81)."""
    m = Model(name or f"chain{n}")
    qs = m.coordinates([f"q{i}" for i in range(n)])
    ps = m.parameters(**{f"m{i}": 1.0 for i in range(n)}, **{f"l{i}": 1.0 for i in range(n)}, g=9.81)
    pos = sp.zeros(2, 1)
    for i in range(n):
        pos = pos + ps[n + i] * sp.Matrix([sp.sin(qs[i]), -sp.cos(qs[i])])
        m.point(f"p{i}", pos, mass=ps[i])
    m.gravity(ps[-1])
    return m
