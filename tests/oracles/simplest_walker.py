"""The simplest walker of Garcia, Chatterjee, Ruina & Coleman (1998) written out by hand from
their equations (docs/references.md, section 2) and integrated with SciPy: the fixed points of
the step-to-step map, their step times and multipliers.

Nothing here comes from amble. Scaled units (g = l = 1, time in sqrt(l/g)); theta is the stance
leg's angle from the slope normal, phi the angle from the stance leg to the swing leg::

    theta'' = sin(theta - gamma)
    phi''   = sin(theta - gamma) + theta'^2 sin(phi) - cos(theta - gamma) sin(phi)

Heel strike: phi - 2 theta rises through 0 with theta < 0 (its downward crossing near
mid-stance is the swing foot scuffing, ignored). The impact and leg swap (their eq. 4)::

    theta+ = -theta-,   theta'+ = cos(2 theta-) theta'-,
    phi+ = -2 theta-,   phi'+ = cos(2 theta-) (1 - cos(2 theta-)) theta'-

Every post-impact state lies on phi = 2 theta, phi' = (1 - cos 2 theta) theta', so the map is
two-dimensional in z = (theta, theta'). Its Jacobian comes from the variational equations
integrated alongside the state and the saltation matrix at the heel strike (exact up to the
integration tolerance); ``jacobian_by_differences`` gives it again by central differences, as
a check of the first.

Run as a script it prints both gaits at gamma = 0.009 (well under a second each)."""

from __future__ import annotations

import math

import numpy as np
from scipy.integrate import solve_ivp

GAMMA = 0.009
RTOL = ATOL = 1e-13
#: the long- and short-period gaits of Garcia's code at gamma = 0.009, (theta*, theta'*)
LONG_GUESS = (0.2003109, -0.1998325)
SHORT_GUESS = (0.1939374, -0.2038669)


def rhs(x: np.ndarray, gamma: float) -> np.ndarray:
    th, ph, thd, phd = x
    thdd = math.sin(th - gamma)
    return np.array([thd, phd, thdd, thdd + thd**2 * math.sin(ph) - math.cos(th - gamma) * math.sin(ph)])


def rhs_jacobian(x: np.ndarray, gamma: float) -> np.ndarray:
    """d rhs / d (theta, phi, theta', phi')."""
    th, ph, thd, _ = x
    c, s = math.cos(th - gamma), math.sin(th - gamma)
    a = np.zeros((4, 4))
    a[0, 2] = a[1, 3] = 1.0
    a[2, 0] = c
    a[3, 0] = c + s * math.sin(ph)
    a[3, 1] = (thd**2 - c) * math.cos(ph)
    a[3, 2] = 2 * thd * math.sin(ph)
    return a


def _with_variations(_t: float, y: np.ndarray, gamma: float) -> np.ndarray:
    x, phi = y[:4], y[4:].reshape(4, 4)
    return np.concatenate([rhs(x, gamma), (rhs_jacobian(x, gamma) @ phi).ravel()])


def impact(x: np.ndarray) -> np.ndarray:
    th, _, thd, _ = x
    c = math.cos(2 * th)
    return np.array([-th, -2 * th, c * thd, c * (1 - c) * thd])


def impact_jacobian(x: np.ndarray) -> np.ndarray:
    th, _, thd, _ = x
    c, s = math.cos(2 * th), math.sin(2 * th)
    d = np.zeros((4, 4))
    d[0, 0], d[1, 0] = -1.0, -2.0
    d[2, 0], d[2, 2] = -2 * s * thd, c
    # d/dθ [c (1 − c)] = −2s (1 − c) + c · 2s = 2s (2c − 1)
    d[3, 0], d[3, 2] = 2 * s * (2 * c - 1) * thd, c * (1 - c)
    return d


