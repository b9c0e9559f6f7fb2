"""Independent planar four-bar linkage under gravity (NumPy/SciPy only, nothing from amble).

Ground link from ``O = (0, 0)`` to ``D = (d, 0)``; the crank (length ``a``) turns about ``O`` at
the absolute angle ``θ1`` (from the +x axis, counter-clockwise), the coupler (``b``) runs from the
crank's tip ``B`` at ``θ2``, the rocker (``c``) turns about ``D`` at ``θ3`` and meets the coupler
at ``C``. Each link is a uniform rod (mass ``m_i``, moment ``m_i l_i²/12`` about its centre);
gravity ``g`` along −z. The loop closes when

    ``f(θ) = (a cos θ1 + b cos θ2 − d − c cos θ3,  a sin θ1 + b sin θ2 − c sin θ3) = 0``.

Two ways to the motion, written independently of each other:

* :func:`reduced_motion`: one degree of freedom. Closed-form position analysis (the triangle
  ``B C D`` by the law of cosines), the velocity ratios ``s = dθ/dθ1`` and their derivatives
  ``σ = d²θ/dθ1²`` from the closure, the effective inertia ``m(θ1)`` and Lagrange's equation
  ``m θ̈1 + ½ m' θ̇1² + V' = 0``, integrated by ``solve_ivp`` (DOP853).
* :func:`kkt`: the three angles with the closure as constraints; ``M``, ``h`` written by hand
  from the rods' kinetic and potential energies, and the KKT system
  ``M θ̈ + h = Jᵀλ``, ``J θ̈ = −J̇ θ̇`` solved by ``numpy.linalg.solve``.
"""

from __future__ import annotations

import numpy as np
from scipy.integrate import solve_ivp

#: ground, crank, coupler, rocker lengths (m); Grashof crank–rocker: the crank turns fully
LINKS = {"d": 1.0, "a": 0.3, "b": 0.9, "c": 0.8}
MASSES = {"m1": 1.0, "m2": 2.0, "m3": 1.5}
G = 9.81


def positions(th1: float, branch: int = 1, links: dict = LINKS) -> tuple[float, float]:
    """``(θ2, θ3)`` of the assembly at crank angle ``th1`` (``branch`` ±1 picks the side of BD
    the coupler lies on)."""
    a, b, c, d = links["a"], links["b"], links["c"], links["d"]
    bx, bz = a * np.cos(th1), a * np.sin(th1)
    ex, ez = d - bx, -bz
    L = np.hypot(ex, ez)
    beta = np.arccos((b * b + L * L - c * c) / (2 * b * L))
    th2 = np.arctan2(ez, ex) + branch * beta
    cx, cz = bx + b * np.cos(th2), bz + b * np.sin(th2)
    th3 = np.arctan2(cz, cx - d)
    return float(th2), float(th3)


def _ratios(th: np.ndarray, links: dict) -> tuple[np.ndarray, np.ndarray]:
    """``s = dθ/dθ1`` and ``σ = d²θ/dθ1²`` (three entries each; the first 1 and 0)."""
    a, b, c = links["a"], links["b"], links["c"]
    c1, s1, c2, s2, c3, s3 = np.cos(th[0]), np.sin(th[0]), np.cos(th[1]), np.sin(th[1]), np.cos(th[2]), np.sin(th[2])
    A = np.array([[-b * s2, c * s3], [b * c2, -c * c3]])  # ∂f/∂(θ2, θ3)
    s23 = np.linalg.solve(A, -np.array([-a * s1, a * c1]))
    s = np.array([1.0, *s23])
    rhs = a * np.array([c1, s1]) + b * np.array([c2, s2]) * s[1] ** 2 - c * np.array([c3, s3]) * s[2] ** 2
    sig = np.array([0.0, *np.linalg.solve(A, rhs)])
    return s, sig


def _centres(th: np.ndarray, s: np.ndarray, sig: np.ndarray, links: dict) -> list[tuple[np.ndarray, ...]]:
    """Per link: its centre, ``d/dθ1`` and ``d²/dθ1²`` of it."""
    a, b, c, d = links["a"], links["b"], links["c"], links["d"]
    u = [np.array([np.cos(x), np.sin(x)]) for x in th]
    n = [np.array([-np.sin(x), np.cos(x)]) for x in th]
    p1 = a / 2 * u[0]
    dp1 = a / 2 * n[0]
    ddp1 = -a / 2 * u[0]
    p2 = a * u[0] + b / 2 * u[1]
    dp2 = a * n[0] + b / 2 * n[1] * s[1]
    ddp2 = -a * u[0] + b / 2 * (-u[1] * s[1] ** 2 + n[1] * sig[1])
    p3 = np.array([d, 0.0]) + c / 2 * u[2]
    dp3 = c / 2 * n[2] * s[2]
    ddp3 = c / 2 * (-u[2] * s[2] ** 2 + n[2] * sig[2])
    return [(p1, dp1, ddp1), (p2, dp2, ddp2), (p3, dp3, ddp3)]


