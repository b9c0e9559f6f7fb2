"""The unit a library model declares for each coordinate agrees with how the coordinate enters its
points' positions: a coordinate inside a sine or cosine is an angle (rad); one that enters every
position it appears in outside any trigonometric function, as a length would, is a length (m).
A dimensional check, run over every model of the library (tree models are read from their own
declarations too: their points are built from the same coordinates)."""

from __future__ import annotations

import pytest
import sympy as sp

from amble.models import load, names

TRIG = (sp.sin, sp.cos, sp.tan)


def _roles(expr: sp.Expr, q: sp.Symbol) -> set[str]:
    """How ``q`` occurs in ``expr``: ``"angle"`` inside a trigonometric argument, ``"length"``
    outside any."""
    roles: set[str] = set()

    def walk(e: sp.Basic, inside: bool) -> None:
        if e == q:
            roles.add("angle" if inside else "length")
            return
        for a in e.args:
            walk(a, inside or isinstance(e, TRIG))

    walk(sp.sympify(expr), False)
    return roles


@pytest.mark.parametrize("name", names())
def test_declared_units_match_how_coordinates_enter_positions(name):
    system = load(name).symbolic()
    checked = 0
    for mode in system.modes.values():
        for q in mode.q:
            roles = set().union(*(_roles(e, q) for p in mode.points.values() for e in p))
            unit = mode.unit(str(q))
            if "angle" in roles:
                assert unit == "rad", f"{name}: {q} is an angle in its positions, declared {unit!r}"
                checked += 1
            elif roles == {"length"}:
                assert unit == "m", f"{name}: {q} is a length in its positions, declared {unit!r}"
                checked += 1
    assert checked > 0
