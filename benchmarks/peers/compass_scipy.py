"""Compass-gait walker integrated with SciPy's ``solve_ivp`` (DOP853).

This is the plain-SciPy peer for the compass-gait benchmark.  The model follows
the conventions of Drake's ``examples/compass_gait`` exactly:

* state ``x = (stance, swing, stancedot, swingdot)``; both angles are the
  angle of the leg vector (foot -> hip) from the world vertical, positive when
  the hip is downhill (+x) of that foot,
* swing-phase dynamics ``M(q) qdd + bias(q, v) = 0`` with Drake's mass matrix
  and bias term (no hip torque),
* foot-collision witness ``max(2*slope - stance - swing, swing - stance)``
  triggered in the positive-then-non-positive direction (the ``max`` is the
  "swing leg in front" enabling condition that suppresses foot scuffing),
* the impact reset computed from a planar floating-base model with the
  pre-impact stance toe at the origin, followed by swapping the legs.

The default parameters are Drake's (``CompassGaitParams``).

Run ``python -m benchmarks.peers.compass_scipy`` for a small table.
"""

from __future__ import annotations

import argparse
import math
import statistics
import time
import warnings
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
from scipy.integrate import solve_ivp

#: Drake's default ``CompassGaitParams``.
DEFAULT_PARAMS: dict[str, float] = {
    "mass_hip": 10.0,
    "mass_leg": 5.0,
    "length_leg": 1.0,
    "center_of_mass_leg": 0.5,
    "gravity": 9.81,
    "slope": 0.0525,
}

#: Post-impact state on the stable period-one limit cycle for the default
#: parameters, in Drake's state order (stance, swing, stancedot, swingdot).
#: Obtained with :func:`find_limit_cycle` (DOP853, rtol = atol = 1e-13,
#: Newton-polished; ``|P(x0) - x0| ~ 5e-15``, step duration 0.73446062134 s).
LIMIT_CYCLE_X0: np.ndarray = np.array(
    [
        -0.2187746179802934,
        0.3237746179802934,
        1.0928668105800068,
        0.37613459353088385,
    ]
)

#: Upper bound on the duration of one walking step; exceeding it means the
#: walker fell or stopped.
MAX_STEP_DURATION: float = 5.0


def _params(params: dict[str, float] | None) -> dict[str, float]:
    """Merge ``params`` into a copy of :data:`DEFAULT_PARAMS`."""
    p = dict(DEFAULT_PARAMS)
    if params:
        p.update(params)
    return p


def make_dynamics(
    params: dict[str, float] | None = None,
) -> Callable[[float, Sequence[float]], list[float]]:
    """Return the swing-phase vector field ``f(t, x)`` (Drake's equations).

    ``M = [[mh l^2 + m (l^2 + a^2), -m l b c], [-m l b c, m b^2]]`` with
    ``c = cos(swing - stance)``, and
    ``bias = [-m l b vsw^2 s - (mh l + m (a + l)) g sin(stance),
              m l b vst^2 s + m b g sin(swing)]`` with ``s = sin(stance - swing)``;
    ``qdd = -M^{-1} bias``.
    """
    p = _params(params)
    m = p["mass_leg"]
    mh = p["mass_hip"]
    ln = p["length_leg"]
    b = p["center_of_mass_leg"]
    a = ln - b
    g = p["gravity"]
    m11 = mh * ln * ln + m * (ln * ln + a * a)
    mlb = m * ln * b
    m22 = m * b * b
    g1 = (mh * ln + m * (a + ln)) * g
    g2 = m * b * g
    sin = math.sin
    cos = math.cos

    def dynamics(t: float, x: Sequence[float]) -> list[float]:
        """Time derivative of ``x = (stance, swing, stancedot, swingdot)``."""
        st, sw, vst, vsw = x[0], x[1], x[2], x[3]
        s = sin(st - sw)
        m12 = -mlb * cos(sw - st)
        b1 = -mlb * vsw * vsw * s - g1 * sin(st)
        b2 = mlb * vst * vst * s + g2 * sin(sw)
        det = m11 * m22 - m12 * m12
        return [
            vst,
            vsw,
            (-m22 * b1 + m12 * b2) / det,
            (m12 * b1 - m11 * b2) / det,
        ]

    return dynamics


