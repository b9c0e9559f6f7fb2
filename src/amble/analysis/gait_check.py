"""Physical feasibility of a gait: ground reaction, friction, foot clearance, impact, input limits.

A model pinned at its stance foot says nothing about whether the ground can hold it there. Over
a simulated gait this module asks, from Newton's law for the whole robot (independent of the
equations of motion that produced the motion):

* the **ground reaction** at the stance foot ``F = Σ mᵢ aᵢ − m g`` (the total mass times the
  acceleration of the centre of mass, less gravity; :mod:`amble.modelling.contact.reaction`):
  its normal component ``F_n`` (along the slope's normal) must be positive, and the friction
  ratio ``|F_t|/F_n`` below ``μ``;
* the **swing foot** must stay above the ground between footfalls (the height of the impacting
  point along the slope's normal, away from the first and last ``margin`` of each step);
* at each **footfall** the ground's impulse ``ΔP = m (v⁺_com − v⁻_com)`` must push (positive
  normal component), and the trailing foot must leave the ground (its normal velocity just after
  the footfall positive) — otherwise the impact assumed is not the one that happens;
* every **input** within its declared limit.

The accelerations come from the compiled right-hand side at each sample.
"""

from __future__ import annotations

import math
import weakref
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np
import sympy as sp

from ..errors import AmbleError, ModelError
from ..modelling.contact import reaction

#: default friction coefficient of the stance foot
MU = 0.7
#: fraction of each step at its start and end where the swing foot may touch the ground
MARGIN = 0.05

_FN: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


@dataclass
class GaitCheck:
    """Worst values over the gait and whether each check passed (forces in N, heights in m)."""

    min_normal_force: float
    max_friction_ratio: float
    min_swing_clearance: float
    min_normal_impulse: float
    min_trailing_foot_lift_speed: float
    max_input_ratio: float  # max |u_j| / limit_j over inputs with a limit (0 without any)
    mu: float
    normal_force_positive: bool
    friction_ok: bool
    swing_foot_clear: bool
    impulse_positive: bool
    trailing_foot_leaves: bool
    within_limits: bool

    @property
    def ok(self) -> bool:
        return all((self.normal_force_positive, self.friction_ok, self.swing_foot_clear, self.impulse_positive,
                    self.trailing_foot_leaves, self.within_limits))

    def to_json(self) -> dict[str, Any]:
        out = {k: (None if isinstance(v, float) and not math.isfinite(v) else v) for k, v in asdict(self).items()}
        out["ok"] = self.ok
        return out


def _momentum_functions(model: Any) -> tuple[Any, Any]:
    """NumPy functions of the ground's force ``(q, q̇, q̈, params)`` and of the total linear
    momentum ``(q, q̇, params)`` (:mod:`amble.modelling.contact.reaction`)."""
    hit = _FN.get(model)
    if hit is None:
        q, qd = model.q, model.qd
        args = [*q, *qd, *reaction.accelerations(model), *model.params]
        hit = (sp.lambdify(args, list(reaction.ground_force(model)), "numpy", cse=True),
               sp.lambdify([*q, *qd, *model.params], list(reaction.linear_momentum(model)), "numpy"))
        _FN[model] = hit
    return hit


def _normal(system: Any, params: dict) -> np.ndarray:
    """Unit normal of the ground (3 components; 2D models have y = 0)."""
    slope = system.slope_value(params)
    return np.array([math.sin(slope), 0.0, math.cos(slope)])


