"""Hsu Chen's passive kneed walker (point feet; MIT M.Eng. thesis 2007, Tedrake's
``kneedCompassGait.m``), written out here from docs/references.md section 3a and integrated with
SciPy: its exact continuous-time limit cycle, step time and multipliers.

Nothing here comes from amble. The swing phase's equations are Lagrange's for the point masses,
formed by SymPy from the positions below; the knee-strike and heel-strike maps are the matrices
of ``kneedCompassGait.m`` as transcribed in docs/references.md.

Conventions (hers, Goswami's): absolute angles from the vertical, counter-clockwise positive, the
walker moving toward +x. q1 the stance leg (knee locked), q2 the swing thigh, q3 the swing shank.
Masses: the stance leg's ms at a1 and mt at ls + a2 above its foot; mH at the hip; the swing
thigh's mt at b2 below the hip, the swing shank's ms at b1 below the knee. lt = a2 + b2,
ls = a1 + b1, l = lt + ls. A step: unlocked 3-link swing until q3 reaches q2 (knee strike, the
knee locks), locked 2-link motion until q1 + q2 = -2 gamma with q2 > q1 (heel strike, the legs
swap, the new swing knee straight).

Run as a script it prints the fixed point, step time and multipliers (a few seconds)."""

from __future__ import annotations

import math
from functools import cache

import numpy as np
import sympy as sp
from scipy.integrate import solve_ivp

#: Table 3.1 of the thesis, g = 9.8 (the code's), the code's slope asin(7.25/144)
PARAMS = dict(mh=0.5, mt=0.5, ms=0.05, a1=0.375, b1=0.125, a2=0.175, b2=0.325, g=9.8, slope=math.asin(7.25 / 144))
RTOL = ATOL = 1e-12


@cache
def _dynamics(locked: bool):
    """NumPy function (q, q', params) → q'' of the unlocked (3 coordinates) or locked (2) phase."""
    mh, mt, ms, a1, b1, a2, b2, g = sp.symbols("mh mt ms a1 b1 a2 b2 g", positive=True)
    lt, ls = a2 + b2, a1 + b1
    l = lt + ls
    n = 2 if locked else 3
    q = sp.symbols(f"q1:{n + 1}")
    qd = sp.symbols(f"qd1:{n + 1}")
    q1, q2 = q[0], q[1]
    q3 = q[1] if locked else q[2]
    up = lambda th: sp.Matrix([-sp.sin(th), sp.cos(th)])  # noqa: E731  foot → hip of a leg at th
    down = lambda th: sp.Matrix([sp.sin(th), -sp.cos(th)])  # noqa: E731  hip → foot
    hip = l * up(q1)
    knee = hip + lt * down(q2)
    points = [(ms, a1 * up(q1)), (mt, (ls + a2) * up(q1)), (mh, hip), (mt, hip + b2 * down(q2)),
              (ms, knee + b1 * down(q3))]
    T, V = sp.Integer(0), sp.Integer(0)
    for m, r in points:
        v = r.jacobian(q) * sp.Matrix(qd)
        T += m * (v.T * v)[0] / 2
        V += m * g * r[1]
    M = sp.hessian(T, qd)
    # M q'' + C = 0 with C = (dM/dt) q' − ∂T/∂q + ∂V/∂q
    dM = sum((sp.diff(M, qi) * qdi for qi, qdi in zip(q, qd)), sp.zeros(n, n))
    C = dM * sp.Matrix(qd) - sp.Matrix([sp.diff(T, qi) for qi in q]) + sp.Matrix([sp.diff(V, qi) for qi in q])
    args = [*q, *qd, mh, mt, ms, a1, b1, a2, b2, g]
    fM, fC = sp.lambdify(args, M, "numpy"), sp.lambdify(args, C, "numpy")

    def qdd(x, p):
        a = [*x, p["mh"], p["mt"], p["ms"], p["a1"], p["b1"], p["a2"], p["b2"], p["g"]]
        return np.linalg.solve(np.array(fM(*a), float), -np.array(fC(*a), float).ravel())

    return qdd


def _lengths(p):
    lt, ls = p["a2"] + p["b2"], p["a1"] + p["b1"]
    return lt, ls, lt + ls


def knee_strike(x: np.ndarray, p: dict) -> np.ndarray:
    """[q1, q2, q3, q1', q2', q3'] just before the knee locks → [q1, q2, q1', q2'] just after."""
    q1, q2, q3, d1, d2, d3 = x
    mh, mt, ms, a1, b1, a2, b2 = (p[k] for k in ("mh", "mt", "ms", "a1", "b1", "a2", "b2"))
    lt, ls, l = _lengths(p)
    a, b, c = q1 - q2, q1 - q3, q2 - q3
    qm = np.array([
        [ms * a1**2 + mt * a2**2 + (-mt * l * b2 - ms * l * lt) * math.cos(a) + mh * l**2 + ms * l**2
         - ms * b1 * l * math.cos(b) + 2 * mt * a2 * ls + mt * l**2 + mt * ls**2,
         (-mt * l * b2 - ms * l * lt) * math.cos(a) + mt * b2**2 + ms * b1 * lt * math.cos(c) + ms * lt**2,
         -ms * b1 * l * math.cos(b) + ms * b1**2 + ms * b1 * lt * math.cos(c)],
        [(-mt * l * b2 - ms * l * lt) * math.cos(a) - ms * b1 * l * math.cos(b),
         ms * b1 * lt * math.cos(c) + ms * lt**2 + mt * b2**2,
         ms * b1 * lt * math.cos(c) + ms * b1**2]])
    k = (-ms * l * lt - mt * l * b2 - ms * b1 * l) * math.cos(a)
    qp = np.array([
        [k + ms * a1**2 + ms * l**2 + 2 * mt * a2 * ls + mt * a2**2 + mt * ls**2 + mt * l**2 + mh * l**2,
         k + ms * lt**2 + 2 * ms * b1 * lt + ms * b1**2 + mt * b2**2],
        [k, ms * b1**2 + 2 * ms * b1 * lt + ms * lt**2 + mt * b2**2]])
    v = np.linalg.solve(qp, qm @ np.array([d1, d2, d3]))
    return np.array([q1, q2, v[0], v[1]])


