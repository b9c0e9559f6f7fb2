"""RABBIT's hybrid zero dynamics computed numerically from its full-order equations, written
out here: the restricted Poincaré map θ̇⁺ → θ̇⁺ of the 1-DOF zero dynamics, its fixed point,
its multiplier and the step time.

Nothing here comes from amble. The five-link planar biped (point feet; absolute link angles of
the vector from a link's lower to its upper end, R(θ) = (sin θ, cos θ), gravity along -z): q =
(torso, stance_hip, swing_hip, stance_knee, swing_knee), the hips each femur's absolute angle
less the torso's, the knees each tibia's absolute angle less its femur's; the inputs act on the
four joints, so the torso row of M q'' + h = B u carries no input. Its equations are Kane's: M =
Σ m JᵀJ + Σ I jᵀj over the link masses and inertias, h the velocity-product and gravity terms,
the Jacobians written out by hand (every point is a sum of link vectors).

On the zero-dynamics manifold every joint follows its Bézier polynomial h_d(s) of the phase
θ = torso + stance_hip + stance_knee/2, s = (θ - θ⁺)/(θ⁻ - θ⁺) (SciPy's ``BPoly``), so
q = q(θ) in closed form (the torso is θ - stance_hip - stance_knee/2), q' = q_θ θ', q'' =
q_θ θ'' + q_θθ θ'²; the torso row then gives θ'' as a function of (θ, θ'). The step ends at
θ = θ⁻; there the swing foot's plastic impact (coordinates extended by the stance foot's
position, the stance foot free) and the leg swap give θ'⁺ = δ θ'⁻.

Run as a script it prints the default gait's fixed point, multiplier and step time."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from scipy.integrate import solve_ivp
from scipy.interpolate import BPoly

#: Chevallereau et al. 2003 / Westervelt et al. 2007 Table 6.3 (SI units)
PARAMS = dict(mT=20.0, mf=6.8, mt=3.2, lf=0.4, lt=0.4, pT=0.2, pf=0.163, pt=0.128, IT=2.22, If=1.08, It=0.93, g=9.81)
RTOL = ATOL = 1e-12
#: the phase's weights on q: θ = c·q
C = np.array([1.0, 1.0, 0.0, 0.5, 0.0])


#: the rows of the five links' absolute angles a = A q (torso, stance femur, stance tibia, swing
#: femur, swing tibia)
A = np.array([[1, 0, 0, 0, 0], [1, 1, 0, 0, 0], [1, 1, 0, 1, 0], [1, 0, 1, 0, 0], [1, 0, 1, 0, 1]], float)


def _arms(p: dict) -> np.ndarray:
    """Every point is Σ_k K[i, k] R(a_k): rows torso, stance femur, stance tibia, swing femur and
    swing tibia masses, then the swing foot; columns the links (A's rows). The hip is
    lt R(t1) + lf R(f1) above the stance foot; the swing knee lf R(f2) below the hip."""
    lf, lt, pT, pf, pt = p["lf"], p["lt"], p["pT"], p["pf"], p["pt"]
    return np.array([[pT, lf, lt, 0, 0],
                     [0, lf - pf, lt, 0, 0],
                     [0, 0, lt - pt, 0, 0],
                     [0, lf, lt, -pf, 0],
                     [0, lf, lt, -lf, -pt],
                     [0, lf, lt, -lf, -lt]])


def _terms(q, qd, p):
    """x and z rows of the points' Jacobians (6 × 5 each) and their velocity-product
    accelerations: with R(a) = (sin a, cos a), R' = (cos a, -sin a) and R'' = -R."""
    k = _arms(p)
    a, ad = A @ q, A @ qd
    sn, cs = np.sin(a), np.cos(a)
    jx, jz = (k * cs) @ A, -(k * sn) @ A
    bx, bz = -(k * sn) @ ad**2, -(k * cs) @ ad**2
    return jx, jz, bx, bz


def _masses(p):
    return np.array([p["mT"], p["mf"], p["mt"], p["mf"], p["mt"]])


def dynamics(q, qd, p) -> tuple[np.ndarray, np.ndarray]:
    """M(q) and h(q, q') (gravity included) of M q'' + h = B u."""
    jx, jz, bx, bz = _terms(q, qd, p)
    m = _masses(p)
    jx, jz, bx, bz = jx[:5], jz[:5], bx[:5], bz[:5]
    inertia = np.array([p["IT"], p["If"], p["It"], p["If"], p["It"]])
    mm = jx.T @ (m[:, None] * jx) + jz.T @ (m[:, None] * jz) + A.T @ (inertia[:, None] * A)
    h = jx.T @ (m * bx) + jz.T @ (m * (bz + p["g"]))
    return mm, h


class ZeroDynamics:
    """The restricted dynamics of the Bézier virtual constraints ``alpha`` (4 × (degree + 1),
    rows: stance hip, swing hip, stance knee, swing knee) from phase ``start`` to ``end``."""

    def __init__(self, alpha: Sequence[Sequence[float]], start: float, end: float, params: dict | None = None):
        self.p = dict(PARAMS, **(params or {}))
        self.start, self.end = start, end
        scale = 1.0 / (end - start)
        # one piecewise polynomial for the four outputs (coefficients × 1 interval × 4)
        self.hd = BPoly(np.asarray(alpha, float).T[:, None, :], [0.0, 1.0])
        self.d1, self.d2 = self.hd.derivative(1), self.hd.derivative(2)
        self.scale = scale

    def q_of(self, theta: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """q, dq/dθ, d²q/dθ² on the manifold."""
        s, k = (theta - self.start) * self.scale, self.scale
        joints, dj, ddj = self.hd(s), self.d1(s) * k, self.d2(s) * k * k

        def full(j, torso):
            return np.array([torso, j[0], j[1], j[2], j[3]])

        return (full(joints, theta - joints[0] - joints[2] / 2), full(dj, 1 - dj[0] - dj[2] / 2),
                full(ddj, -ddj[0] - ddj[2] / 2))

    def theta_ddot(self, theta: float, theta_dot: float) -> float:
        q, q1, q2 = self.q_of(theta)
        mm, h = dynamics(q, q1 * theta_dot, self.p)
        return -(mm[0] @ q2 * theta_dot**2 + h[0]) / (mm[0] @ q1)

    def impact_ratio(self) -> float:
        """δ = θ'⁺/θ'⁻ at the footfall θ = end."""
        q, q1, _ = self.q_of(self.end)
        qd = q1  # θ'⁻ = 1: the impact is linear in the velocities
        p = self.p
        jx, jz, _, _ = _terms(q, qd, p)
        mm, _ = dynamics(q, qd, p)
        masses = _masses(p)
        me = np.zeros((7, 7))
        me[:2, :2] = masses.sum() * np.eye(2)
        coupling = np.vstack([masses @ jx[:5], masses @ jz[:5]])  # Σ m J of the link masses
        me[:2, 2:], me[2:, :2], me[2:, 2:] = coupling, coupling.T, mm
        jf = np.hstack([np.eye(2), np.vstack([jx[5], jz[5]])])
        kkt = np.block([[me, -jf.T], [jf, np.zeros((2, 2))]])
        v = np.linalg.solve(kkt, np.concatenate([me @ np.concatenate([np.zeros(2), qd]), np.zeros(2)]))[2:7]
        swapped = v[[0, 2, 1, 4, 3]]  # the legs swap: torso, stance_hip ↔ swing_hip, stance_knee ↔ swing_knee
        return float(C @ swapped)

    def step(self, theta_dot: float) -> tuple[float, float]:
        """θ'⁺ → (θ'⁻ at the footfall, the step time)."""

        def end(_t, y):
            return y[0] - self.end

        end.terminal, end.direction = True, 1
        sol = solve_ivp(lambda _t, y: [y[1], self.theta_ddot(y[0], y[1])], (0.0, 5.0), [self.start, theta_dot],
                        method="DOP853", events=end, rtol=RTOL, atol=ATOL)
        if sol.status != 1:
            raise RuntimeError("the phase does not reach its end within 5 s")
        return float(sol.y_events[0][0][1]), float(sol.t_events[0][0])

    def limit_cycle(self, guess: float = 1.0) -> dict:
        """The fixed point θ'⁺* of θ'⁺ → δ θ'⁻ (Newton with central differences), its
        multiplier and the step time (s)."""
        delta = self.impact_ratio()
        w, h = guess, 1e-6

        def P(x):
            return delta * self.step(x)[0]

        for _ in range(30):
            slope = (P(w + h) - P(w - h)) / (2 * h)
            dw = (P(w) - w) / (1 - slope)
            w += dw
            if abs(dw) < 1e-13:
                break
        else:
            raise RuntimeError("Newton did not converge")
        return dict(theta_dot=w, multiplier=(P(w + h) - P(w - h)) / (2 * h), step_time=self.step(w)[1], delta=delta,
                    residual=abs(P(w) - w))


if __name__ == "__main__":
    alpha = [[-0.4, -0.3081551494564341, -0.16605346826621353, 0.2270601478435086, 0.04970721613181213, 0.1],
             [0.1, 0.11737909407493607, 0.00038439800609303394, -0.22976576788170783, -0.6299212649578043, -0.4],
             [0.1, -0.01896672967530122, 0.1612502508393034, 0.49611220938858624, 0.09494393675106377, 0.1],
             [0.1, 0.12216095445951894, 2.275019608209081, 0.39921662714633, 0.14579490709209958, 0.1]]
    print(ZeroDynamics(alpha, -0.25, 0.25).limit_cycle())