def ground_reaction(traj: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The stance foot's ground reaction per sample, ``F = Σ mᵢ aᵢ − m g`` (N, (N, 3), world
    axes of the step's frame; 2D models have y = 0), its normal component ``F_n`` and the norm
    of its tangential part ``|F_t|`` along the ground of a walker."""
    system, k, p = traj.system.symbolic(), traj.kernels, traj.params  # the masses are declared, symbolic
    n3 = _normal(system, traj.parameters)
    F = np.full((len(traj.t), 3), np.nan)
    for mi, mname in enumerate(traj.mode_names):
        rows = np.flatnonzero(traj.mode == mi)
        if rows.size == 0:
            continue
        model = system.modes[mname]
        force, _ = _momentum_functions(model)
        pm = [traj.parameters[str(s)] for s in model.params]
        n = len(model.q)
        for r in rows:
            x = traj.x[r, : 2 * n]
            qdd = k.rhs(mname, float(traj.t[r]), x, p)[n:]
            f = np.asarray(force(*x, *qdd, *pm), float)
            F[r] = f if model.dims == 3 else (f[0], 0.0, f[1])
    Fn = F @ n3
    Ft = np.linalg.norm(F - Fn[:, None] * n3[None, :], axis=1)
    return F, Fn, Ft


def check_gait(traj: Any, mu: float = MU, margin: float = MARGIN) -> GaitCheck:
    """Feasibility checks (see the module) over a :class:`~amble.simulation.trajectory.Trajectory`
    of whole steps (e.g. ``LimitCycle.trajectory()``)."""
    if not mu > 0:
        raise AmbleError(f"friction coefficient μ must be positive, got {mu}")
    if traj.system is None or getattr(traj.system, "hip", None) is None:
        raise ModelError("check_gait needs a trajectory of a walker")
    system = traj.system.symbolic()
    k, p = traj.kernels, traj.params
    n3 = _normal(system, traj.parameters)
    _, F_n, F_t = ground_reaction(traj)
    ratio = np.where(F_n > 0, F_t / np.where(F_n > 0, F_n, 1.0), np.inf)
    steps = [tr for tr in system.transitions if tr.step and tr.reset is not None and tr.reset.impact_point]
    if not steps:
        raise ModelError(f"system {system.name!r}: check_gait needs footfalls that are impacts")
    names = k.meta["points"]
    pidx = names.index(steps[0].reset.impact_point)
    pos, _ = k.kinematics_rows(traj.t, traj.mode, traj.x, p)
    height = pos[:, pidx, :] @ n3
    ev_t = [traj.t[0]] + [e.t for e in traj.step_events] + [traj.t[-1]]
    clear = []
    for a, b in zip(ev_t[:-1], ev_t[1:]):
        sel = (traj.t > a + margin * (b - a)) & (traj.t < b - margin * (b - a))
        if np.any(sel):
            clear.append(float(np.min(height[sel])))
    impulses, lifts = [], []
    for e in traj.step_events:
        src, dst = system.modes[e.source], system.modes[e.target]
        _, vs = _momentum_functions(src)
        _, vd = _momentum_functions(dst)
        dP = (np.asarray(vd(*e.x_post, *[traj.parameters[str(s)] for s in dst.params]), float)
              - np.asarray(vs(*e.x_pre, *[traj.parameters[str(s)] for s in src.params]), float))
        impulses.append(float(dP @ (n3 if dP.size == 3 else n3[[0, 2]])))
        # the trailing foot: the point that sits, just after the footfall, where the old stance
        # foot (the old frame's origin) was
        pre, _ = k.kinematics_rows(np.array([e.t]), np.array([k.mode_index(e.source)]), e.x_pre[None, :], p)
        post, vpost = k.kinematics_rows(np.array([e.t]), np.array([k.mode_index(e.target)]), e.x_post[None, :], p)
        _, flip = system.frame_change(e.name)
        old_origin = -np.asarray(flip) * pre[0, pidx]
        d = np.linalg.norm(post[0] - old_origin[None, :], axis=1)
        j = int(np.nanargmin(d))
        lifts.append(float(vpost[0, j] @ n3) if d[j] < 1e-6 * (1 + np.nanmax(np.abs(post[0]))) else math.nan)
    u = traj.inputs() if any(getattr(m, "inputs", None) for m in system.modes.values()) else {}
    limits = {kk: v for m in system.modes.values() for kk, v in m.input_limits.items()}
    ur = [float(np.nanmax(np.abs(v)) / limits[kk]) for kk, v in u.items() if limits.get(kk)]
    minf = float(np.nanmin(F_n)) if F_n.size else math.nan
    maxr = float(np.nanmax(ratio)) if ratio.size else math.nan
    minc = min(clear) if clear else math.nan
    mini = min(impulses) if impulses else math.nan
    minl = min(lifts) if lifts else math.nan
    maxu = max(ur) if ur else 0.0
    return GaitCheck(minf, maxr, minc, mini, minl, maxu, mu, bool(minf > 0), bool(maxr < mu), bool(minc > 0),
                     bool(mini > 0), bool(minl > 0), bool(maxu <= 1.0))
