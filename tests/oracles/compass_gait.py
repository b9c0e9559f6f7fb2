"""The passive compass gait written out by hand in Goswami, Thuilot & Espiau's form (their
equations as transcribed in docs/references.md, section 1), integrated with SciPy: the fixed point
of the step-to-step map, its multipliers, and the slope of the first period doubling.

Nothing here comes from amble. Conventions are Goswami's: q = [th_ns, th_s] (swing leg first),
absolute angles from the vertical, counter-clockwise positive; the walker moves toward +x down a
slope phi. Parameters: m = 5 kg per leg at a = 0.5 m from the foot, b = 0.5 m from the hip,
mH = 10 kg, l = a + b, g = 9.81.

Run as a script it prints the period-doubling slope (about 4.391 degrees, a few seconds)."""

from __future__ import annotations

import math

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

M_LEG, M_HIP, A, B, G = 5.0, 10.0, 0.5, 0.5, 9.81
L = A + B
RTOL = ATOL = 1e-12


def rhs(_t: float, x: np.ndarray) -> np.ndarray:
    """M(q) q'' + N(q, q') q' + g(q) = 0."""
    ns, s, dns, ds = x
    m, mh, a, b, l = M_LEG, M_HIP, A, B, L
    c, sn = math.cos(s - ns), math.sin(s - ns)
    M = np.array([[m * b * b, -m * l * b * c], [-m * l * b * c, (mh + m) * l * l + m * a * a]])
    N = np.array([[0.0, m * l * b * sn * ds], [-m * l * b * sn * dns, 0.0]])
    grav = G * np.array([m * b * math.sin(ns), -(mh * l + m * a + m * l) * math.sin(s)])
    qdd = np.linalg.solve(M, -N @ np.array([dns, ds]) - grav)
    return np.array([dns, ds, qdd[0], qdd[1]])


def impact(x: np.ndarray) -> np.ndarray:
    """Q+(alpha) q'+ = Q-(alpha) q'-, q+ = J q- (the legs swap), 2 alpha = th_ns- - th_s-."""
    ns, s, dns, ds = x
    m, mh, a, b, l = M_LEG, M_HIP, A, B, L
    c2 = math.cos(ns - s)
    qm = np.array([[-m * a * b, -m * a * b + (mh * l * l + 2 * m * a * l) * c2], [0.0, -m * a * b]])
    qp = np.array([[m * b * (b - l * c2), m * l * (l - b * c2) + m * a * a + mh * l * l], [m * b * b, -m * b * l * c2]])
    v = np.linalg.solve(qp, qm @ np.array([dns, ds]))
    return np.array([s, ns, v[0], v[1]])


def step(x: np.ndarray, phi: float) -> tuple[np.ndarray, float]:
    """Post-impact state to the next post-impact state, and the step time. Heel strike:
    th_ns + th_s = -2 phi with the swing leg in front (th_ns > th_s), crossed downward; the
    first 0.1 s (the guard is 0 at the start and the swing foot scuffs near mid-stance) is
    integrated without it."""
    early = solve_ivp(rhs, (0.0, 0.1), x, method="DOP853", rtol=RTOL, atol=ATOL)

    def strike(_t, y):
        return y[0] + y[1] + 2 * phi

    strike.terminal, strike.direction = True, -1
    sol = solve_ivp(rhs, (0.1, 5.0), early.y[:, -1], method="DOP853", rtol=RTOL, atol=ATOL, events=strike)
    (te,), (xe,) = sol.t_events[0], sol.y_events[0]
    assert xe[0] > xe[1], "the swing leg must be in front at heel strike"
    return impact(xe), float(te)


def _full(z: np.ndarray, phi: float) -> np.ndarray:
    """Post-impact state from the section coordinates z = [th_s, dth_ns, dth_s]."""
    return np.array([-2 * phi - z[0], z[0], z[1], z[2]])


def _map(z: np.ndarray, phi: float) -> np.ndarray:
    x, _ = step(_full(z, phi), phi)
    return x[1:]


def _jacobian(z: np.ndarray, phi: float, h: float = 1e-6) -> np.ndarray:
    return np.column_stack([(_map(z + h * e, phi) - _map(z - h * e, phi)) / (2 * h) for e in np.eye(3)])


def fixed_point(phi: float, z0=(0.2187, -0.377, -1.092)) -> tuple[np.ndarray, np.ndarray]:
    """Post-impact fixed point [th_ns, th_s, dth_ns, dth_s] on slope phi (rad), by Newton with a
    central-difference Jacobian, and the Jacobian of the 3-D section map there."""
    z = np.asarray(z0, float)
    for _ in range(20):
        jac = _jacobian(z, phi)
        dz = np.linalg.solve(jac - np.eye(3), -(_map(z, phi) - z))
        z = z + dz
        if np.max(np.abs(dz)) < 1e-11:
            break
    return _full(z, phi), _jacobian(z, phi)


def multipliers(phi: float) -> np.ndarray:
    return np.linalg.eigvals(fixed_point(phi)[1])


def first_period_doubling(lo_deg: float = 4.3, hi_deg: float = 4.5, xtol: float = 1e-7) -> float:
    """Slope (rad) where the period-1 gait's multiplier reaches -1: det(J + I) = 0."""
    start = [np.array([0.2187, -0.377, -1.092])]

    def flip(phi):
        x, jac = fixed_point(phi, start[0])
        start[0] = x[1:]
        return float(np.linalg.det(jac + np.eye(3)))

    return brentq(flip, math.radians(lo_deg), math.radians(hi_deg), xtol=xtol)


if __name__ == "__main__":
    print(math.degrees(first_period_doubling()))