def make_foot_collision(
    params: dict[str, float] | None = None,
) -> Callable[[float, Sequence[float]], float]:
    """Return Drake's foot-collision witness as a terminal ``solve_ivp`` event.

    ``w(x) = max(2*slope - stance - swing, swing - stance)``; it is positive
    while the swing foot is above the ramp or behind the stance foot and the
    event fires when it goes from positive to non-positive (``direction=-1``).
    """
    slope = _params(params)["slope"]

    def foot_collision(t: float, x: Sequence[float]) -> float:
        """Witness value; the step ends where it crosses zero downwards."""
        return max(2.0 * slope - x[0] - x[1], x[1] - x[0])

    foot_collision.terminal = True  # type: ignore[attr-defined]
    foot_collision.direction = -1.0  # type: ignore[attr-defined]
    return foot_collision


def collision_dynamics(x: Sequence[float], params: dict[str, float] | None = None) -> np.ndarray:
    """Drake's impact reset: pre-impact state -> post-impact state.

    A planar floating-base model (base = pre-impact stance toe) gets the
    pre-impact velocity ``(0, 0, stancedot, swingdot)``; the impulse that stops
    the swing toe is ``v+ = v- - M^-1 J^T (J M^-1 J^T)^-1 J v-``.  Afterwards
    the legs are swapped: ``stance+ = swing-``, ``swing+ = stance-``,
    ``stancedot+ = v+[3]``, ``swingdot+ = v+[2]``.
    """
    p = _params(params)
    m = p["mass_leg"]
    mh = p["mass_hip"]
    ln = p["length_leg"]
    b = p["center_of_mass_leg"]
    a = ln - b
    st, sw, vst, vsw = (float(v) for v in x)
    cst, csw = math.cos(st), math.cos(sw)
    sst, ssw = math.sin(st), math.sin(sw)
    c = math.cos(sw - st)
    k = m * a + m * ln + mh * ln
    mfb = np.array(
        [
            [2 * m + mh, 0.0, k * cst, -m * b * csw],
            [0.0, 2 * m + mh, -k * sst, m * b * ssw],
            [k * cst, -k * sst, m * a * a + (m + mh) * ln * ln, -m * ln * b * c],
            [-m * b * csw, m * b * ssw, -m * ln * b * c, m * b * b],
        ]
    )
    jac = np.array(
        [
            [1.0, 0.0, ln * cst, -ln * csw],
            [0.0, 1.0, -ln * sst, ln * ssw],
        ]
    )
    v_pre = np.array([0.0, 0.0, vst, vsw])
    minv_jt = np.linalg.solve(mfb, jac.T)
    impulse = np.linalg.solve(jac @ minv_jt, jac @ v_pre)
    v_post = v_pre - minv_jt @ impulse
    return np.array([sw, st, v_post[3], v_post[2]])


def simulate(
    x0: Sequence[float],
    steps: int,
    rtol: float,
    atol: float,
    params: dict[str, float] | None = None,
) -> dict[str, Any]:
    """Walk ``steps`` steps once (no timing repeats).

    Each swing phase is one ``solve_ivp(method="DOP853")`` call that stops at
    the foot-collision event; the reset is then applied and the next phase
    starts from the post-impact state.

    Returns a dict with ``post_impact_states`` (``steps x 4``), ``pre_impact_states``
    (``steps x 4``), ``step_durations`` (``steps``), ``impact_times``
    (cumulative, ``steps``) and ``nfev`` (total right-hand-side evaluations).
    """
    fun = make_dynamics(params)
    event = make_foot_collision(params)
    x = np.asarray(x0, dtype=float).copy()
    post = np.empty((steps, 4))
    pre = np.empty((steps, 4))
    durations = np.empty(steps)
    nfev = 0
    with warnings.catch_warnings():
        # rtol below 100*eps is clipped by SciPy; that is intended for the
        # reference solution, so the warning is silenced here.
        warnings.simplefilter("ignore", UserWarning)
        for k in range(steps):
            sol = solve_ivp(
                fun,
                (0.0, MAX_STEP_DURATION),
                x,
                method="DOP853",
                rtol=rtol,
                atol=atol,
                events=event,
            )
            nfev += sol.nfev
            if sol.status != 1 or sol.t_events[0].size == 0:
                raise RuntimeError(
                    f"step {k}: no foot collision within {MAX_STEP_DURATION} s "
                    f"(status {sol.status}: {sol.message})"
                )
            durations[k] = sol.t_events[0][0]
            pre[k] = sol.y_events[0][0]
            x = collision_dynamics(pre[k], params)
            post[k] = x
    return {
        "post_impact_states": post,
        "pre_impact_states": pre,
        "step_durations": durations,
        "impact_times": np.cumsum(durations),
        "nfev": nfev,
    }


