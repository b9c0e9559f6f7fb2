"""Fit the interior Bézier coefficients of the ``rabbit`` gait on its zero dynamics.

The footfall pose (last column of ``amble.models.rabbit.ALPHA``) and the phase range stay; the
first two columns follow from hybrid invariance; the twelve interior coefficients are chosen by
Nelder–Mead for: a margin of speed over the step (ζ = θ̇²/2 ≥ 0.15), a restricted multiplier
below 0.85, the swing foot 3 cm clear of the ground, a walking speed between 0.6 and 0.9 m/s and
joint torques (from M q̈ + h on the zero dynamics) below 110 N·m. Prints the coefficients to paste
into ``ALPHA``. Takes a few minutes: ``python scripts/design_rabbit_gait.py``.
"""

import json

import numpy as np
import sympy as sp
from scipy.integrate import solve_ivp
from scipy.optimize import minimize

from amble.analysis.hzd import invariant_parameters, restricted_map, zero_dynamics_functions
from amble.backend.kernels import compiled
from amble.models import rabbit

system = rabbit.build()
model = system.modes["rabbit"]
kernels = compiled(system)
fn = zero_dynamics_functions(model)
foot = sp.lambdify([*model.q, *model.params], list(model.points["swing_foot"]), cse=True)
INTERIOR = [(i, k) for i in range(4) for k in (2, 3, 4)]


def parameters(z):
    p = dict(system.parameters)
    p.update({f"alpha_{i}_{k}": float(v) for (i, k), v in zip(INTERIOR, z)})
    return invariant_parameters(system, p)


def gait(z):
    """Speed margin, multiplier, clearance, speed (m/s) and peak torque (N·m) of a design."""
    p = parameters(z)
    rm = restricted_map(system, p)
    pm = [p[str(s)] for s in model.params]
    ths = np.linspace(p["phase_start"], p["phase_end"], 41)
    qs = np.array([fn.Phi(th, *pm) for th in ths])
    out = {"min_zeta": rm.min_zeta, "multiplier": rm.multiplier,
           "clearance": min(foot(*q, *pm)[1] for q in qs[4:-4])}
    if not (rm.zeta_plus > 0 and rm.min_zeta > 0):
        return out
    a = lambda th: float(fn.a(th, *pm))
    b2 = lambda th: 2 * (float(fn.a1(th, *pm)) - a(th))
    sol = solve_ivp(lambda th, z: [a(th) + b2(th) * z[0]], (ths[0], ths[-1]), [rm.zeta_plus], dense_output=True,
                    rtol=1e-8)
    zeta = np.maximum(sol.sol(ths)[0], 1e-9)
    out["speed"] = foot(*qs[-1], *pm)[0] / np.trapezoid(1 / np.sqrt(2 * zeta), ths)
    pv = np.array([p[n] for n in kernels.meta["params"]])
    peak = 0.0
    for th, zt, q in zip(ths, zeta, qs):
        w, acc = np.sqrt(2 * zt), a(th) + b2(th) * zt
        d1 = np.asarray(fn.dPhi(th, *pm), float)
        d2 = (np.asarray(fn.dPhi(th + 1e-5, *pm), float) - np.asarray(fn.dPhi(th - 1e-5, *pm), float)) / 2e-5
        M, h, _ = kernels.dynamics("rabbit", 0.0, np.concatenate([q, d1 * w]), pv)
        peak = max(peak, float(np.max(np.abs((M @ (d1 * acc + d2 * w**2) + h)[1:]))))
    out["torque"] = peak
    return out


def cost(z, z0):
    try:
        g = gait(z)
    except Exception:  # a design whose impact or zero dynamics fail
        return 1e3
    c = 1e4 * max(0, 0.15 - g["min_zeta"]) ** 2 + 1e5 * max(0, 0.03 - g["clearance"]) ** 2
    c += 100 * max(0, abs(g["multiplier"]) - 0.85) ** 2
    if "speed" not in g:
        return c + 1e3
    c += 100 * (max(0, 0.6 - g["speed"]) ** 2 + max(0, g["speed"] - 0.9) ** 2)
    return c + 1e-2 * max(0, g["torque"] - 110) ** 2 + 0.01 * np.sum((z - z0) ** 2)


if __name__ == "__main__":
    z0 = np.array([rabbit.ALPHA[i][k] for i, k in INTERIOR])
    print("start:", gait(z0))
    res = minimize(cost, z0, args=(z0,), method="Nelder-Mead", options={"maxfev": 350, "xatol": 1e-4})
    print("fitted:", gait(res.x))
    p = parameters(res.x)
    print("ALPHA =", json.dumps([[p[f"alpha_{i}_{k}"] for k in range(6)] for i in range(4)]))
