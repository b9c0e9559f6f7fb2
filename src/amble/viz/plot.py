"""Plots of trajectories and limit cycles (matplotlib; PNG, SVG or PDF by file suffix)."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ..analysis.poincare import LimitCycle
from ..simulation.trajectory import Trajectory


def _plt():
    import matplotlib

    if matplotlib.get_backend().lower() not in ("agg", "module://matplotlib_inline.backend_inline"):
        matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


_QUANTITY = {"rad": "angle", "rad/s": "angular velocity", "m": "position", "m/s": "velocity", "s": "time",
             "J": "energy", "N·m": "torque", "N": "force", "W": "power"}


def _label(traj: Trajectory, names: Sequence[str], fallback: str) -> str:
    """Axis label from the declared units of the plotted columns: ``angle [rad]`` when they share
    one unit, ``fallback [m, rad]`` when they mix."""
    units = sorted({traj.unit(n) for n in names} - {""})
    if len(units) == 1:
        return f"{_QUANTITY.get(units[0], fallback)} [{units[0]}]"
    return f"{fallback} [{', '.join(units)}]" if units else fallback


def plot_trajectory(traj: Trajectory, path: str | Path | None = None, variables: Sequence[str] | None = None) -> Any:
    """Time series of state variables (default: all coordinates) with footfalls marked, the
    energies, and — for a controlled model — the inputs with their declared limits dashed."""
    plt = _plt()
    names = list(variables or [n for n in traj.state_names() if not n.endswith("_dot")])
    u = traj.inputs() if traj.system is not None else {}
    fig, axes = plt.subplots(3 if u else 2, 1, figsize=(8, 8 if u else 5.5), sharex=True)
    for n in names:
        axes[0].plot(traj.t, traj.column(n), label=n)
    for e in traj.step_events:
        for ax in axes:
            ax.axvline(e.t, color="0.85", lw=0.8, zorder=0)
    axes[0].set_ylabel(_label(traj, names, "coordinate"))
    axes[0].legend(loc="upper right", fontsize=8)
    energy = traj.energy()
    axes[1].plot(traj.t, energy[:, 0], label="kinetic")
    axes[1].plot(traj.t, energy[:, 1] - energy[0, 1], label="potential (rel.)")
    axes[1].plot(traj.t, energy.sum(axis=1) - energy[0, 1], label="total (rel.)", color="k", lw=1)
    axes[1].set_ylabel(_label(traj, ["kinetic_energy"], "energy"))
    axes[-1].set_xlabel(_label(traj, ["t"], "time"))
    axes[1].legend(loc="upper right", fontsize=8)
    if u:
        limits = {k: v for m in traj.system.modes.values() for k, v in m.input_limits.items()}
        for i, (k, v) in enumerate(u.items()):
            axes[2].plot(traj.t, v, label=k, color=f"C{i}")
            if limits.get(k) is not None:
                for sgn in (-1, 1):
                    axes[2].axhline(sgn * limits[k], color=f"C{i}", ls="--", lw=0.8)
        axes[2].set_ylabel(_label(traj, list(u), "input"))
        axes[2].legend(loc="upper right", fontsize=8)
    axes[0].set_title(f"{traj.kernels.meta['name']}: {traj.status}, {traj.steps} steps")
    fig.tight_layout()
    return _finish(fig, path)


def plot_limit_cycle(traj: Trajectory | LimitCycle, path: str | Path | None = None,
                     cycle: LimitCycle | None = None) -> Any:
    """Phase portrait (coordinate vs its rate) of each coordinate over the last step(s), with the
    impact jumps drawn as arrows (thesis Figures 8, 10, 12). Given a :class:`LimitCycle`, its
    gait is simulated over two periods and the fixed point marked."""
    if isinstance(traj, LimitCycle):
        traj, cycle = traj.trajectory(), traj
    plt = _plt()
    steps = traj.step_events
    t0 = steps[-2].t if len(steps) >= 2 else traj.t[0]
    sel = traj.t >= t0
    mode0 = traj.mode_names[0]
    coords = [n for n in traj.state_names(mode0) if not n.endswith("_dot")]
    fig, ax = plt.subplots(figsize=(6.5, 5))
    for i, n in enumerate(coords):
        q, qd = traj.column(n)[sel], traj.column(n + "_dot")[sel]
        (ln,) = ax.plot(q, qd, label=n, color=f"C{i}")
        names_pre = traj.state_names(steps[-1].source) if steps else []
        names_post = traj.state_names(steps[-1].target) if steps else []
        for e in [ev for ev in traj.events if ev.t >= t0]:
            src, dst = traj.state_names(e.source), traj.state_names(e.target)
            if n in src and n in dst:
                a = (e.x_pre[src.index(n)], e.x_pre[src.index(n + "_dot")])
                b = (e.x_post[dst.index(n)], e.x_post[dst.index(n + "_dot")])
                ax.annotate("", xy=b, xytext=a, arrowprops={"arrowstyle": "->", "color": ln.get_color(), "lw": 1,
                                                            "ls": "--"})
        del names_pre, names_post
    if cycle is not None:
        fp = dict(zip(cycle.state_names, cycle.fixed_point))
        ax.plot([fp[n] for n in coords], [fp[n + "_dot"] for n in coords], "k*", ms=9, label="fixed point")
        mods = ", ".join(f"{abs(m):.3f}" for m in cycle.multipliers)
        ax.set_title(f"{cycle.system}: step {cycle.step_time:.4f} {traj.unit('t')}, |multipliers| {mods}",
                     fontsize=9)
    ax.set_xlabel(_label(traj, coords, "coordinate"))
    ax.set_ylabel(_label(traj, [n + "_dot" for n in coords], "rate"))
    ax.axhline(0, color="0.85", lw=0.8, zorder=0)
    ax.legend(fontsize=8)
    fig.tight_layout()
    return _finish(fig, path)


def _finish(fig: Any, path: str | Path | None) -> Any:
    if path is None:
        return fig
    fig.savefig(path, dpi=120)
    import matplotlib.pyplot as plt

    plt.close(fig)
    return Path(path)


def plot_series(x: np.ndarray, ys: dict[str, np.ndarray], path: str | Path | None, xlabel: str, ylabel: str,
                title: str = "", style: str = "-") -> Any:
    """A plain multi-line plot (sweep results)."""
    plt = _plt()
    fig, ax = plt.subplots(figsize=(7, 4.5))
    for k, y in ys.items():
        ax.plot(x, y, style, label=k, ms=2)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    if title:
        ax.set_title(title)
    if len(ys) > 1:
        ax.legend(fontsize=8)
    fig.tight_layout()
    return _finish(fig, path)
