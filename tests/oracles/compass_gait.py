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


#: (m, mH, a, b, g): the leg mass and hip mass (kg), the leg's mass from the foot and from the hip
#: (m), gravity (m/s²); every function takes another such tuple as ``par``.
DEFAULT = (M_LEG, M_HIP, A, B, G)


def rhs(_t: float, x: np.ndarray, par: tuple = DEFAULT) -> np.ndarray:
    """M(q) q'' + N(q, q') q' + g(q) = 0."""
    ns, s, dns, ds = x
    m, mh, a, b, g = par
    l = a + b
    c, sn = math.cos(s - ns), math.sin(s - ns)
    M = np.array([[m * b * b, -m * l * b * c], [-m * l * b * c, (mh + m) * l * l + m * a * a]])
    N = np.array([[0.0, m * l * b * sn * ds], [-m * l * b * sn * dns, 0.0]])
    grav = g * np.array([m * b * math.sin(ns), -(mh * l + m * a + m * l) * math.sin(s)])
    qdd = np.linalg.solve(M, -N @ np.array([dns, ds]) - grav)
    return np.array([dns, ds, qdd[0], qdd[1]])


def impact(x: np.ndarray, par: tuple = DEFAULT) -> np.ndarray:
    """Q+(alpha) q'+ = Q-(alpha) q'-, q+ = J q- (the legs swap), 2 alpha = th_ns- - th_s-."""
    ns, s, dns, ds = x
    m, mh, a, b, _ = par
    l = a + b
    c2 = math.cos(ns - s)
    qm = np.array([[-m * a * b, -m * a * b + (mh * l * l + 2 * m * a * l) * c2], [0.0, -m * a * b]])
    qp = np.array([[m * b * (b - l * c2), m * l * (l - b * c2) + m * a * a + mh * l * l], [m * b * b, -m * b * l * c2]])
    v = np.linalg.solve(qp, qm @ np.array([dns, ds]))
    return np.array([s, ns, v[0], v[1]])


def step(x: np.ndarray, phi: float, par: tuple = DEFAULT) -> tuple[np.ndarray, float]:
    """Post-impact state to the next post-impact state, and the step time. Heel strike:
    th_ns + th_s = -2 phi with the swing leg in front (th_ns > th_s), crossed downward; the
    first 0.1 s (the guard is 0 at the start and the swing foot scuffs near mid-stance) is
    integrated without it."""
    early = solve_ivp(rhs, (0.0, 0.1), x, method="DOP853", rtol=RTOL, atol=ATOL, args=(par,))

    def strike(_t, y, _par):
        return y[0] + y[1] + 2 * phi

    strike.terminal, strike.direction = True, -1
    sol = solve_ivp(rhs, (0.1, 5.0), early.y[:, -1], method="DOP853", rtol=RTOL, atol=ATOL, events=strike,
                    args=(par,))
    (te,), (xe,) = sol.t_events[0], sol.y_events[0]
    assert xe[0] > xe[1], "the swing leg must be in front at heel strike"
    return impact(xe, par), float(te)


def _full(z: np.ndarray, phi: float) -> np.ndarray:
    """Post-impact state from the section coordinates z = [th_s, dth_ns, dth_s]."""
    return np.array([-2 * phi - z[0], z[0], z[1], z[2]])


def _map(z: np.ndarray, phi: float, par: tuple = DEFAULT) -> np.ndarray:
    x, _ = step(_full(z, phi), phi, par)
    return x[1:]


def _jacobian(z: np.ndarray, phi: float, h: float = 1e-6, par: tuple = DEFAULT) -> np.ndarray:
    return np.column_stack([(_map(z + h * e, phi, par) - _map(z - h * e, phi, par)) / (2 * h) for e in np.eye(3)])


def fixed_point(phi: float, z0=(0.2187, -0.377, -1.092), par: tuple = DEFAULT) -> tuple[np.ndarray, np.ndarray]:
    """Post-impact fixed point [th_ns, th_s, dth_ns, dth_s] on slope phi (rad), by Newton with a
    central-difference Jacobian, and the Jacobian of the 3-D section map there; ``par`` as
    :data:`DEFAULT`."""
    z = np.asarray(z0, float)
    for _ in range(20):
        jac = _jacobian(z, phi, par=par)
        dz = np.linalg.solve(jac - np.eye(3), -(_map(z, phi, par) - z))
        z = z + dz
        if np.max(np.abs(dz)) < 1e-11:
            break
    return _full(z, phi), _jacobian(z, phi, par=par)


def follow(phi: float, par: tuple, stages: int = 8, z0=(0.2187, -0.377, -1.092), phi0: float = 0.05
           ) -> tuple[np.ndarray, np.ndarray]:
    """The fixed point at (phi, par) by natural-parameter continuation from Goswami's walker at
    slope phi0 (the guess ``z0`` lies near its gait): all of (phi, m, mH, a, b, g) move linearly
    in ``stages`` stages, each Newton's guess extrapolated from the last two gaits (secant)."""
    start = np.array([*DEFAULT, phi0])
    end = np.array([*par, phi])
    zs = [np.asarray(z0, float)]
    for k in range(1, stages + 1):
        v = start + (end - start) * k / stages
        guess = 2 * zs[-1] - zs[-2] if len(zs) > 1 else zs[-1]
        x, jac = fixed_point(v[-1], guess, tuple(v[:-1]))
        zs.append(x[1:])
    return x, jac


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
