"""Independent bipedal spring-mass runner with swing-leg retraction: SciPy and NumPy only.

Written from the physics (Seyfarth, Geyer & Herr 2003, "Swing-leg retraction: a simple control
model for stable running", J. Exp. Biol. 206:2547–2555): a point mass ``m`` on two massless linear
spring legs (stiffness ``k``, rest length ``L0``) that take turns; one is on the ground at a time
and flight phases separate the stances. In flight the leg about to land turns backwards at a
constant rate ``omega`` (rad/s) from the angle ``alpha`` (from the horizontal ground, the foot
ahead of the mass) it has at the apex: ``angle(t) = alpha + omega (t − t_apex)``. It lands when
the mass falls through ``L0 sin(angle(t))``, the foot placed ``L0 cos(angle)`` ahead of the mass.
Stance is integrated in Cartesian coordinates of the mass relative to the foot (``solve_ivp``,
DOP853, rtol 1e-13), lift-off is the leg back at its rest length (the normal force through zero).
Flight is ballistic (closed form); the touchdown time is the root of
``y − g τ²/2 − L0 sin(alpha + omega τ)`` (brentq). The legs being massless, both legs and
hence the one-step map are the same for either leg: a gait of the biped is a fixed point of the
apex-to-apex map, apex height ``y`` → next apex height, at the system energy
``E = m g y0 + m v0²/2`` (the forward speed at an apex follows from the energy).

The fixed point is found by a Newton iteration written here, with a central-difference
derivative of the map. Nothing here is imported from amble.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

from scipy.integrate import solve_ivp
from scipy.optimize import brentq


@dataclass(frozen=True)
class BipedRunner:
    m: float = 80.0
    L0: float = 1.0
    k: float = 20000.0
    alpha: float = math.radians(66.0)
    omega: float = math.radians(60.0)
    g: float = 9.81
    y0: float = 1.0
    v0: float = 5.0

    def apex_speed(self, y: float) -> float:
        """Forward speed (m/s) at an apex ``y`` m high on the energy level of (y0, v0)."""
        return math.sqrt(self.v0**2 + 2 * self.g * (self.y0 - y))

    def energy(self, y: float, xd: float, yd: float, leg: float = None) -> float:
        """Total energy (J): height, speed, and the spring compressed to length ``leg`` (if given)."""
        spring = 0.0 if leg is None else 0.5 * self.k * (self.L0 - leg) ** 2
        return self.m * self.g * y + 0.5 * self.m * (xd**2 + yd**2) + spring

    def touchdown_time(self, y: float) -> float:
        """Time (s) from an apex at height ``y`` to touchdown: the first root of
        ``y − g τ²/2 − L0 sin(alpha + omega τ)``."""
        g, L0, a, w = self.g, self.L0, self.alpha, self.omega

        def h(tau):
            return y - 0.5 * g * tau**2 - L0 * math.sin(a + w * tau)

        if h(0.0) <= 0:
            raise ValueError("apex below the landing leg's reach")
        hi = 0.01
        while h(hi) > 0:
            hi *= 1.5
        return brentq(h, 0.0, hi, xtol=1e-15, rtol=1e-15)

    def stride(self, y: float) -> dict:
        """One step from an apex at height ``y`` (x = 0): event times (s, from the apex), the leg
        angle at touchdown, states at touchdown and lift-off (the mass relative to the foot), the
        next apex height and forward speed."""
        g, L0, k, m = self.g, self.L0, self.k, self.m
        vx = self.apex_speed(y)
        t_td = self.touchdown_time(y)
        ang = self.alpha + self.omega * t_td
        s0 = [-L0 * math.cos(ang), y - 0.5 * g * t_td**2, vx, -g * t_td]

        def rhs(_t, s):
            px, py, vx_, vy_ = s
            r = math.hypot(px, py)
            f = k * (L0 - r) / (m * r)
            return [vx_, vy_, f * px, f * py - g]

        def liftoff(_t, s):
            return math.hypot(s[0], s[1]) - L0

        liftoff.terminal, liftoff.direction = True, 1.0

        def fall(_t, s):
            return s[1]

        fall.terminal, fall.direction = True, -1.0
        sol = solve_ivp(rhs, (0.0, 5.0), s0, method="DOP853", rtol=1e-13, atol=1e-13, events=(liftoff, fall),
                        first_step=1e-6)
        if sol.status != 1 or len(sol.t_events[0]) == 0:
            raise ValueError("no lift-off")
        t_st = float(sol.t_events[0][0])
        lo = [float(v) for v in sol.y_events[0][0]]
        if lo[3] <= 0:
            raise ValueError("lift-off while falling: no flight phase")
        t_rise = lo[3] / g
        return {"t_td": t_td, "t_lo": t_td + t_st, "t_apex": t_td + t_st + t_rise, "angle_td": ang,
                "touchdown": s0, "liftoff": lo, "y_next": lo[1] + lo[3] ** 2 / (2 * g), "vx_next": lo[2],
                "step_length": vx * t_td + L0 * math.cos(ang) + lo[0] + lo[2] * t_rise}

    def apex_map(self, y: float) -> float:
        return self.stride(y)["y_next"]

    def derivative(self, y: float, h: float = 1e-5) -> float:
        """dP/dy by a five-point central difference (error ~ h⁴)."""
        P = self.apex_map
        return (8 * (P(y + h) - P(y - h)) - (P(y + 2 * h) - P(y - 2 * h))) / (12 * h)

    def fixed_point(self, y: float, tol: float = 1e-13, max_iter: int = 30) -> float:
        """Newton's iteration on ``P(y) − y`` from ``y``, with a central-difference derivative."""
        for _ in range(max_iter):
            r = self.apex_map(y) - y
            h = 1e-6
            d = (self.apex_map(y + h) - self.apex_map(y - h)) / (2 * h) - 1.0
            dy = -r / d
            y += dy
            if abs(dy) < tol:
                return y
        raise RuntimeError("Newton did not converge")

    def multiplier(self, y: float) -> float:
        """The gait's Floquet multiplier: dP/dy at its apex height ``y``."""
        return self.derivative(y)

    def fixed_angle(self, y: float) -> BipedRunner:
        """The runner without retraction whose leg lands at the angle this one's does from an apex
        at ``y``: both run the same gait when ``y`` is its apex."""
        return replace(self, alpha=self.stride(y)["angle_td"], omega=0.0)