def _reduced_rhs(th1: float, w: float, branch: int, links: dict, masses: dict) -> float:
    th = np.array([th1, *positions(th1, branch, links)])
    s, sig = _ratios(th, links)
    ms = [masses["m1"], masses["m2"], masses["m3"]]
    ls = [links["a"], links["b"], links["c"]]
    m_eff = dm = dV = 0.0
    for i, (_, dp, ddp) in enumerate(_centres(th, s, sig, links)):
        inertia = ms[i] * ls[i] ** 2 / 12
        m_eff += ms[i] * dp @ dp + inertia * s[i] ** 2
        dm += 2 * ms[i] * dp @ ddp + 2 * inertia * s[i] * sig[i]
        dV += ms[i] * G * dp[1]
    return -(0.5 * dm * w * w + dV) / m_eff


def reduced_motion(th1_0: float, w0: float, times: np.ndarray, branch: int = 1, links: dict = LINKS,
                   masses: dict = MASSES) -> np.ndarray:
    """``θ1(t)`` and ``θ̇1(t)`` at ``times`` (rows), by solve_ivp at tolerance 1e-13."""
    sol = solve_ivp(lambda t, y: [y[1], _reduced_rhs(y[0], y[1], branch, links, masses)], (0.0, times[-1]),
                    [th1_0, w0], method="DOP853", rtol=1e-13, atol=1e-13, t_eval=times)
    return sol.y.T


def state(th1: float, w1: float, branch: int = 1, links: dict = LINKS) -> np.ndarray:
    """The full state ``(θ1, θ2, θ3, θ̇1, θ̇2, θ̇3)`` of the assembly at crank angle and rate."""
    th = np.array([th1, *positions(th1, branch, links)])
    s, _ = _ratios(th, links)
    return np.concatenate([th, s * w1])


def energy(x: np.ndarray, links: dict = LINKS, masses: dict = MASSES) -> float:
    """Kinetic plus potential energy (J) of a full state."""
    M, _ = mass_and_bias(x, links, masses)
    a, b, c = links["a"], links["b"], links["c"]
    m1, m2, m3 = masses["m1"], masses["m2"], masses["m3"]
    V = G * (m1 * a / 2 * np.sin(x[0]) + m2 * (a * np.sin(x[0]) + b / 2 * np.sin(x[1])) + m3 * c / 2 * np.sin(x[2]))
    return float(0.5 * x[3:] @ M @ x[3:] + V)


def mass_and_bias(x: np.ndarray, links: dict = LINKS, masses: dict = MASSES) -> tuple[np.ndarray, np.ndarray]:
    """``M(θ)`` and ``h(θ, θ̇)`` of the three free rods (crank and rocker pivoted, coupler pinned
    to the crank's tip), written from their energies."""
    a, b, c = links["a"], links["b"], links["c"]
    m1, m2, m3 = masses["m1"], masses["m2"], masses["m3"]
    th1, th2, th3, w1, w2, _ = x
    k = m2 * a * b / 2
    M = np.array([[m1 * a * a / 3 + m2 * a * a, k * np.cos(th1 - th2), 0.0],
                  [k * np.cos(th1 - th2), m2 * b * b / 4 + m2 * b * b / 12, 0.0],
                  [0.0, 0.0, m3 * c * c / 3]])
    h = np.array([k * np.sin(th1 - th2) * w2 ** 2 + G * np.cos(th1) * (m1 * a / 2 + m2 * a),
                  -k * np.sin(th1 - th2) * w1 ** 2 + G * m2 * b / 2 * np.cos(th2),
                  G * m3 * c / 2 * np.cos(th3)])
    return M, h


def closure(x: np.ndarray, links: dict = LINKS) -> np.ndarray:
    """``f(θ)``, the loop-closure residual (m)."""
    a, b, c, d = links["a"], links["b"], links["c"], links["d"]
    t1, t2, t3 = x[:3]
    return np.array([a * np.cos(t1) + b * np.cos(t2) - d - c * np.cos(t3),
                     a * np.sin(t1) + b * np.sin(t2) - c * np.sin(t3)])


def kkt(x: np.ndarray, links: dict = LINKS, masses: dict = MASSES) -> tuple[np.ndarray, np.ndarray]:
    """``(θ̈, λ)`` of ``M θ̈ + h = Jᵀλ``, ``J θ̈ = −J̇ θ̇`` (λ in N: the closure's force)."""
    a, b, c = links["a"], links["b"], links["c"]
    t1, t2, t3, w1, w2, w3 = x
    M, h = mass_and_bias(x, links, masses)
    J = np.array([[-a * np.sin(t1), -b * np.sin(t2), c * np.sin(t3)],
                  [a * np.cos(t1), b * np.cos(t2), -c * np.cos(t3)]])
    gamma = (a * np.array([np.cos(t1), np.sin(t1)]) * w1 ** 2 + b * np.array([np.cos(t2), np.sin(t2)]) * w2 ** 2
             - c * np.array([np.cos(t3), np.sin(t3)]) * w3 ** 2)
    K = np.block([[M, -J.T], [J, np.zeros((2, 2))]])
    sol = np.linalg.solve(K, np.concatenate([-h, gamma]))
    return sol[:3], sol[3:]
