"""The 3D humanoid with pelvis yaw (straight legs, a pelvis of width w, a torso, an upper-body
inertia) written out here from its description and integrated with SciPy: one step of its
return map, the map's fixed-point residual and its multipliers.

Nothing here comes from amble. The equations of motion are formed by Kane's method (the
Newton–Euler equations of each mass and of the upper body projected on the partial
velocities), not by Lagrange's, and the upper body's angular velocity is written out from its
Euler-angle sequence, not from R^T R'. SymPy forms only the positions' Jacobians and their
velocity-product terms; the rest is NumPy.

Robot (SI units, angles in rad). Every leg or torso direction is
R3(Θ, Φ) = (sin Θ cos Φ, sin Φ, cos Θ cos Φ). Coordinates q = (stance, swing, stance_cor,
swing_cor, torso, torso_cor, yaw); the stance foot at the origin; the stance hip at
l R3(stance, stance_cor), l = a + b; the upper body turned by F = Ry(torso) Rx(-torso_cor)
Rz(yaw), its y column the pelvis axis (stance hip → hip → swing hip, w/2 apart), its z column
the torso axis; the hip mass mh at the pelvis centre, the torso mass mt at lt along the torso
axis, a leg mass m at b from each foot, and the upper body's inertia diag(I_xy, I_xy, I_z)
about its own axes. Gravity g along -z. The ground descends along +x at the slope γ: a point's
height is n·p with n = (sin γ, 0, cos γ), it is ahead when d·p > 0 with d = (cos γ, 0, -sin γ).

Forces Γ on the coordinates: stance 0; swing -k_leg·L while L = -d·(swing foot) > 0; the
coronal angles, the torso's lean and the yaw each a spring-damper to zero (gains below).

Heel strike: the swing foot's height falls through 0 while it is ahead. Plastic impact of
the swing foot with the stance foot free to lift: in coordinates extended by the stance foot's
position p0, M_e (qe'+ - qe'-) = J^T Λ and J qe'+ = 0, J the swing foot's Jacobian. Then the
legs swap and the lateral axis is mirrored (y → -y): the Θ's swap, the Φ's swap with their
signs changed, torso_cor and yaw change sign (S F S with S = diag(1, -1, 1) is
Ry(torso) Rx(torso_cor) Rz(-yaw)); the state is again taken with the new stance foot at the
origin.

Run as a script it prints the step time, the residual of amble's published fixed point and the
map's multipliers there (about a minute: 28 steps for the central differences)."""

from __future__ import annotations

from functools import cache

import numpy as np
import sympy as sp
from scipy.integrate import solve_ivp

PARAMS = dict(mh=10.0, m=5.0, mt=3.0, a=0.53, b=0.47, lt=0.5, w=0.1, g=9.81, slope=0.05, I_xy=0.2, I_z=0.2,
              k_leg=5.0, k_sc=400.0, kv_sc=40.0, k_sw=50.0, kv_sw=20.0, k_t=60.0, kv_t=20.0, k_tc=100.0,
              kv_tc=20.0, k_yaw=50.0, kv_yaw=10.0)
RTOL = ATOL = 1e-12
N = 7


def _r3(th, ph):
    return sp.Matrix([sp.sin(th) * sp.cos(ph), sp.sin(ph), sp.cos(th) * sp.cos(ph)])


def _rot(axis: int, a):
    c, s = sp.cos(a), sp.sin(a)
    if axis == 0:
        return sp.Matrix([[1, 0, 0], [0, c, -s], [0, s, c]])
    if axis == 1:
        return sp.Matrix([[c, 0, s], [0, 1, 0], [-s, 0, c]])
    return sp.Matrix([[c, -s, 0], [s, c, 0], [0, 0, 1]])


