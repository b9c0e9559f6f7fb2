"""A rigid pendulum released from rest with its centre of mass level with the pivot: the time it
takes to swing down through an angle ``a``, in closed form and again by SciPy's integrator.

Nothing here comes from amble. A body of mass ``m`` whose centre of mass is ``l`` from a
horizontal pivot axis, with moment of inertia ``I`` about the parallel axis through the centre
of mass, swings by the angle ``q`` below the horizontal::

    (m l² + I) q̈ = m g l cos q,     q(0) = 0, q̇(0) = 0,

so ``q̇² = 2 ω² sin q`` with ``ω² = m g l / (m l² + I)``. Measured from the downward vertical,
``φ = π/2 − q`` swings from the amplitude ``φ₀ = π/2``; with ``k = sin(φ₀/2)`` and
``sin(φ/2) = k sin ψ``, the time from the release to ``φ`` is (Byrd & Friedman 1971, 111.02)::

    t = (K(k²) − F(ψ, k²)) / ω

(``K``, ``F``: the complete and incomplete elliptic integrals of the first kind in SciPy's
parameter ``m = k²``). :func:`time_by_integration` finds the same time with ``solve_ivp`` and an
event on the written-out equation, as a check of the closed form.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.integrate import solve_ivp
from scipy.special import ellipk, ellipkinc


def omega2(m: float, l: float, inertia: float, g: float = 9.81) -> float:
    """``ω² = m g l / (m l² + I)`` (1/s²)."""
    return m * g * l / (m * l * l + inertia)


def time_to_angle(a: float, w2: float) -> float:
    """Time (s) from the release at the horizontal to the angle ``a`` below it (0 < a ≤ π/2)."""
    k = math.sin(math.pi / 4)
    psi = math.asin(math.sin((math.pi / 2 - a) / 2) / k)
    return (ellipk(k * k) - ellipkinc(psi, k * k)) / math.sqrt(w2)


def time_by_integration(a: float, w2: float) -> float:
    """The same time from ``solve_ivp`` (DOP853, tight tolerances) with an event at ``q = a``."""
    def reached(t, y):
        return y[0] - a

    reached.terminal, reached.direction = True, 1
    sol = solve_ivp(lambda t, y: [y[1], w2 * np.cos(y[0])], (0.0, 10.0), [0.0, 0.0], method="DOP853",
                    rtol=1e-13, atol=1e-13, events=reached)
    return float(sol.t_events[0][0])


def speed_at_angle(a: float, w2: float) -> float:
    """``q̇`` (rad/s) at the angle ``a``: ``√(2 ω² sin a)``, from the energy."""
    return math.sqrt(2 * w2 * math.sin(a))
