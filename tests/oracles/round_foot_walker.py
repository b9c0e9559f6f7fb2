"""McGeer's round-foot walker written from its physics, independently of amble: SymPy's Lagrangian
with a rolling stance foot, a plastic impact solved as an impulse on the extended (floating)
coordinates, SciPy's DOP853 at rtol 1e-12 / atol 1e-13 with event location, and Newton on the
step-to-step map with a central-difference Jacobian.

World frame: x horizontal (downhill +), y up; the slope's tangent t = (cos γ, −sin γ) points
downhill and its normal n = (sin γ, cos γ) away from the ground. Legs: angles θ₁ (stance), θ₂
(swing) from the vertical, the direction foot → hip being e(θ) = (sin θ, cos θ). The stance foot
is an arc of radius r centred C at l from the hip; rolling without slip puts C at
r n + r (θ₁ − γ) t (a wheel turning by Δθ advances by r Δθ). Hip H = C + l e(θ₁); each leg's
mass m at H − c e(θᵢ), moment of inertia I about it; hip mass mh. Gravity g along −y.

Heel strike: the swing foot's arc (centre H − l e(θ₂)) reaches the ground, n·centre = r, with the
swing foot ahead (θ₁ > θ₂; the same equation also holds at mid-stance, where the legs pass and the
foot scuffs). Impact: the stance foot centre is freed (coordinates X = (Cx, Cy, θ₁, θ₂)), the
impulse acts only on the material point of the swing foot at the contact, and after it that
point is at rest (no slip, no bounce): M_X (Ẋ⁺ − Ẋ⁻) = Jᵀ Λ, J Ẋ⁺ = 0. Then the legs swap.

State: (θ₁, θ₂, θ̇₁, θ̇₂) in rad, rad/s; parameters by amble's round-foot-walker names (mh, m,
I, l, c, r, g, slope) so that tests can pass one dictionary to both.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np
import sympy as sp
from scipy.integrate import solve_ivp

RTOL, ATOL = 1e-12, 1e-13
NAMES = ("mh", "m", "I", "l", "c", "r", "g", "slope")


@lru_cache(maxsize=1)
def _derived():
    """Lambdified q̈(q, q̇, p), the extended mass matrix M_X(q, p) and the contact Jacobian J(q, p)."""
    th1, th2, w1, w2 = sp.symbols("th1 th2 w1 w2", real=True)
    cx, cy, vx, vy = sp.symbols("cx cy vx vy", real=True)
    mh, m, inertia, l, c, r, g, gam = sp.symbols(" ".join(NAMES), real=True)
    e = lambda a: sp.Matrix([sp.sin(a), sp.cos(a)])  # noqa: E731
    t, n = sp.Matrix([sp.cos(gam), -sp.sin(gam)]), sp.Matrix([sp.sin(gam), sp.cos(gam)])

    def lagrangian(centre, coords, speeds):
        hip = centre + l * e(th1)
        bodies = [(mh, hip), (m, hip - c * e(th1)), (m, hip - c * e(th2))]
        vel = lambda p: p.jacobian(coords) * speeds  # noqa: E731
        kin = sum(mi * (vel(p).T * vel(p))[0] for mi, p in bodies) / 2 + inertia * (w1**2 + w2**2) / 2
        pot = g * sum(mi * p[1] for mi, p in bodies)
        return kin, pot, hip

    # single support: the stance foot rolls
    q, u = sp.Matrix([th1, th2]), sp.Matrix([w1, w2])
    kin, pot, _ = lagrangian(r * n + r * (th1 - gam) * t, q, u)
    L = kin - pot
    M = sp.hessian(kin, u)
    # d/dt ∂L/∂q̇ − ∂L/∂q = M q̈ + (∂²L/∂q̇∂q) q̇ − ∂L/∂q
    rest = sp.Matrix([sum(sp.diff(L, u[i], q[j]) * u[j] for j in range(2)) - sp.diff(L, q[i]) for i in range(2)])
    acc = sp.lambdify([th1, th2, w1, w2, mh, m, inertia, l, c, r, g, gam], M.LUsolve(-rest), "numpy")
    # impact: the stance foot's centre free
    X, V = sp.Matrix([cx, cy, th1, th2]), sp.Matrix([vx, vy, w1, w2])
    kin_x, _, hip = lagrangian(sp.Matrix([cx, cy]), X, V)
    MX = sp.hessian(kin_x, V)
    # the swing leg's material point at the contact: the foot's centre − r n; the leg turns at
    # −θ̇₂ about z (θ grows clockwise), so that point's velocity is Ḣ + ω × (point − H)
    contact = hip - l * e(th2) - r * n
    arm = contact - hip
    hip_vel = hip.jacobian(X) * V
    point_vel = hip_vel + (-w2) * sp.Matrix([-arm[1], arm[0]])
    J = point_vel.jacobian(V)
    args = [cx, cy, th1, th2, mh, m, inertia, l, c, r, g, gam]
    return acc, sp.lambdify(args, MX, "numpy"), sp.lambdify(args, J, "numpy")


def _p(params: dict) -> list[float]:
    return [float(params[k]) for k in NAMES]


def rhs(_t: float, x: np.ndarray, p: list[float]) -> np.ndarray:
    acc = _derived()[0]
    a = np.asarray(acc(*x, *p), float).ravel()
    return np.array([x[2], x[3], a[0], a[1]])


def height(x: np.ndarray, p: list[float]) -> float:
    """Height of the swing foot's arc above the slope (m): n·(its centre) − r."""
    _, _, _, l, _, r, _, gam = p
    n = np.array([np.sin(gam), np.cos(gam)])
    e = lambda a: np.array([np.sin(a), np.cos(a)])  # noqa: E731
    centre = r * n + r * (x[0] - gam) * np.array([np.cos(gam), -np.sin(gam)])
    return float(n @ (centre + l * e(x[0]) - l * e(x[1])) - r)