@cache
def _kinematics():
    """Functions of (sin q, cos q, q', a, b, lt, w): the positions, Jacobians and velocity-product
    accelerations (the q'' -free part of each point's acceleration) of the four masses and the
    swing foot; of (sin q, cos q, q'): the upper body's frame F, angular-velocity Jacobian J_w
    (world axes) and its velocity-product term; of (sin q, cos q, a, b, w): the swing foot."""
    q = sp.symbols("q0:7")
    qd = sp.symbols("qd0:7")
    a, b, lt, w = sp.symbols("a b lt w", positive=True)
    st, sw, stc, swc, tor, torc, yaw = q
    frame = _rot(1, tor) * _rot(0, -torc) * _rot(2, yaw)
    pelvis = frame[:, 1]
    hip_r = (a + b) * _r3(st, stc)
    hip = hip_r + w / 2 * pelvis
    hip_l = hip_r + w * pelvis
    # the masses stance_mass (m), hip (mh), swing_mass (m), torso (mt), then the swing foot
    points = [b * _r3(st, stc), hip, hip_l - a * _r3(sw, swc), hip + lt * _r3(tor, torc),
              hip_l - (a + b) * _r3(sw, swc)]
    qv, qdv = sp.Matrix(q), sp.Matrix(qd)
    rows_p, rows_j, rows_b = [], [], []
    for p in points:
        jac = p.jacobian(qv)
        rows_p.append(p)
        rows_j.append(jac)
        rows_b.append((jac * qdv).jacobian(qv) * qdv)
    # ω = torso' e_y + (-torso_cor') Ry(torso) e_x + yaw' Ry(torso) Rx(-torso_cor) e_z (world axes)
    jw = sp.zeros(3, 7)
    jw[:, 4] = sp.Matrix([0, 1, 0])
    jw[:, 5] = -_rot(1, tor)[:, 0]
    jw[:, 6] = (_rot(1, tor) * _rot(0, -torc))[:, 2]
    bw = (jw * qdv).jacobian(qv) * qdv
    # every expression is a polynomial in the sines and cosines of q: evaluate those once per call
    sn, cs = sp.symbols("s0:7"), sp.symbols("c0:7")
    trig = {sp.sin(qi): si for qi, si in zip(q, sn, strict=True)}
    trig |= {sp.cos(qi): ci for qi, ci in zip(q, cs, strict=True)}

    def rows(exprs):
        return [[sp.sympify(e).xreplace(trig) for e in v] for v in exprs]

    args = (sn, cs, qd, a, b, lt, w)
    # scalar arithmetic (the math module) is several times faster than NumPy's on single numbers
    pts = sp.lambdify(args, [rows(rows_p), [rows(j.tolist()) for j in rows_j], rows(rows_b)], "math", cse=True)
    body = sp.lambdify((sn, cs, qd), [rows(frame.tolist()), rows(jw.tolist()), rows([bw])[0]], "math", cse=True)
    foot = sp.lambdify((sn, cs, a, b, w), rows([points[4]])[0], "math", cse=True)
    return pts, body, foot


def _terms(x: np.ndarray, p: dict):
    q, qd = x[:N], x[N:]
    pts, body, _ = _kinematics()
    sn, cs = np.sin(q).tolist(), np.cos(q).tolist()
    pos, jac, bias = pts(sn, cs, qd, p["a"], p["b"], p["lt"], p["w"])
    pos = [np.asarray(v, float).ravel() for v in pos]
    jac = [np.asarray(v, float) for v in jac]
    bias = [np.asarray(v, float).ravel() for v in bias]
    frame, jw, bw = (np.asarray(v, float) for v in body(sn, cs, qd))
    return pos, jac, bias, frame, jw, bw.ravel()


def mass_matrix_and_bias(x: np.ndarray, p: dict) -> tuple[np.ndarray, np.ndarray]:
    """M(q) and h(q, q') with M q'' + h = Γ (Kane's equations; h holds gravity)."""
    _, jac, bias, frame, jw, bw = _terms(x, p)
    masses = (p["m"], p["mh"], p["m"], p["mt"])
    ez = np.array([0.0, 0.0, 1.0])
    mm = np.zeros((N, N))
    h = np.zeros(N)
    for mass, j, bb in zip(masses, jac[:4], bias[:4], strict=True):
        mm += mass * j.T @ j
        h += mass * j.T @ (bb + p["g"] * ez)
    inertia = frame @ np.diag([p["I_xy"], p["I_xy"], p["I_z"]]) @ frame.T
    omega = jw @ x[N:]
    mm += jw.T @ inertia @ jw
    h += jw.T @ (inertia @ bw + np.cross(omega, inertia @ omega))
    return mm, h


def points(x: np.ndarray, p: dict | None = None) -> dict[str, np.ndarray]:
    """Positions (m) of the masses and the swing foot, the stance foot at the origin."""
    pos = _terms(x, PARAMS if p is None else p)[0]
    return dict(zip(("stance_mass", "hip", "swing_mass", "torso", "swing_foot"), pos, strict=True))


def swing_foot(x: np.ndarray, p: dict) -> np.ndarray:
    q = x[:N]
    return np.array(_kinematics()[2](np.sin(q).tolist(), np.cos(q).tolist(), p["a"], p["b"], p["w"]))


def ahead(x: np.ndarray, p: dict) -> float:
    """d·(swing foot) (m): how far the swing foot is downhill of the stance foot along the slope."""
    f, s = swing_foot(x, p), p["slope"]
    return float(np.cos(s) * f[0] - np.sin(s) * f[2])


