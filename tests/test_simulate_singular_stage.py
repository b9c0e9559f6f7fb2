"""A trial stage of an explicit step may land where the mass matrix is singular although the flow
never goes there: the step is rejected and shortened, the run goes on. Only a singular mass
matrix at a state the flow reaches ends a run (``singular_mass``).

The model: a unit spring, ``V = x²/2``, and a position-dependent inertia ``M(x) = 1 − x²``,
singular at |x| = 1. From x = 0 at speed v < 1 the oscillation turns at x = ±v (energy
``M ẋ²/2 + x²/2 = v²/2``), so ``dt = sqrt((1 − x²) / (v² − x²)) dx`` and, with x = v sin φ, a
quarter period is the complete elliptic integral of the second kind ``E(m = v²)``. Near a turning
point a long step's stages extrapolate past it, beyond |x| = 1."""

import pytest
from scipy.special import ellipe

import amble
from amble import Explicit, Guard, HybridSystem, Model


def _oscillator() -> HybridSystem:
    m = Model("inertia-vanishing-at-one")
    (x,) = m.coordinates(["x"])
    (xd,) = m.qd
    m.add_kinetic((1 - x**2) * xd**2 / 2)
    m.add_potential(x**2 / 2)
    s = HybridSystem("inertia-vanishing-at-one", {"osc": m})
    s.transition("turn", "osc", Guard(xd, -1), Explicit(q=[x], qd=[xd]), target="osc", step=True)
    return s


@pytest.mark.parametrize("method", ["dop853", "tsit5"])
@pytest.mark.parametrize("v", [0.9, 0.995])
def test_a_singular_trial_stage_shortens_the_step(method, v):
    # loose tolerances: long steps, whose stages overshoot the turning point (before: singular_mass)
    run = amble.simulate(_oscillator(), [0.0, v], steps=3, rtol=1e-4, atol=1e-4, method=method)
    assert run.status == "completed", run.message
    quarter = float(ellipe(v**2))
    t = [e.t for e in run.events]
    assert abs(t[0] - quarter) <= 1e-3 * quarter
    assert all(abs(b - a - 4 * quarter) <= 2e-3 * quarter for a, b in zip(t, t[1:]))


def test_a_state_where_the_mass_matrix_is_singular_still_ends_the_run():
    run = amble.simulate(_oscillator(), [1.0, 0.5], steps=1, rtol=1e-4, atol=1e-4)
    assert run.status == "singular_mass"
