"""World poses of a robot's links over a trajectory, for drawing their meshes.

A model read from a URDF keeps its file and the links that are no body of its tree (massless
links on fixed joints: a frame of the body they hang from; ``RigidTree.link_frames``). The pose of
every link is computed here by forward kinematics in NumPy from the tree's joints, each body's
frame ``R = R_parent Ro X(θ) Rpost``, ``p = p_parent + R_parent xyz (+ axis θ) (+ post_xyz)`` as
:meth:`amble.modelling.tree.RigidTree.local_transform` writes it, at the coordinates of each
frame (interpolated between samples of one mode as :meth:`Trajectory.resample` does), then placed
in the world by the trajectory's frame changes (:meth:`Trajectory.world_frames`).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import sympy as sp

from ..modelling.sparse_algebra import rpy_matrix
from ..modelling.tree import RigidTree
from ..simulation.trajectory import Trajectory

__all__ = ["link_poses", "robot_file"]

#: A pose track: positions ``(F, 3)`` (m) and rotations ``(F, 3, 3)`` (link axes in the world).
Poses = dict[str, tuple[np.ndarray, np.ndarray]]


def _tree(model: Any) -> RigidTree | None:
    tree = getattr(model, "tree", None)
    return tree if isinstance(tree, RigidTree) and tree.file is not None else None


def robot_file(system: Any) -> Path | None:
    """The robot file (URDF or MJCF) every mode of ``system`` was read from, or ``None`` (a model built in code, a
    constrained or a mixed one)."""
    files = {None if _tree(m) is None else Path(_tree(m).file) for m in system.modes.values()}
    return files.pop() if len(files) == 1 else None


def _axis_rotation(axis: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """Rodrigues' rotations ``(F, 3, 3)`` about the unit ``axis`` by the angles ``theta``."""
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    c, s = np.cos(theta)[:, None, None], np.sin(theta)[:, None, None]
    return np.eye(3) + s * k + (1 - c) * (k @ k)


def _value(v: Any, subs: dict) -> float:
    return float(sp.sympify(v).subs(subs)) if isinstance(v, sp.Basic) else float(v)


def _vector(v: Any, subs: dict) -> np.ndarray:
    return np.zeros(3) if v is None else np.array([_value(x, subs) for x in v])


def _bodies(tree: RigidTree, q: dict[str, np.ndarray], n: int, subs: dict) -> Poses:
    """Every body's frame in the model frame at ``n`` configurations (coordinate name → values)."""
    out: Poses = {}
    names = [str(s) for s in tree.model.q]
    world = (np.broadcast_to(np.eye(3), (n, 3, 3)), np.zeros((n, 3)))
    for b in tree.bodies:
        j = b.joint
        R0, p0 = out[b.parent.name] if b.parent is not None else world
        Ro = np.asarray(j.rotation, dtype=float) if j.rotation is not None else rpy_matrix(j.rpy)
        R, p = R0 @ Ro, p0 + R0 @ _vector(j.xyz, subs)
        if b.coordinate is not None:
            theta = _value(b.multiplier, subs) * q[names[b.index]] + (j.offset if j.mimic else 0.0)
            axis = np.asarray(j.axis, dtype=float)
            if j.type == "prismatic":
                p = p + (R @ axis) * theta[:, None]
            else:
                R = R @ _axis_rotation(axis, theta)
        if j.post_xyz is not None:
            p = p + R @ _vector(j.post_xyz, subs)
        if j.post_rotation is not None:
            R = R @ np.asarray(j.post_rotation, dtype=float)
        out[b.name] = (R, p)
    return out


def _samples(traj: Trajectory, times: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Each time's sample row, the next row and the weight between them (0 across a mode switch
    or an event), as :meth:`Trajectory.resample` interpolates."""
    idx = np.clip(np.searchsorted(traj.t, times, side="right") - 1, 0, len(traj.t) - 1)
    nxt = np.clip(idx + 1, 0, len(traj.t) - 1)
    dt = traj.t[nxt] - traj.t[idx]
    same = (traj.mode[nxt] == traj.mode[idx]) & (dt > 0)
    w = np.where(same, (times - traj.t[idx]) / np.where(dt > 0, dt, 1.0), 0.0)
    return idx, nxt, w


def link_poses(traj: Trajectory, times: np.ndarray, links: set[str] | None = None) -> Poses:
    """World poses of the robot file's links at ``times`` (s): link → ``(positions (F, 3) m,
    rotations (F, 3, 3))``, the link frame's axes as columns (an MJCF file's bodies are its
    links); ``links``: only these. Empty for a system that was not read from a robot file."""
    system = traj.system
    if robot_file(system) is None:
        return {}
    times = np.asarray(times, dtype=float)
    idx, nxt, w = _samples(traj, times)
    origins, axes = traj.world_frames()
    F = len(times)
    out: Poses = {}
    for mi, mode in enumerate(traj.mode_names):
        rows = np.nonzero(traj.mode[idx] == mi)[0]
        if not len(rows):
            continue
        model = system.modes[mode]
        tree = _tree(model)
        names = traj.state_names(mode)
        x = traj.x[idx[rows]] + (traj.x[nxt[rows]] - traj.x[idx[rows]]) * w[rows, None]
        x = np.where(np.isfinite(x), x, traj.x[idx[rows]])
        q = {n: x[:, names.index(n)] for n in (str(s) for s in model.q)}
        subs = {s: traj.parameters.get(str(s), v) for s, v in model.params.items()}
        bodies = _bodies(tree, q, len(rows), subs)
        # the bodies that are links (a composite joint's inner frames are not)
        frames = {lk: bodies[lk] for lk in bodies if lk in tree.com_points and (links is None or lk in links)}
        for lk, (body, Rl, origin) in tree.link_frames.items():
            if (links is None or lk in links) and (body is None or body in bodies):
                R, p = bodies[body] if body is not None else (np.eye(3)[None], np.zeros((1, 3)))
                frames[lk] = (R @ np.asarray(Rl, dtype=float), p + R @ _vector(origin, subs))
        Fw, ow = axes[idx[rows]], origins[idx[rows]]
        for lk, (R, p) in frames.items():
            if lk not in out:
                out[lk] = (np.full((F, 3), np.nan), np.full((F, 3, 3), np.nan))
            out[lk][0][rows] = (Fw @ p[..., None])[..., 0] + ow
            out[lk][1][rows] = Fw @ R
    return out
