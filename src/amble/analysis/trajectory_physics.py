"""The physics of a run as columns of its trajectory file: ground reaction, friction ratio, work.

:meth:`Trajectory.table <amble.simulation.trajectory.Trajectory.table>` holds the states, the
energies, every input (joint torque or force) and its power ``P_j = u_j ω_j``. A walker's file also
needs what the ground does, which the simulation layer cannot compute alone (it is Newton's law
for the whole robot, :func:`amble.analysis.gait_check.ground_reaction`). These columns are added
by :func:`physics_columns`, each with its unit:

* ``stance_force_x``, (``stance_force_y`` in 3D,) ``stance_force_z`` — the ground's force on the
  robot ``F = Σ mᵢ aᵢ − m g`` in the stance-foot frame of the step (N; world axes, ``z`` up);
* ``stance_force_normal``, ``stance_force_tangential`` — its component along the slope's normal
  and the norm of the rest (N);
* ``friction_ratio`` — ``|F_t| / F_n``, the friction coefficient the foot needs (``inf`` where
  the ground would have to pull);
* ``work_<input>`` — the work input ``j`` has done since the start, ``∫ u_j ω_j dt`` (J, the
  trapezoidal rule on the samples; a footfall's two rows share a time, so no interval straddles
  an impact).

A model whose time is not in seconds (a dimensionless walker) gets the same columns without units.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .gait_check import ground_reaction


def _units(traj: Any, unit: str) -> str:
    return unit if traj.system is None or traj.system.time_unit == "s" else ""


def force_columns(traj: Any) -> dict[str, tuple[np.ndarray, str]]:
    """The ground reaction columns (name → (values, unit)) of a walker's run; empty for a
    system without a hip (no stance foot to name)."""
    if traj.system is None or getattr(traj.system, "hip", None) is None or len(traj.t) == 0:
        return {}
    F, Fn, Ft = ground_reaction(traj)
    unit = _units(traj, "N")
    cols = {"stance_force_x": (F[:, 0], unit)}
    if traj.system.dims == 3:
        cols["stance_force_y"] = (F[:, 1], unit)
    cols["stance_force_z"] = (F[:, 2], unit)
    cols["stance_force_normal"] = (Fn, unit)
    cols["stance_force_tangential"] = (Ft, unit)
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.where(Fn > 0, Ft / np.where(Fn > 0, Fn, 1.0), np.inf)
    cols["friction_ratio"] = (np.where(np.isnan(Fn), np.nan, ratio), "")
    return cols


def work_columns(traj: Any) -> dict[str, tuple[np.ndarray, str]]:
    """``work_<input>``: the cumulative work of every input since the run's start (J)."""
    if traj.system is None or len(traj.t) < 2:
        return {}
    power = traj.joint_power()
    dt = np.diff(traj.t)
    unit = _units(traj, "J")
    out = {}
    for name, p in power.items():
        p = np.nan_to_num(p)  # modes without the input do no work with it
        out[f"work_{name}"] = (np.concatenate([[0.0], np.cumsum(0.5 * (p[1:] + p[:-1]) * dt)]), unit)
    return out


def physics_columns(traj: Any) -> dict[str, tuple[np.ndarray, str]]:
    """Every column of this module for ``traj`` (name → (values per sample, unit)), ready for
    :meth:`Trajectory.save(path, extra=...) <amble.simulation.trajectory.Trajectory.save>`."""
    return {**force_columns(traj), **work_columns(traj)}


__all__ = ["force_columns", "physics_columns", "work_columns"]
