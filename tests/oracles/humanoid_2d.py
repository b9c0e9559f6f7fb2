"""The 2D humanoid (a kneed biped with a PD-held torso and a step-length torque on the swing
leg; thesis 4.3) written out here and integrated with SciPy: one step of its return map
(free knee, knee lock, straight-legged swing, heel strike), the map's residual at a state and
its multipliers.

Nothing here comes from amble. Absolute angles from the vertical, R(θ) = (sin θ, cos θ) from a
link's lower to its upper end, positive leaning downhill (+x); gravity along -z; the slope γ
descends along +x (height n·p with n = (sin γ, cos γ), ahead when d·p > 0 with
d = (cos γ, -sin γ)). Free knee: q = (stance, shank, thigh, torso); locked knee: (stance, thigh,
torso) with the shank = the thigh, q = T q_l. Masses: on the stance leg ms at a1 and mt at
a1 + b1 + a2 above the foot, mh at the hip l = a1 + b1 + a2 + b2 above it; the swing thigh's mt
b2 below the hip, the swing knee a2 + b2 below it, the swing shank's ms b1 below the knee, the
swing foot a1 + b1 below it; the torso's mT lT above the hip. Kane's equations, the Jacobians
written out by hand (every point is a sum of link vectors l_k R(θ_k)); the locked phase's
M_l = Tᵀ M T, h_l = Tᵀ h, Γ_l = Tᵀ Γ.

Forces: τ = kT (θ_d - torso) - kv torso' between the torso and the stance leg (+τ on the
torso, -τ on the stance leg), and τ₂ = -kleg L on the thigh while L = -x(swing foot) > 0.

Events: the knee locks when shank - thigh falls through 0 (plastic: M q'⁺ = M q'⁻ + Aᵀλ,
A q'⁺ = 0, A = shank - thigh); the heel strikes when the swing foot's height falls through 0
while it is ahead (plastic impact in coordinates extended by the stance foot's position, which
may lift), then the legs swap: stance⁺ = thigh⁻, shank⁺ = thigh⁺ = stance⁻, the torso kept.

Run as a script it prints the residual of amble's published fixed point and the multipliers."""

from __future__ import annotations

import numpy as np
from scipy.integrate import solve_ivp

PARAMS = dict(mh=10.0, mt=3.5, ms=1.5, a1=0.25, b1=0.25, a2=0.15, b2=0.35, It=0.0, Is=0.0, g=9.81, slope=0.05,
              mT=3.0, lT=0.5, kT=100.0, kv=10.0, theta_d=0.0, kleg=5.0)
RTOL = ATOL = 1e-12
#: the locked knee: q = T q_l, q_l = (stance, thigh, torso)
T = np.array([[1.0, 0, 0], [0, 1, 0], [0, 1, 0], [0, 0, 1]])


def _arms(p: dict) -> np.ndarray:
    """Points Σ_k K[i, k] R(q_k), q = (stance, shank, thigh, torso): rows the masses stance
    shank, stance thigh, hip, swing thigh, swing shank, torso, then the swing foot."""
    a1, b1, a2, b2, lT = p["a1"], p["b1"], p["a2"], p["b2"], p["lT"]
    l = a1 + b1 + a2 + b2
    return np.array([[a1, 0, 0, 0],
                     [a1 + b1 + a2, 0, 0, 0],
                     [l, 0, 0, 0],
                     [l, 0, -b2, 0],
                     [l, -b1, -(a2 + b2), 0],
                     [l, 0, 0, lT],
                     [l, -(a1 + b1), -(a2 + b2), 0]])


def _masses(p: dict) -> np.ndarray:
    return np.array([p["ms"], p["mt"], p["mh"], p["mt"], p["ms"], p["mT"]])


def _terms(q, qd, p):
    """x and z rows of the points' Jacobians and their velocity-product accelerations
    (R' = (cos, -sin), R'' = -R), the points' positions."""
    k = _arms(p)
    sn, cs = np.sin(q), np.cos(q)
    return k * cs, -(k * sn), -(k * sn) @ qd**2, -(k * cs) @ qd**2, k @ sn, k @ cs


def dynamics(q, qd, p):
    """M(q), h(q, q') (gravity included) and Γ(q, q') of the free-knee equations."""
    jx, jz, bx, bz, px, _ = _terms(q, qd, p)
    m = _masses(p)
    inertia = np.diag([p["It"] + p["Is"], p["Is"], p["It"], 0.0])
    mm = jx[:6].T @ (m[:, None] * jx[:6]) + jz[:6].T @ (m[:, None] * jz[:6]) + inertia
    h = jx[:6].T @ (m * bx[:6]) + jz[:6].T @ (m * (bz[:6] + p["g"]))
    tau = p["kT"] * (p["theta_d"] - q[3]) - p["kv"] * qd[3]
    step_length = -px[6]
    gam = np.array([-tau, 0.0, -p["kleg"] * step_length if step_length > 0 else 0.0, tau])
    return mm, h, gam


def rhs(_t, x, p, locked: bool):
    if locked:
        ql, qdl = x[:3], x[3:]
        mm, h, gam = dynamics(T @ ql, T @ qdl, p)
        return np.concatenate([qdl, np.linalg.solve(T.T @ mm @ T, T.T @ (gam - h))])
    mm, h, gam = dynamics(x[:4], x[4:], p)
    return np.concatenate([x[4:], np.linalg.solve(mm, gam - h)])