def walk(
    x0: Sequence[float] | None = None,
    steps: int = 20,
    rtol: float = 1e-10,
    atol: float = 1e-10,
    repeats: int = 5,
    params: dict[str, float] | None = None,
) -> dict[str, Any]:
    """Time ``steps`` walking steps with DOP853 at ``rtol``/``atol``.

    The whole walk is repeated ``repeats`` times (at least 5) and the median
    wall time is reported.

    Returns a dict with keys

    * ``time_per_step_s``: median wall time of one walk divided by ``steps``,
    * ``min_time_per_step_s``: fastest repeat divided by ``steps``,
    * ``wall_times_s``: wall time of every repeat (whole walk),
    * ``post_impact_states``: ``steps x 4`` array (Drake state order),
    * ``step_durations``: simulated duration of each step (s),
    * ``impact_times``: cumulative simulated impact times (s),
    * ``nfev_per_step``: right-hand-side evaluations per walking step,
    * ``steps``, ``rtol``, ``atol``, ``repeats``.
    """
    x0 = LIMIT_CYCLE_X0 if x0 is None else x0
    repeats = max(int(repeats), 5)
    walls: list[float] = []
    out: dict[str, Any] = {}
    simulate(x0, min(steps, 2), rtol, atol, params)  # warm-up, untimed (as amble's first call is)
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = simulate(x0, steps, rtol, atol, params)
        walls.append(time.perf_counter() - t0)
    return {
        "time_per_step_s": statistics.median(walls) / steps,
        "min_time_per_step_s": min(walls) / steps,
        "wall_times_s": walls,
        "post_impact_states": out["post_impact_states"],
        "step_durations": out["step_durations"],
        "impact_times": out["impact_times"],
        "nfev_per_step": out["nfev"] / steps,
        "steps": steps,
        "rtol": rtol,
        "atol": atol,
        "repeats": repeats,
    }


def reference(
    x0: Sequence[float] | None = None,
    steps: int = 20,
    tol: float = 1e-13,
    params: dict[str, float] | None = None,
) -> dict[str, Any]:
    """Reference walk: DOP853 at ``rtol = atol = tol`` (default 1e-13).

    Returns the same keys as :func:`simulate` (``post_impact_states``,
    ``pre_impact_states``, ``step_durations``, ``impact_times``, ``nfev``) plus
    ``tol`` and ``self_error``: the max-abs difference of the post-impact states
    against a run at ``tol/4`` (SciPy clips ``rtol`` at ``100*eps``), an
    estimate of the reference's own error.
    """
    x0 = LIMIT_CYCLE_X0 if x0 is None else x0
    ref = simulate(x0, steps, tol, tol, params)
    tighter = simulate(x0, steps, tol / 4, tol / 4, params)
    ref["tol"] = tol
    ref["self_error"] = float(
        np.max(np.abs(ref["post_impact_states"] - tighter["post_impact_states"]))
    )
    return ref


def state_error(states: np.ndarray, ref_states: np.ndarray) -> dict[str, float]:
    """Accuracy of a walk against a reference walk.

    Returns ``final_error`` (max-abs error of the last post-impact state) and
    ``max_error`` (max-abs error over all post-impact states).
    """
    n = min(len(states), len(ref_states))
    diff = np.abs(np.asarray(states)[:n] - np.asarray(ref_states)[:n])
    return {"final_error": float(np.max(diff[-1])), "max_error": float(np.max(diff))}