def on_section(z: np.ndarray) -> np.ndarray:
    """Post-impact state (theta, phi, theta', phi') of z = (theta, theta')."""
    th, thd = z
    return np.array([th, 2 * th, thd, (1 - math.cos(2 * th)) * thd])


def _section_embedding(z: np.ndarray) -> np.ndarray:
    th, thd = z
    return np.array([[1.0, 0.0], [2.0, 0.0], [0.0, 1.0], [2 * math.sin(2 * th) * thd, 1 - math.cos(2 * th)]])


def _strike(_t, y, _gamma):
    return y[1] - 2 * y[0]


_strike.terminal, _strike.direction = True, +1


def _past_normal(_t, y, _gamma):
    return y[0]


_past_normal.terminal, _past_normal.direction = True, -1


def step(z: np.ndarray, gamma: float = GAMMA) -> tuple[np.ndarray, float, np.ndarray]:
    """One step from the section point z: the next post-impact z, the step time, and the 2 × 2
    Jacobian of the map there. The step runs in two legs, until theta crosses 0 (the guard is
    enabled only for theta < 0) and then to the heel strike."""
    z = np.asarray(z, float)
    y0 = np.concatenate([on_section(z), np.eye(4).ravel()])
    t0, t_end = 0.0, 20.0
    for event in (_past_normal, _strike):
        sol = solve_ivp(_with_variations, (t0, t_end), y0, method="DOP853", rtol=RTOL, atol=ATOL,
                        events=event, args=(gamma,))
        if sol.status != 1:
            raise RuntimeError(f"no {event.__name__} within {t_end} time units from {z}")
        t0, y0 = float(sol.t_events[0][0]), sol.y_events[0][0]
    x, phi = y0[:4], y0[4:].reshape(4, 4)
    assert x[0] < 0, "heel strike with the stance leg past the normal"
    # saltation: the strike time moves with the start, dt = -(dg x dx) / (dg . f)
    dg = np.array([-2.0, 1.0, 0.0, 0.0])
    f = rhs(x, gamma)
    salt = np.eye(4) - np.outer(f, dg) / (dg @ f)
    post = impact(x)
    full = impact_jacobian(x) @ salt @ phi @ _section_embedding(z)
    return post[[0, 2]], t0, full[[0, 2]]


def jacobian_by_differences(z: np.ndarray, gamma: float = GAMMA, h: float = 1e-6) -> np.ndarray:
    z = np.asarray(z, float)
    cols = [(step(z + h * e, gamma)[0] - step(z - h * e, gamma)[0]) / (2 * h) for e in np.eye(2)]
    return np.column_stack(cols)


def limit_cycle(gamma: float = GAMMA, guess: tuple[float, float] = LONG_GUESS) -> dict:
    """Newton on z -> step(z) - z. Returns the post-impact ``fixed_point`` (theta, phi, theta',
    phi'), the ``step_time`` (scaled), the ``multipliers`` (the two non-trivial eigenvalues of
    the 4-D stride map, equal to those of the 2-D map) and the final ``residual``."""
    z = np.asarray(guess, float)
    for _ in range(30):
        nxt, _, jac = step(z, gamma)
        dz = np.linalg.solve(jac - np.eye(2), -(nxt - z))
        z = z + dz
        if np.max(np.abs(dz)) < 1e-13:
            break
    nxt, period, jac = step(z, gamma)
    return dict(fixed_point=on_section(z), step_time=period, multipliers=np.linalg.eigvals(jac),
                residual=float(np.max(np.abs(nxt - z))), jacobian=jac)


if __name__ == "__main__":
    for name, guess in (("long", LONG_GUESS), ("short", SHORT_GUESS)):
        lc = limit_cycle(GAMMA, guess)
        print(name, lc["fixed_point"], lc["step_time"], lc["multipliers"], lc["residual"])
        by_differences = jacobian_by_differences(lc["fixed_point"][[0, 2]])
        print("  variational minus differences:", np.max(np.abs(lc["jacobian"] - by_differences)))