def _full(x, locked):
    return (T @ x[:3], T @ x[3:]) if locked else (x[:4], x[4:])


def swing_foot(x, p, locked):
    q, qd = _full(x, locked)
    _, _, _, _, px, pz = _terms(q, qd, p)
    return np.array([px[6], pz[6]])


def knee_lock(x, p):
    """Free-knee state → locked state: Tᵀ M T q_l'⁺ = Tᵀ M q'⁻ (the knee impulse does no work on T's motions)."""
    mm, _, _ = dynamics(x[:4], x[4:], p)
    return np.concatenate([x[[0, 2, 3]], np.linalg.solve(T.T @ mm @ T, T.T @ mm @ x[4:])])


def heel_strike(x, p):
    """Locked state → free-knee state after the impact and the swap."""
    q, qd = _full(x, True)
    jx, jz, _, _, _, _ = _terms(q, qd, p)
    mm, _, _ = dynamics(q, qd, p)
    m = _masses(p)
    me = np.zeros((5, 5))
    me[:2, :2] = m.sum() * np.eye(2)
    coupling = np.vstack([m @ jx[:6], m @ jz[:6]]) @ T
    me[:2, 2:], me[2:, :2], me[2:, 2:] = coupling, coupling.T, T.T @ mm @ T
    jf = np.hstack([np.eye(2), np.vstack([jx[6], jz[6]]) @ T])
    kkt = np.block([[me, -jf.T], [jf, np.zeros((2, 2))]])
    v = np.linalg.solve(kkt, np.concatenate([me @ np.concatenate([np.zeros(2), x[3:]]), np.zeros(2)]))[2:5]

    def swap(y):  # (stance, thigh, torso) locked → (stance, shank, thigh, torso)
        return np.array([y[1], y[0], y[0], y[2]])

    return np.concatenate([swap(x[:3]), swap(v)])


def step(x: np.ndarray, p: dict | None = None) -> tuple[np.ndarray, float, float]:
    """Post-impact free-knee state → next post-impact state, the knee-lock time and the step
    time (s). The integration also stops where the swing foot passes x = 0, the kink of τ₂."""
    p = PARAMS if p is None else p
    gam = p["slope"]

    def knee(_t, y, p, locked):
        return y[1] - y[2]

    def passes(_t, y, p, locked):
        return swing_foot(y, p, locked)[0]

    def strike(_t, y, p, locked):
        f = swing_foot(y, p, locked)
        return np.sin(gam) * f[0] + np.cos(gam) * f[1]

    for e, d in ((knee, -1), (passes, +1), (strike, -1)):
        e.terminal, e.direction = True, d
    y, t, locked, passed, t_knee = np.asarray(x, float), 0.0, False, False, None
    while True:
        events = ([] if passed else [passes]) + [strike if locked else knee]
        sol = solve_ivp(rhs, (t, t + 5.0), y, method="DOP853", rtol=RTOL, atol=ATOL, events=events, args=(p, locked))
        hit = [i for i, te in enumerate(sol.t_events) if len(te)]
        if sol.status != 1 or len(hit) != 1:
            raise RuntimeError("no single event within 5 s")
        event = events[hit[0]]
        t, y = float(sol.t_events[hit[0]][0]), sol.y_events[hit[0]][0]
        if event is passes:
            passed = True
        elif event is knee:
            y, locked, t_knee = knee_lock(y, p), True, t
        else:
            f = swing_foot(y, p, True)
            assert np.cos(gam) * f[0] - np.sin(gam) * f[1] > 0, "the heel strike must be ahead of the stance foot"
            return heel_strike(y, p), t_knee, t


def on_section(z: np.ndarray) -> np.ndarray:
    """Free-knee post-impact state from z = (stance, thigh, torso, their rates): shank = thigh."""
    return np.array([z[0], z[1], z[1], z[2], z[3], z[4], z[4], z[5]])


def jacobian(x: np.ndarray, p: dict | None = None, h: float = 1e-5) -> np.ndarray:
    """Central differences of the 6-D map z → z (z as in :func:`on_section`) at the state x. The
    step 1e-5 balances the truncation error (~1e-5 in the complex pair at 1e-4) against the
    integration's noise (~1e-12 / h: the pair moves by ~1e-6 at h = 1e-6)."""
    z = np.asarray(x, float)[[0, 2, 3, 4, 6, 7]]

    def image(z):
        return step(on_section(z), p)[0][[0, 2, 3, 4, 6, 7]]

    return np.column_stack([(image(z + h * e) - image(z - h * e)) / (2 * h) for e in np.eye(6)])


if __name__ == "__main__":
    x_star = np.array([-0.2206099995, 0.3206099995, 0.3206099995, -0.0442356769, 0.9708804245, 0.4105759175,
                       0.4105759175, 0.4637318092])
    nxt, tk, ts = step(x_star)
    print("knee lock", tk, "step", ts, "residual", np.max(np.abs(nxt - x_star)))
    mu = np.linalg.eigvals(jacobian(x_star))
    print("multipliers", mu[np.argsort(-abs(mu))])
