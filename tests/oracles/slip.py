"""Independent spring-loaded inverted pendulum (SLIP) runner: SciPy and NumPy only.

Written from the physics (Seyfarth, Geyer, Günther & Blickhan 2002, "A movement criterion for
running", J. Biomech. 35:649–655): a point mass ``m`` on a massless linear spring leg of stiffness
``k`` and rest length ``L0``. Flight is ballistic (closed form). The leg touches down at the angle
of attack ``alpha`` measured from the horizontal ground, the foot ahead of the mass, when the mass
falls through the height ``L0 sin(alpha)``. Stance is integrated in Cartesian coordinates of the
mass relative to the foot (``solve_ivp``, DOP853, rtol 1e-12), the spring pushing along the leg;
lift-off is the event where the leg is back at its rest length (the ground's normal force, the
spring force times the leg's vertical direction cosine, reaches zero), located by ``solve_ivp``.

The apex-to-apex map at fixed system energy ``E = m g y0 + m v0²/2``: apex height ``y`` →
next apex height (the forward speed at an apex follows from the energy). Nothing here is
imported from amble.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq


@dataclass(frozen=True)
class Slip:
    m: float = 80.0
    L0: float = 1.0
    k: float = 20000.0
    alpha: float = math.radians(68.0)
    g: float = 9.81
    y0: float = 1.0
    v0: float = 5.0

    def apex_speed(self, y: float) -> float:
        """Forward speed at an apex of height ``y`` (m/s) on the energy level of (y0, v0)."""
        return math.sqrt(self.v0**2 + 2 * self.g * (self.y0 - y))

    def stride(self, y: float) -> dict:
        """One apex-to-apex stride from an apex at height ``y`` (x = 0): times (from the apex) of
        touchdown and lift-off, the next apex height and time, the states at the events."""
        g, L0, a = self.g, self.L0, self.alpha
        vx = self.apex_speed(y)
        y_td = L0 * math.sin(a)
        if y <= y_td:
            raise ValueError("apex below the touchdown height")
        t_td = math.sqrt(2 * (y - y_td) / g)
        vy_td = -g * t_td
        foot = vx * t_td + L0 * math.cos(a)
        # stance: mass position relative to the foot
        s0 = [-L0 * math.cos(a), y_td, vx, vy_td]
        k, m = self.k, self.m

        def rhs(_t, s):
            px, py, vx_, vy_ = s
            r = math.hypot(px, py)
            f = k * (L0 - r) / (m * r)  # spring force per mass along the unit leg vector / r
            return [vx_, vy_, f * px, f * py - g]

        def liftoff(_t, s):
            return math.hypot(s[0], s[1]) - L0

        liftoff.terminal, liftoff.direction = True, 1.0

        def fall(_t, s):
            return s[1]

        fall.terminal, fall.direction = True, -1.0
        # the leg starts at its rest length: begin the event search after it has compressed
        sol = solve_ivp(rhs, (0.0, 5.0), s0, method="DOP853", rtol=1e-12, atol=1e-12,
                        events=(liftoff, fall), dense_output=True, first_step=1e-6)
        if sol.status != 1 or len(sol.t_events[0]) == 0:
            raise ValueError("no lift-off")
        t_st = float(sol.t_events[0][0])
        px, py, vxl, vyl = sol.y_events[0][0]
        if vyl <= 0:
            raise ValueError("lift-off while falling: no apex")
        t_rise = vyl / g
        y_next = py + vyl**2 / (2 * g)
        return {"t_td": t_td, "t_lo": t_td + t_st, "t_apex": t_td + t_st + t_rise, "y_next": y_next,
                "vx_next": vxl, "x_next": foot + px + vxl * t_rise, "liftoff_state": (px, py, vxl, vyl),
                "stance_time": t_st}

    def from_flight(self, x: float, y: float, xd: float, yd: float) -> dict:
        """The stride from any flight state before touchdown (``x`` from the last apex, ``y`` the
        height, velocities in m/s), not only from an apex on the energy level: the states just
        after touchdown and lift-off in stance coordinates (the mass relative to the foot) and
        at the next apex (``x`` measured from that apex, so 0), with their times (s). Ballistic
        flight in closed form, stance as in :meth:`stride`."""
        g, L0, a, k, m = self.g, self.L0, self.alpha, self.k, self.m
        y_td = L0 * math.sin(a)
        # y + yd t − g t²/2 = y_td, the later root (falling through the touchdown height)
        t_td = (yd + math.sqrt(yd**2 + 2 * g * (y - y_td))) / g
        td = (-L0 * math.cos(a), y_td, xd, yd - g * t_td)

        def rhs(_t, s):
            px, py, vx_, vy_ = s
            r = math.hypot(px, py)
            f = k * (L0 - r) / (m * r)
            return [vx_, vy_, f * px, f * py - g]

        def liftoff(_t, s):
            return math.hypot(s[0], s[1]) - L0

        liftoff.terminal, liftoff.direction = True, 1.0
        sol = solve_ivp(rhs, (0.0, 5.0), td, method="DOP853", rtol=1e-13, atol=1e-13, events=liftoff,
                        first_step=1e-6)
        if sol.status != 1:
            raise ValueError("no lift-off")
        t_lo = t_td + float(sol.t_events[0][0])
        lo = tuple(float(v) for v in sol.y_events[0][0])
        t_rise = lo[3] / g
        apex = (0.0, lo[1] + lo[3] ** 2 / (2 * g), lo[2], 0.0)
        return {"touchdown": (t_td, np.array(td)), "liftoff": (t_lo, np.array(lo)),
                "apex": (t_lo + t_rise, np.array(apex))}

    def apex_map(self, y: float) -> float:
        return self.stride(y)["y_next"]

    def energy_check(self, y: float) -> float:
        """Relative energy change over one stride (zero for the exact flow)."""
        s = self.stride(y)
        e0 = self.m * self.g * y + 0.5 * self.m * self.apex_speed(y) ** 2
        e1 = self.m * self.g * s["y_next"] + 0.5 * self.m * s["vx_next"] ** 2
        return (e1 - e0) / e0

    def fixed_point(self, lo: float | None = None, hi: float | None = None, n: int = 60) -> list[float]:
        """Apex heights where ``P(y) = y`` between ``lo`` and ``hi`` (default: from just above the
        touchdown height to the energy's ceiling), bracketed on a grid of ``n`` and refined by brentq."""
        y_td = self.L0 * math.sin(self.alpha)
        top = self.y0 + self.v0**2 / (2 * self.g)
        lo = y_td + 1e-6 if lo is None else lo
        hi = top - 1e-6 if hi is None else hi

        def F(y):
            try:
                return self.apex_map(y) - y
            except ValueError:
                return math.nan

        ys = np.linspace(lo, hi, n)
        fs = [F(y) for y in ys]
        roots = []
        for i in range(n - 1):
            if np.isfinite(fs[i]) and np.isfinite(fs[i + 1]) and fs[i] * fs[i + 1] < 0:
                roots.append(brentq(F, ys[i], ys[i + 1], xtol=1e-14, rtol=1e-14))
        return roots

    def multiplier(self, y: float, h: float = 1e-5) -> float:
        """dP/dy at ``y`` by a five-point central difference of the map (error ~ h⁴). Near the
        touchdown height the map has a square-root singularity (the descent time grows as
        sqrt(y − L0 sin(alpha))), so the step shrinks to a twentieth of the apex's height above it."""
        h = min(h, (y - self.L0 * math.sin(self.alpha)) / 20)
        P = self.apex_map
        return (8 * (P(y + h) - P(y - h)) - (P(y + 2 * h) - P(y - 2 * h))) / (12 * h)

    def gaits(self, n: int = 40) -> list[tuple[float, float]]:
        """Every period-1 gait found on a grid of ``n`` apex heights: ``(apex height, dP/dy)``."""
        return [(y, self.multiplier(y)) for y in self.fixed_point(n=n)]

    def root_near(self, y: float, dy: float = 1e-4) -> float | None:
        """The fixed point in ``[y - dy, y + dy]`` if ``P(y) - y`` changes sign there, else None
        (``dy`` shrinks to half the apex's height above the touchdown height)."""
        def F(z):
            return self.apex_map(z) - z

        dy = min(dy, (y - self.L0 * math.sin(self.alpha)) / 2)  # stay above the touchdown height
        try:
            a, b = F(y - dy), F(y + dy)
        except ValueError:
            return None
        if a * b > 0:
            return None
        return brentq(F, y - dy, y + dy, xtol=1e-14, rtol=1e-14)