def height(x: np.ndarray, p: dict) -> float:
    f, s = swing_foot(x, p), p["slope"]
    return float(np.sin(s) * f[0] + np.cos(s) * f[2])


def forces(x: np.ndarray, p: dict) -> np.ndarray:
    q, qd = x[:N], x[N:]
    step_length = -ahead(x, p)
    return np.array([
        0.0,
        -p["k_leg"] * step_length if step_length > 0 else 0.0,
        -p["k_sc"] * q[2] - p["kv_sc"] * qd[2],
        -p["k_sw"] * q[3] - p["kv_sw"] * qd[3],
        -p["k_t"] * q[4] - p["kv_t"] * qd[4],
        -p["k_tc"] * q[5] - p["kv_tc"] * qd[5],
        -p["k_yaw"] * q[6] - p["kv_yaw"] * qd[6],
    ])


def rhs(_t: float, x: np.ndarray, p: dict) -> np.ndarray:
    mm, h = mass_matrix_and_bias(x, p)
    return np.concatenate([x[N:], np.linalg.solve(mm, forces(x, p) - h)])


def impact(x: np.ndarray, p: dict) -> np.ndarray:
    """Plastic impact of the swing foot (stance foot free), then the legs swap and y → -y."""
    pos, jac, _, _, _, _ = _terms(x, p)
    masses = (p["m"], p["mh"], p["m"], p["mt"])
    mm, _ = mass_matrix_and_bias(x, p)
    me = np.zeros((N + 3, N + 3))
    me[:3, :3] = sum(masses) * np.eye(3)
    coupling = sum(mass * j for mass, j in zip(masses, jac[:4], strict=True))
    me[:3, 3:], me[3:, :3], me[3:, 3:] = coupling, coupling.T, mm
    jf = np.hstack([np.eye(3), jac[4]])
    kkt = np.block([[me, -jf.T], [jf, np.zeros((3, 3))]])
    v_minus = np.concatenate([np.zeros(3), x[N:]])
    v_plus = np.linalg.solve(kkt, np.concatenate([me @ v_minus, np.zeros(3)]))[:N + 3][3:]

    def swap(v):
        st, sw, stc, swc, tor, torc, yaw = v
        return np.array([sw, st, -swc, -stc, tor, -torc, -yaw])

    return np.concatenate([swap(x[:N]), swap(v_plus)])


def step(x: np.ndarray, p: dict | None = None) -> tuple[np.ndarray, float]:
    """Post-impact state → next post-impact state, and the step time (s). Two legs: until the
    swing foot passes the stance foot (where the swing-leg force switches off, so the
    integrator never steps across that kink), then to the heel strike."""
    p = PARAMS if p is None else p

    def passes(_t, y, p):
        return ahead(y, p)

    def strike(_t, y, p):
        return height(y, p)

    passes.terminal, passes.direction = True, +1
    strike.terminal, strike.direction = True, -1
    t0, y0 = 0.0, np.asarray(x, float)
    for event in (passes, strike):
        sol = solve_ivp(rhs, (t0, t0 + 5.0), y0, method="DOP853", rtol=RTOL, atol=ATOL, events=event, args=(p,))
        if sol.status != 1:
            raise RuntimeError(f"no {event.__name__} event within 5 s")
        t0, y0 = float(sol.t_events[0][0]), sol.y_events[0][0]
    assert ahead(y0, p) > 0, "the heel strike must be ahead of the stance foot"
    return impact(y0, p), t0


def jacobian(x: np.ndarray, p: dict | None = None, h: float = 1e-6) -> np.ndarray:
    """Central differences of the 14-D post-impact-to-post-impact map."""
    x = np.asarray(x, float)
    return np.column_stack([(step(x + h * e, p)[0] - step(x - h * e, p)[0]) / (2 * h) for e in np.eye(2 * N)])


if __name__ == "__main__":
    import time

    x_star = np.array([-0.17513872545372786, 0.21584692131603855, -0.0027109889560943323, -0.0007943995955461281,
                       -0.026276535422660098, -0.11538290987512972, -0.005241697963894061, 0.824737150927434,
                       0.6092596999815059, -0.08939453002223806, -0.12489102822875123, 0.1031354286921594,
                       0.4242854569830537, -0.35175036643091706])
    t = time.time()
    nxt, period = step(x_star)
    print("step time", period, "residual", np.max(np.abs(nxt - x_star)), f"({time.time() - t:.2f} s)")
    mu = np.linalg.eigvals(jacobian(x_star))
    print("multipliers", mu[np.argsort(-abs(mu))], f"({time.time() - t:.1f} s)")
