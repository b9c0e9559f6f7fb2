"""Independent bipedal spring-mass walker: SciPy and NumPy only.

Written from the physics (Geyer, Seyfarth & Blickhan 2006, "Compliant leg behaviour explains
basic dynamics of walking and running", Proc. R. Soc. B 273:2861–2867): a point mass ``m`` on
two massless linear spring legs (stiffness ``k``, rest length ``L0``), gravity ``g``. Positions
are world coordinates ``(x, y)`` of the mass with the current stance foot at ``x = 0``.

* single support: one spring, its foot at the origin, pushes along the leg.
* touchdown: the swing leg, held at the angle of attack ``alpha`` from the horizontal with its
  foot ahead, lands when ``y`` falls through ``L0 sin(alpha)``; its foot is placed at
  ``x + L0 cos(alpha)``.
* double support: both springs push, both feet fixed.
* liftoff: the rear leg is back at its rest length (its spring force falls through zero); the
  front foot becomes the origin.
* the step ends at the vertical leg orientation (midstance): ``x`` rising through zero.

The section is midstance at the system energy ``E``: the state ``(y, y_dot)`` there, the
forward speed following from ``E``. Events are located by ``solve_ivp`` (DOP853, rtol = atol =
1e-12). Nothing here is imported from amble.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import fsolve

TOL = dict(method="DOP853", rtol=1e-12, atol=1e-12)


@dataclass(frozen=True)
class SlipWalker:
    m: float = 80.0
    L0: float = 1.0
    k: float = 20000.0
    alpha: float = math.radians(69.0)
    g: float = 9.81
    E: float = 840.0

    def speed(self, y: float, yd: float) -> float:
        """Forward speed at midstance (m/s) at height ``y``, vertical velocity ``yd``, energy E."""
        spring = 0.5 * self.k * (self.L0 - y) ** 2
        return math.sqrt(2 * (self.E - self.m * self.g * y - spring) / self.m - yd**2)

    def energy(self, s: np.ndarray, feet: tuple[float, ...]) -> float:
        x, y, xd, yd = s
        springs = sum(0.5 * self.k * (self.L0 - math.hypot(x - f, y)) ** 2 for f in feet)
        return self.m * self.g * y + 0.5 * self.m * (xd**2 + yd**2) + springs

    def _rhs(self, feet: tuple[float, ...]):
        k, m, L0, g = self.k, self.m, self.L0, self.g

        def f(_t, s):
            x, y, xd, yd = s
            ax, ay = 0.0, -g
            for foot in feet:
                r = math.hypot(x - foot, y)
                push = k * (L0 - r) / (m * r)  # spring force per mass, over the leg length
                ax += push * (x - foot)
                ay += push * y
            return [xd, yd, ax, ay]

        return f

    def _phase(self, s0, feet, event):
        event.terminal = True

        def down(_t, s):
            return s[1]

        down.terminal, down.direction = True, -1.0
        sol = solve_ivp(self._rhs(feet), (0.0, 5.0), s0, events=(event, down), **TOL)
        if sol.status != 1 or len(sol.t_events[0]) == 0:
            raise ValueError("the phase did not end in its event")
        return float(sol.t_events[0][0]), np.array(sol.y_events[0][0])

    def step(self, y: float, yd: float) -> dict:
        """One step from midstance at ``(y, yd)``: times from midstance and states (world
        coordinates relative to the foot of the phase's start) at touchdown, liftoff and the next
        midstance, and the front foot's distance ``d`` ahead of the rear one."""
        L0, a = self.L0, self.alpha
        s0 = np.array([0.0, y, self.speed(y, yd), yd])

        def touchdown(_t, s):
            return s[1] - L0 * math.sin(a)

        touchdown.direction = -1.0
        t_td, s_td = self._phase(s0, (0.0,), touchdown)
        d = s_td[0] + L0 * math.cos(a)

        def liftoff(_t, s):
            return math.hypot(s[0], s[1]) - L0

        liftoff.direction = 1.0
        t_ds, s_lo = self._phase(s_td, (0.0, d), liftoff)
        s_lo = s_lo - np.array([d, 0.0, 0.0, 0.0])

        def midstance(_t, s):
            return s[0]

        midstance.direction = 1.0
        t_ss, s_mid = self._phase(s_lo, (0.0,), midstance)
        return dict(t_td=t_td, s_td=s_td, d=d, t_lo=t_td + t_ds, s_lo=s_lo, t_mid=t_td + t_ds + t_ss,
                    s_mid=s_mid, double_support=t_ds)

    def map(self, p: np.ndarray) -> np.ndarray:
        """The return map at midstance: ``(y, y_dot)`` → the next one."""
        s = self.step(float(p[0]), float(p[1]))["s_mid"]
        return np.array([s[1], s[3]])

    def fixed_point(self, guess=(0.98, 0.0)) -> np.ndarray:
        p, _, ok, msg = fsolve(lambda p: self.map(p) - p, np.array(guess), xtol=1e-13, full_output=True)
        if ok != 1:
            raise ValueError(msg)
        return p

    def multipliers(self, p: np.ndarray, h: float = 1e-5) -> np.ndarray:
        """Eigenvalues of the return map's Jacobian by central differences."""
        J = np.zeros((2, 2))
        for i in range(2):
            e = np.zeros(2)
            e[i] = h
            J[:, i] = (self.map(p + e) - self.map(p - e)) / (2 * h)
        return np.linalg.eigvals(J)