def heel_strike(x: np.ndarray, p: dict) -> np.ndarray:
    """[q1, q2, q1', q2'] (locked) just before heel strike → [q1, q2, q3, q1', q2', q3'] just after."""
    q1, q2, d1, d2 = x
    mh, mt, ms, a1, b1, a2, b2 = (p[k] for k in ("mh", "mt", "ms", "a1", "b1", "a2", "b2"))
    lt, ls, l = _lengths(p)
    alpha = q2 - q1
    K = ms * a1 * (lt + b1) + mt * b2 * (ls + a2)
    kk = -l * (ms * (b1 + lt) + mt * b2) * math.cos(alpha)
    qm = np.array([[-K + l * math.cos(alpha) * (mh * l + 2 * (mt * (a2 + ls) + ms * a1)), -K], [-K, 0.0]])
    qp = np.array([[kk + l**2 * (ms + mt + mh) + ms * a1**2 + mt * (a2 + ls)**2, kk + ms * (b1 + lt)**2 + mt * b2**2],
                   [kk, mt * b2**2 + ms * (b1 + lt)**2]])
    v = np.linalg.solve(qp, qm @ np.array([d1, d2]))
    return np.array([q2, q1, q1, v[0], v[1], v[1]])


def _flow(locked: bool, p: dict):
    f = _dynamics(locked)
    n = 2 if locked else 3
    return lambda _t, x: np.concatenate([x[n:], f(x, p)])


def step(x: np.ndarray, p: dict) -> tuple[np.ndarray, float, float]:
    """One step from just after heel strike to just after the next: the state, the knee-strike
    time and the step time. The first 0.02 s of each phase are integrated without its guard
    (which is 0 at the start of the swing)."""
    unlocked, locked = _flow(False, p), _flow(True, p)

    def knee(_t, y):
        return y[2] - y[1]

    knee.terminal, knee.direction = True, 1
    x = solve_ivp(unlocked, (0.0, 0.02), x, method="DOP853", rtol=RTOL, atol=ATOL).y[:, -1]
    sol = solve_ivp(unlocked, (0.02, 3.0), x, method="DOP853", rtol=RTOL, atol=ATOL, events=knee)
    (tk,), (xk,) = sol.t_events[0], sol.y_events[0]
    gamma = p["slope"]

    def heel(_t, y):
        return y[0] + y[1] + 2 * gamma

    heel.terminal, heel.direction = True, -1
    sol = solve_ivp(locked, (tk, 5.0), knee_strike(xk, p), method="DOP853", rtol=RTOL, atol=ATOL, events=heel)
    (th,), (xh,) = sol.t_events[0], sol.y_events[0]
    assert xh[1] > xh[0], "the swing leg must be in front at heel strike"
    return heel_strike(xh, p), float(tk), float(th)


def _full(z: np.ndarray, p: dict) -> np.ndarray:
    """Post-heel-strike state from z = [q1, q1', q2']: q2 = q3 = -2 gamma - q1, q3' = q2'."""
    q2 = -2 * p["slope"] - z[0]
    return np.array([z[0], q2, q2, z[1], z[2], z[2]])


def _map(z: np.ndarray, p: dict) -> np.ndarray:
    x = step(_full(z, p), p)[0]
    return x[[0, 3, 4]]


def _jacobian(z: np.ndarray, p: dict, h: float = 1e-6) -> np.ndarray:
    return np.column_stack([(_map(z + h * e, p) - _map(z - h * e, p)) / (2 * h) for e in np.eye(3)])


def limit_cycle(p: dict | None = None, z0=(0.1877, -1.1014, -0.0399)) -> dict:
    """Fixed point (post heel strike, hers: [q1, q2, q3, q1', q2', q3']), knee-strike time, step
    time and the multipliers of the 3-D section map, by Newton with central differences."""
    p = dict(PARAMS, **(p or {}))
    z = np.asarray(z0, float)
    for _ in range(30):
        jac = _jacobian(z, p)
        dz = np.linalg.solve(jac - np.eye(3), z - _map(z, p))
        z = z + dz
        if np.max(np.abs(dz)) < 1e-11:
            break
    else:
        raise RuntimeError("Newton did not converge")
    x = _full(z, p)
    _, tk, ts = step(x, p)
    return dict(fixed_point=x, knee_time=tk, step_time=ts, multipliers=np.linalg.eigvals(_jacobian(z, p)))


if __name__ == "__main__":
    for k, v in limit_cycle().items():
        print(k, v)