def impact(x: np.ndarray, p: list[float]) -> np.ndarray:
    """Pre-impact state → post-impact state (legs swapped)."""
    _, MX, J = _derived()
    _, _, _, _, _, r, _, gam = p
    th1, th2, w1, w2 = x
    vc = r * w1 * np.array([np.cos(gam), -np.sin(gam)])  # the rolling centre's velocity
    Mx = np.asarray(MX(0.0, 0.0, th1, th2, *p), float)
    Jx = np.asarray(J(0.0, 0.0, th1, th2, *p), float)
    v_minus = np.r_[vc, w1, w2]
    K = np.block([[Mx, -Jx.T], [Jx, np.zeros((2, 2))]])
    sol = np.linalg.solve(K, np.r_[Mx @ v_minus, 0.0, 0.0])
    v_plus = sol[:4]
    return np.array([th2, th1, v_plus[3], v_plus[2]])


def step(x: np.ndarray, params: dict) -> tuple[np.ndarray, float]:
    """Post-impact state → next post-impact state and the step time (s)."""
    p = _p(params)

    def strike(_t, y, p):
        return height(y, p)

    strike.terminal, strike.direction = True, -1
    t0, y0 = 0.0, np.asarray(x, float)
    tscale = np.sqrt(p[3] / p[6])  # √(l/g): the walker's own time unit
    for _ in range(4):  # a crossing with the legs side by side is the mid-stance scuff: go on
        sol = solve_ivp(rhs, (t0, t0 + 40 * tscale), y0, method="DOP853", rtol=RTOL, atol=ATOL, events=strike,
                        args=(p,))
        if not sol.t_events[0].size:
            raise RuntimeError("no heel strike")
        te, xe = float(sol.t_events[0][0]), sol.y_events[0][0]
        if xe[0] - xe[1] > 1e-3:
            return impact(xe, p), te
        nudge = solve_ivp(rhs, (te, te + 1e-3 * tscale), xe, method="DOP853", rtol=RTOL, atol=ATOL, args=(p,))
        t0, y0 = float(nudge.t[-1]), nudge.y[:, -1]
    raise RuntimeError("no heel strike with the swing foot ahead")


def _full(z: np.ndarray, params: dict) -> np.ndarray:
    """Post-impact state from the section coordinates (θ₁, θ̇₁, θ̇₂): both arcs on the ground,
    n·C₁ = n·C₂, i.e. cos(θ₁ − γ) = cos(θ₂ − γ) with the legs apart: θ₂ = 2γ − θ₁."""
    return np.array([z[0], 2 * params["slope"] - z[0], z[1], z[2]])


def _map(z: np.ndarray, params: dict) -> tuple[np.ndarray, float]:
    x, T = step(_full(z, params), params)
    return x[[0, 2, 3]], T


def fixed_point(params: dict, x0, tol: float = 1e-11, h: float = 1e-6) -> tuple[np.ndarray, float, np.ndarray]:
    """Newton on the section map from the post-impact state ``x0``: (fixed point, step time,
    multipliers from the central-difference Jacobian)."""
    z = np.asarray(x0, float)[[0, 2, 3]]
    for _ in range(20):
        jac = np.column_stack([(_map(z + h * e, params)[0] - _map(z - h * e, params)[0]) / (2 * h)
                               for e in np.eye(3)])
        Pz, T = _map(z, params)
        if np.max(np.abs(Pz - z)) < tol:
            return _full(z, params), T, np.linalg.eigvals(jac)
        z = z + np.linalg.solve(jac - np.eye(3), -(Pz - z))
    raise RuntimeError("Newton did not converge")
