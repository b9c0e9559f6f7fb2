"""Symbolic constants (π) in resets and guards compile: the generated C prints their
values, not the ``M_PI`` macros that C99's ``<math.h>`` does not declare."""

import math

import sympy as sp
from scipy.integrate import quad

import amble
from amble import Explicit, Guard, HybridSystem, Model

G, W0 = 9.81, 10.0  # m/s², rad/s at the bottom


def _spinning_pendulum() -> HybridSystem:
    """A unit pendulum going over the top; its angle is wrapped from π to −π (a reset with π)."""
    m = Model("spin-wrap-pi")
    (th,) = m.coordinates(["th"])
    m.point("bob", sp.Matrix([sp.sin(th), -sp.cos(th)]), mass=1.0)
    m.gravity(G)
    s = HybridSystem("spin-wrap-pi", {"spin": m})
    (thd,) = m.qd
    s.transition("wrap", "spin", Guard(th - sp.pi, 1), Explicit(q=[th - 2 * sp.pi], qd=[thd]),
                 target="spin", step=True)
    return s


def test_pi_in_a_reset_compiles_and_wraps_once_per_turn():
    run = amble.simulate(_spinning_pendulum(), [0.0, W0], steps=3, rtol=1e-12, atol=1e-12)
    assert run.status == "completed", run.message
    # energy: thd² = W0² − 2 g (1 − cos th); bottom to top takes the quadrature below, a turn twice that
    half = quad(lambda th: 1.0 / math.sqrt(W0**2 - 2 * G * (1 - math.cos(th))), 0.0, math.pi, epsabs=1e-13)[0]
    times = [e.t for e in run.events]
    assert abs(times[0] - half) <= 1e-9
    assert all(abs(b - a - 2 * half) <= 1e-9 for a, b in zip(times, times[1:]))
    assert all(abs(e.x_post[0] + math.pi) <= 1e-12 for e in run.events)
