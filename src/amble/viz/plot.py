"""Plots of trajectories and limit cycles (matplotlib; PNG, SVG or PDF by file suffix)."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ..analysis.limit_cycle import LimitCycle
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


def _flows(t: np.ndarray, rows: np.ndarray | None = None) -> list[slice]:
    """Row ranges of continuous flow: an event writes its pre and post rows at the same time, so
    the flow breaks between two rows of equal time (a line through them would draw the jump as
    if it were flow)."""
    n = len(t)
    cuts = [0] + [i for i in range(1, n) if t[i] == t[i - 1]] + [n]
    return [slice(a, b) for a, b in zip(cuts[:-1], cuts[1:]) if b > a]


def _draw_flow(ax: Any, x: np.ndarray, y: np.ndarray, t: np.ndarray, **kw: Any) -> Any:
    """One line per stretch of flow (the first carries the legend label); returns the first."""
    first = None
    for sl in _flows(t):
        (ln,) = ax.plot(x[sl], y[sl], **kw)
        if first is None:
            first = ln
            kw = {**kw, "label": "_nolegend_", "color": ln.get_color()}
    return first


def _world_potential(t: np.ndarray, pe: np.ndarray) -> np.ndarray:
    """The potential energy made continuous across events, relative to the first sample.

    Energies are computed in each step's own frame, and a footfall moves that frame to the new
    foothold: in the new frame the same configuration has a different potential (a walker going
    downhill gains ``m g`` times the step's drop). An event does not move the robot, so the
    potential just after it equals the one just before; shifting every later row by the
    difference gives the potential in the first step's frame (the world's), in which the total
    energy of a passive walker is constant between footfalls and drops at each."""
    out = np.array(pe, dtype=float)
    offset = 0.0
    for i in range(1, len(t)):
        if t[i] == t[i - 1] and np.isfinite(pe[i]) and np.isfinite(pe[i - 1]):
            offset += pe[i - 1] - pe[i]
        out[i] = pe[i] + offset
    return out - out[0]


def _mark_losses(ax: Any, traj: Trajectory, total: np.ndarray, unit: str) -> None:
    """Each footfall's change of total energy ``ΔE = E⁺ − E⁻``: a dashed red drop with its value
    (the losses of a passive gait are a few percent of the energy, invisible at the scale of the
    kinetic and potential energies)."""
    steps = traj.step_events
    label = "impact loss"
    for e in steps:
        i = int(np.searchsorted(traj.t, e.t))  # the pre row: the first row at the event's time
        if i + 1 >= len(traj.t) or traj.t[i + 1] != traj.t[i]:
            continue
        pre, post = total[i], total[i + 1]
        ax.plot([e.t, e.t], [pre, post], ls="--", color="C3", lw=1.2, marker="_", ms=8, label=label, gid="impact_loss")
        label = "_nolegend_"
        if len(steps) <= 12:  # beyond a dozen footfalls the numbers would overlap
            ax.annotate(f"{post - pre:+.3g}{(' ' + unit) if unit else ''}", (e.t, post), xytext=(2, -10),
                        textcoords="offset points", fontsize=7, color="C3")


def plot_trajectory(traj: Trajectory, path: str | Path | None = None, variables: Sequence[str] | None = None) -> Any:
    """Time series of state variables (default: all coordinates) with footfalls marked, the
    energies with the change of total energy at every footfall marked (dashed, with its value),
    and — for a controlled model — the inputs with their declared limits dashed."""
    plt = _plt()
    names = list(variables or [n for n in traj.state_names() if not n.endswith("_dot")])
    u = traj.inputs() if traj.system is not None else {}
    fig, axes = plt.subplots(3 if u else 2, 1, figsize=(8, 8 if u else 5.5), sharex=True)
    t = traj.t
    for n in names:
        _draw_flow(axes[0], t, traj.column(n), t, label=n)
    for e in traj.step_events:
        for ax in axes:
            ax.axvline(e.t, color="0.85", lw=0.8, zorder=0, gid="footfall")
    axes[0].set_ylabel(_label(traj, names, "coordinate"))
    axes[0].legend(loc="upper right", fontsize=8)
    energy = traj.energy()
    eunit = traj.unit("kinetic_energy")
    _draw_flow(axes[1], t, energy[:, 0], t, label="kinetic")
    potential = _world_potential(t, energy[:, 1])
    _draw_flow(axes[1], t, potential, t, label="potential (rel.)")
    axes[1].set_ylabel(_label(traj, ["kinetic_energy"], "energy"))
    axes[1].legend(loc="upper left", fontsize=8)
    # the total on its own scale (right axis), so that the steps it loses at footfalls show
    tot_ax = axes[1].twinx()
    total = energy[:, 0] + potential
    _draw_flow(tot_ax, t, total, t, label="total (rel., right axis)", color="k", lw=1)
    _mark_losses(tot_ax, traj, total, eunit)
    tot_ax.set_ylabel(f"total energy [{eunit}]" if eunit else "total energy")
    tot_ax.legend(loc="upper right", fontsize=8)
    axes[-1].set_xlabel(_label(traj, ["t"], "time"))
    if u:
        limits = {k: v for m in traj.system.modes.values() for k, v in m.input_limits.items()}
        for i, (k, v) in enumerate(u.items()):
            _draw_flow(axes[2], t, v, t, label=k, color=f"C{i}")
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
    """Phase portrait (coordinate vs its rate) of each coordinate over the last step(s): the flow
    solid, every impact jump dashed from an open circle (just before) to a filled one (just after)
    with an arrow head (thesis Figures 8, 10, 12). Given a :class:`LimitCycle`, its gait is
    simulated over two periods and the fixed point marked."""
    if isinstance(traj, LimitCycle):
        traj, cycle = traj.trajectory(), traj
    plt = _plt()
    steps = traj.step_events
    t0 = steps[-2].t if len(steps) >= 2 else traj.t[0]
    sel = traj.t >= t0
    mode0 = traj.mode_names[0]
    coords = [n for n in traj.state_names(mode0) if not n.endswith("_dot")]
    fig, ax = plt.subplots(figsize=(6.5, 5))
    jump_label = "impact jump"
    for i, n in enumerate(coords):
        q, qd = traj.column(n)[sel], traj.column(n + "_dot")[sel]
        ln = _draw_flow(ax, q, qd, traj.t[sel], label=n, color=f"C{i}")
        for e in [ev for ev in traj.events if ev.t >= t0]:
            src, dst = traj.state_names(e.source), traj.state_names(e.target)
            if n in src and n in dst:
                a = (e.x_pre[src.index(n)], e.x_pre[src.index(n + "_dot")])
                b = (e.x_post[dst.index(n)], e.x_post[dst.index(n + "_dot")])
                c = ln.get_color()
                ax.plot([a[0], b[0]], [a[1], b[1]], ls="--", color=c, lw=1, label=jump_label, gid="jump")
                ax.plot([a[0]], [a[1]], "o", mfc="white", mec=c, ms=4, label="_nolegend_", gid="jump_pre")
                ax.plot([b[0]], [b[1]], "o", color=c, ms=4, label="_nolegend_", gid="jump_post")
                ax.annotate("", xy=b, xytext=(a[0] + 0.8 * (b[0] - a[0]), a[1] + 0.8 * (b[1] - a[1])),
                            arrowprops={"arrowstyle": "->", "color": c, "lw": 1})
                jump_label = "_nolegend_"
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