def find_limit_cycle(
    x_guess: Sequence[float] = (0.0, 0.0, 0.4, -2.0),
    steps: int = 50,
    tol: float = 1e-13,
    params: dict[str, float] | None = None,
) -> dict[str, Any]:
    """Find the stable period-one limit cycle by iterating the step map.

    Walks ``steps`` steps from ``x_guess`` (default: the initial condition of
    Drake's ``examples/compass_gait/simulate.cc``, stance = swing = 0,
    stancedot = 0.4, swingdot = -2) and takes the last post-impact
    state, then polishes it with Newton iterations on the step-to-step map
    restricted to the post-impact section ``stance + swing = 2*slope``.

    Returns ``x0`` (post-impact state), ``residual`` (max-abs ``P(x0) - x0``),
    ``period`` (step duration), ``x_after_iteration`` (state after plain
    iteration) and ``eigenvalues`` (of the step-map Jacobian on the section).
    """
    p = _params(params)
    slope = p["slope"]
    walk_out = simulate(x_guess, steps, tol, tol, params)
    x_iter = walk_out["post_impact_states"][-1].copy()

    def step_map(z: np.ndarray) -> np.ndarray:
        """Section coordinates (stance, stancedot, swingdot) -> next ones."""
        x = np.array([z[0], 2 * slope - z[0], z[1], z[2]])
        y = simulate(x, 1, tol, tol, params)["post_impact_states"][0]
        return np.array([y[0], y[2], y[3]])

    z = np.array([x_iter[0], x_iter[2], x_iter[3]])
    jac = np.eye(3)
    for _ in range(6):
        fz = step_map(z)
        r = fz - z
        if np.max(np.abs(r)) < 1e-14:
            break
        jac = np.empty((3, 3))
        for j in range(3):
            dz = np.zeros(3)
            dz[j] = 1e-6
            jac[:, j] = (step_map(z + dz) - step_map(z - dz)) / 2e-6
        z = z - np.linalg.solve(jac - np.eye(3), r)
    x0 = np.array([z[0], 2 * slope - z[0], z[1], z[2]])
    one = simulate(x0, 1, tol, tol, params)
    return {
        "x0": x0,
        "residual": float(np.max(np.abs(one["post_impact_states"][0] - x0))),
        "period": float(one["step_durations"][0]),
        "x_after_iteration": x_iter,
        "eigenvalues": np.linalg.eigvals(jac),
    }


def main(argv: Sequence[str] | None = None) -> None:
    """Print timing and accuracy for DOP853 at the benchmark tolerances."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=20, help="walking steps per walk")
    ap.add_argument("--repeats", type=int, default=5, help="timing repeats (>= 5)")
    ap.add_argument(
        "--find-limit-cycle", action="store_true", help="recompute the limit-cycle state"
    )
    args = ap.parse_args(argv)

    x0 = LIMIT_CYCLE_X0
    if args.find_limit_cycle:
        lc = find_limit_cycle()
        x0 = lc["x0"]
        print("limit cycle (stance, swing, stancedot, swingdot):")
        print("  x0 =", "[" + ", ".join(repr(float(v)) for v in x0) + "]")
        print(f"  |P(x0) - x0| = {lc['residual']:.3e}, period = {lc['period']!r} s")
        print("  |eig(DP)| =", np.sort(np.abs(lc["eigenvalues"]))[::-1])
        print(
            "  after 50 plain steps: |x50 - x0| =",
            f"{np.max(np.abs(lc['x_after_iteration'] - x0)):.3e}",
        )

    ref = reference(x0, args.steps)
    print(
        f"reference: DOP853 rtol=atol=1e-13, {args.steps} steps, "
        f"self-error estimate {ref['self_error']:.1e}, "
        f"step duration {ref['step_durations'][-1]:.12f} s"
    )
    print(f"{'rtol=atol':>10} {'us/step':>10} {'nfev/step':>10} {'final err':>10} {'max err':>10}")
    for tol in (1e-8, 1e-10):
        res = walk(x0, args.steps, tol, tol, args.repeats)
        err = state_error(res["post_impact_states"], ref["post_impact_states"])
        print(
            f"{tol:>10.0e} {res['time_per_step_s'] * 1e6:>10.1f} "
            f"{res['nfev_per_step']:>10.1f} {err['final_error']:>10.2e} "
            f"{err['max_error']:>10.2e}"
        )


if __name__ == "__main__":
    main()
