"""Independent 3D spring-loaded inverted pendulum (SLIP) runner: SciPy and NumPy only.

Written from the physics (Seipel & Holmes 2005, "Running in three dimensions: analysis of a
point-mass sprung-leg model", Int. J. Robotics Research 24(8):657–674): a point mass ``m`` on a
massless linear spring leg (stiffness ``k``, rest length ``L0``), ``z`` up, ``x`` the mean
direction of running. Flight is ballistic (closed form). The leg touches down when the mass falls
through the height ``L0 sin(alpha)``, the foot at ``L0 (cos(alpha) cos(beta), cos(alpha) sin(beta),
−sin(alpha))`` from the mass: ``alpha`` the leg's elevation from the ground, ``beta`` its azimuth
from ``+x`` towards this step's stance side, both fixed in the world frame (``placement="world"``)
or, with ``placement="heading"``, the azimuth measured from the mass's horizontal velocity instead
of ``+x``. Stance is integrated in Cartesian coordinates of the mass relative to the foot
(``solve_ivp``, DOP853, tolerances 1e-13); lift-off is the event where the leg is back at its rest
length. Left and right legs alternate: the next step's stance side is ``−y``, so each apex state
is mirrored (``y_dot → −y_dot``) and the symmetric left–right gait is a fixed point of one step.

The apex-to-apex map at fixed energy ``E = m g z0 + m v0²/2`` acts on ``(z, y_dot)``, the apex
height (m) and lateral velocity (m/s, towards the coming stance foot when > 0); the forward speed
follows from the energy. Its fixed point is found by Newton's method on central-difference
Jacobians, its multipliers are the eigenvalues of the central-difference Jacobian. Nothing here
is imported from amble.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp

TOL = 1e-13


@dataclass(frozen=True)
class Slip3D:
    m: float = 80.0
    L0: float = 1.0
    k: float = 20000.0
    alpha: float = math.radians(68.0)
    beta: float = math.radians(5.0)
    g: float = 9.81
    z0: float = 1.0
    v0: float = 5.0
    placement: str = "world"

    def forward_speed(self, z: float, yd: float) -> float:
        """Forward speed (m/s) at an apex of height ``z`` and lateral velocity ``yd`` on the energy level."""
        return math.sqrt(self.v0**2 + 2 * self.g * (self.z0 - z) - yd**2)

    def _foot(self, xd: float, yd: float) -> np.ndarray:
        """The foot relative to the mass at touchdown (m)."""
        az = self.beta + (math.atan2(yd, xd) if self.placement == "heading" else 0.0)
        c = math.cos(self.alpha)
        return self.L0 * np.array([c * math.cos(az), c * math.sin(az), -math.sin(self.alpha)])

    def _stance(self, s0: np.ndarray):
        k, m, L0, g = self.k, self.m, self.L0, self.g

        def rhs(_t, s):
            p = s[:3]
            r = math.sqrt(p @ p)
            return np.concatenate([s[3:], k * (L0 - r) / (m * r) * p - [0.0, 0.0, g]])

        def liftoff(_t, s):
            return math.sqrt(s[:3] @ s[:3]) - L0

        liftoff.terminal, liftoff.direction = True, 1.0
        # the leg starts at its rest length and shortens: the first step keeps the start off the event
        sol = solve_ivp(rhs, (0.0, 5.0), s0, method="DOP853", rtol=TOL, atol=TOL, events=liftoff, first_step=1e-6)
        if sol.status != 1:
            raise ValueError("no lift-off")
        return float(sol.t_events[0][0]), np.array(sol.y_events[0][0])

    def from_flight(self, state) -> dict:
        """The step from a flight state ``(x, y, z, x_dot, y_dot, z_dot)`` before touchdown: the
        states just after touchdown and lift-off (the mass relative to the foot) and at the next
        apex (origin under the mass, the lateral axis mirrored, the speed kept), with their times
        (s) from the start."""
        _, _, z, xd, yd, zd = (float(v) for v in state)
        g = self.g
        zt = self.L0 * math.sin(self.alpha)
        t_td = (zd + math.sqrt(zd**2 + 2 * g * (z - zt))) / g  # the later root: falling through zt
        td = np.concatenate([-self._foot(xd, yd), [xd, yd, zd - g * t_td]])
        t_st, lo = self._stance(td)
        if lo[5] <= 0:
            raise ValueError("lift-off while falling: no apex")
        t_rise = lo[5] / g
        apex = np.array([0.0, 0.0, lo[2] + lo[5] ** 2 / (2 * g), lo[3], -lo[4], 0.0])
        return {"touchdown": (t_td, td), "liftoff": (t_td + t_st, lo), "apex": (t_td + t_st + t_rise, apex)}

    def apex_state(self, z: float, yd: float) -> np.ndarray:
        return np.array([0.0, 0.0, z, self.forward_speed(z, yd), yd, 0.0])

    def apex_map(self, p) -> np.ndarray:
        """``(z, y_dot)`` at an apex → the same at the next apex (mirrored)."""
        nxt = self.from_flight(self.apex_state(*p))["apex"][1]
        return nxt[[2, 4]]

    def jacobian(self, p, h: float = 1e-6) -> np.ndarray:
        """Central-difference Jacobian of the apex map (error ~ h², plus the integration's ~1e-13 / h)."""
        p = np.asarray(p, float)
        J = np.zeros((2, 2))
        for j in range(2):
            d = np.zeros(2)
            d[j] = h
            J[:, j] = (self.apex_map(p + d) - self.apex_map(p - d)) / (2 * h)
        return J

    def fixed_point(self, guess=(0.939, 0.04), tol: float = 1e-13, max_iter: int = 20) -> np.ndarray:
        """The symmetric gait: ``P(p) = p`` by Newton's method."""
        p = np.asarray(guess, float)
        for _ in range(max_iter):
            r = self.apex_map(p) - p
            if np.max(np.abs(r)) <= tol:
                return p
            p = p - np.linalg.solve(self.jacobian(p) - np.eye(2), r)
        raise ValueError(f"Newton did not converge (residual {np.max(np.abs(r)):.1e})")

    def multipliers(self, p) -> np.ndarray:
        """Eigenvalues of the apex map's Jacobian, largest modulus first."""
        mu = np.linalg.eigvals(self.jacobian(p))
        return mu[np.argsort(-np.abs(mu))]
