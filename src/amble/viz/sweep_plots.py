"""Plots of parameter sweeps (matplotlib, Agg backend): bifurcation diagram, fixed-point branch
with multiplier moduli, continued branches with their bifurcations, two-parameter stability map,
basin of attraction, Poincaré iterates.

Every function writes one figure to ``path`` (format from the suffix: .png, .svg or .pdf) and
returns the path. Angles are in rad, angular velocities in rad/s; a swept parameter's unit is
taken from :data:`UNITS` when known (``slope`` rad, masses kg, lengths m, ``g`` m/s²).
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

import numpy as np

from .errors import VizError

UNITS = {"slope": "rad", "mh": "kg", "m": "kg", "a": "m", "b": "m", "g": "m/s²", "l": "m", "r": "m"}
_SUFFIXES = (".png", ".svg", ".pdf")
#: the marker of each located bifurcation row of a continuation (fold, flip, torus)
_MARKERS = {"fold": "^", "flip": "o", "torus": "s"}


def _plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def branch_axes(a1: Any, a2: Any, coordinate: str | None, param: str) -> None:
    """Label a branch figure's two axes: the post-impact ``coordinate`` over the parameter above,
    the largest multiplier modulus (log scale, the stability line |μ| = 1 dashed) below."""
    a2.axhline(1.0, ls="--", color="k", lw=1)
    a2.set_yscale("log")
    a1.set_ylabel(f"post-impact {_label(coordinate)}" if coordinate else "post-impact state")
    a1.legend(fontsize=8)
    a1.grid(alpha=0.3)
    a2.set_ylabel("largest |μ| (1)")
    a2.set_xlabel(_label(param))
    a2.grid(alpha=0.3, which="both")


def _label(name: str) -> str:
    unit = UNITS.get(name)
    if unit is None:
        unit = "rad/s" if name.endswith("_dot") else ("rad" if name in ("stance", "swing", "theta", "phi") else "")
    return f"{name} ({unit})" if unit else name


def _save(fig: Any, path: str | os.PathLike) -> Path:
    p = Path(path)
    if p.suffix.lower() not in _SUFFIXES:
        raise VizError(f"plot file {str(p)!r} must end with one of {', '.join(_SUFFIXES)}")
    fig.savefig(p, dpi=120, bbox_inches="tight")
    _plt().close(fig)
    return p


def plot_bifurcation(result: Any, path: str | os.PathLike, *, title: str | None = None) -> Path:
    """Post-transient iterates of the kept coordinate vs the swept parameter (one dot each);
    values where the walker fell are marked below the axis."""
    plt = _plt()
    pname = result.params[0]
    xs, ys, fell = [], [], []
    coord = "state"
    for r in result.rows:
        v = float(r[pname])
        coord = r.get("coordinate") or coord
        if r["status"] != "ok":
            fell.append(v)
            continue
        it = json.loads(r["iterates"])
        xs.extend([v] * len(it))
        ys.extend(it)
    fig, ax = plt.subplots(figsize=(7, 4.5))
    ax.plot(xs, ys, ".", ms=1.0 if len(xs) > 5000 else 2.0, color="k", lw=0)
    if fell:
        ax.plot(fell, [ax.get_ylim()[0]] * len(fell) if ys else [0] * len(fell), "x", color="tab:red", ms=4,
                label="fell / failed")
        ax.legend(loc="best", fontsize=8)
    ax.set_xlabel(_label(pname))
    ax.set_ylabel(f"post-impact {_label(coord)}")
    ax.set_title(title or "Bifurcation diagram (post-transient return-map iterates)")
    ax.grid(alpha=0.3)
    return _save(fig, path)


def plot_branch(result: Any, path: str | os.PathLike, *, coordinate: str | None = None,
                title: str | None = None) -> Path:
    """Fixed-point branch: one coordinate of the fixed point (top) and the moduli of the Floquet
    multipliers (bottom, log scale, |λ| = 1 dashed) vs the parameter; stable points filled,
    unstable hollow, failed points marked ×."""
    plt = _plt()
    pname = result.params[0]
    coord = coordinate or (result.state_names[0] if result.state_names else None)
    ok = [r for r in result.rows if r["status"] == "ok"]
    bad = [float(r[pname]) for r in result.rows if r["status"] != "ok"]
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(7, 6), sharex=True)
    for stable, style in ((True, dict(mfc="tab:blue")), (False, dict(mfc="white"))):
        rs = [r for r in ok if (r["stable"] == "true") == stable]
        if not rs:
            continue
        v = [float(r[pname]) for r in rs]
        lab = "stable" if stable else "unstable"
        if coord is not None:
            a1.plot(v, [float(r[f"x_{coord}"]) for r in rs], "o", ms=4, mec="tab:blue", label=lab, **style)
        for r, x in zip(rs, v):
            mods = json.loads(r["moduli"])
            a2.plot([x] * len(mods), mods, "o", ms=3, mec="tab:purple", **({"mfc": "tab:purple"} if stable
                                                                            else {"mfc": "white"}))
    a2.plot([], [], "o", ms=3, mec="tab:purple", mfc="tab:purple", label="|λ|, stable gait")
    a2.plot([], [], "o", ms=3, mec="tab:purple", mfc="white", label="|λ|, unstable gait")
    a2.axhline(1.0, ls="--", color="k", lw=1)
    a2.set_yscale("log")
    if bad:
        a1.plot(bad, [np.nan] * len(bad), "x")
        for x in bad:
            a2.axvline(x, color="tab:red", alpha=0.25, lw=1)
        a2.plot([], [], color="tab:red", alpha=0.4, label="no fixed point")
    a1.set_ylabel(f"fixed point {_label(coord)}" if coord else "fixed point")
    a1.legend(fontsize=8)
    a1.grid(alpha=0.3)
    a2.set_ylabel("multiplier modulus |λ| (1)")
    a2.set_xlabel(_label(pname))
    a2.legend(fontsize=8)
    a2.grid(alpha=0.3, which="both")
    a1.set_title(title or "Fixed-point branch and Floquet multipliers")
    return _save(fig, path)


def _edges(v: np.ndarray) -> np.ndarray:
    """Cell edges of grid values ``v`` (in their order): midway between neighbours, the outer
    ones half a spacing beyond the ends (half a unit, or half the value, for a single value)."""
    if v.size == 1:
        h = 0.5 * (abs(v[0]) or 1.0)
        return np.array([v[0] - h, v[0] + h])
    mid = 0.5 * (v[1:] + v[:-1])
    return np.r_[2 * v[0] - mid[0], mid, 2 * v[-1] - mid[-1]]


#: how each bifurcation curve of a map is drawn on the cell boundaries: colour, line style, label
_CURVES = {"fold": ("tab:orange", "-", "fold (μ = +1)"),
           "flip": ("tab:red", "--", "flip (period doubling, μ = −1)"),
           "torus": ("magenta", ":", "torus (Neimark–Sacker, complex |μ| = 1)")}


def _boundary(i: int, j: int, i2: int, j2: int, ae: np.ndarray, be: np.ndarray) -> list[tuple[float, float]]:
    """The segment (in plot coordinates: x the second parameter, y the first) of the boundary
    between neighbouring cells (i, j) and (i2, j2)."""
    if i2 == i:  # neighbours along the second parameter: a vertical edge
        x = be[j + 1]
        return [(x, ae[i]), (x, ae[i + 1])]
    y = ae[i + 1]
    return [(be[j], y), (be[j + 1], y)]


def _draw_curves(ax: Any, result: Any, ae: np.ndarray, be: np.ndarray, system: Any, params: Any,
                 found: list | None) -> None:
    """The map's bifurcation curves (fold, flip, torus crossings between cells of one branch) and
    the boundaries where a row's branch changed, as segments on the cell boundaries."""
    from matplotlib.collections import LineCollection

    from ..analysis.map_bifurcations import branch_boundaries, map_crossings

    if found is None:
        has_mu = any(r.get("multipliers") for r in result.rows if r.get("status") == "ok")
        found = map_crossings(result, system, params=params) if has_mu and hasattr(result, "kind") else []
    for kind, (col, ls, label) in _CURVES.items():
        segs = [_boundary(c.i, c.j, c.i2, c.j2, ae, be) for c in found if c.kind == kind]
        if segs:
            ax.add_collection(LineCollection(segs, colors=col, linestyles=ls, linewidths=2.6, label=label,
                                             gid=f"crossing_{kind}", capstyle="round"))
    segs = [_boundary(*p, ae, be) for p in branch_boundaries(result)]
    if segs:
        ax.add_collection(LineCollection(segs, colors="k", linestyles="-.", linewidths=1.2,
                                         label="branch changed (no bifurcation)", gid="branch_boundary"))


def plot_parameter_map(result: Any, path: str | os.PathLike, *, title: str | None = None, system: Any = None,
                       params: Any = None, crossings: list | None = None) -> Path:
    """Two-parameter map of the largest multiplier modulus (colour, log scale) over cells centred
    on the grid values, the |λ| = 1 contour, grey cells where no fixed point was found, and the
    map's bifurcation curves on the cell boundaries: fold (orange), flip (red, dashed) and torus
    (magenta, dotted) crossings between neighbouring cells of one branch
    (:func:`amble.analysis.map_bifurcations.map_crossings`; ``system`` and ``params``, the
    sweep's other parameters, decide exactly whether cells of different rows are one branch;
    ``crossings``: that function's answer, when already at hand). Where a row's branch changed,
    the boundary is dash-dotted and the cells off the row's main branch are marked ×: a |λ| = 1
    contour there is a change of gait, not a bifurcation."""
    plt = _plt()
    from matplotlib.colors import LogNorm

    a, b = result.params
    ni = max(int(r["i"]) for r in result.rows) + 1
    nj = max(int(r["j"]) for r in result.rows) + 1
    M = np.full((ni, nj), np.nan)
    av, bv = np.full(ni, np.nan), np.full(nj, np.nan)
    for r in result.rows:
        i, j = int(r["i"]), int(r["j"])
        av[i], bv[j] = float(r[a]), float(r[b])
        if r["status"] == "ok":
            M[i, j] = float(r["max_modulus"])
    ae, be = _edges(av), _edges(bv)
    fig, ax = plt.subplots(figsize=(6.5, 5))
    ax.set_facecolor("0.85")
    finite = np.isfinite(M).any()
    im = ax.pcolormesh(be, ae, np.ma.masked_invalid(M), cmap="viridis", shading="flat",
                       norm=LogNorm(vmin=np.nanmin(M) if finite else 0.1,
                                    vmax=max(np.nanmax(M), 1.01) if finite else 10))
    if ni > 1 and nj > 1 and finite:
        ax.contour(bv, av, M, levels=[1.0], colors="w", linewidths=1.5)
    fig.colorbar(im, ax=ax, label="largest multiplier modulus |λ| (1)")
    _draw_curves(ax, result, ae, be, system, params, crossings)
    branched = _mark_branches(ax, result.rows, a, b)
    if ax.get_legend_handles_labels()[0]:
        ax.legend(fontsize=7, loc="upper right", framealpha=0.85)
    ax.set_xlim(be.min(), be.max())
    ax.set_ylim(ae.min(), ae.max())
    ax.set_xlabel(_label(b))
    ax.set_ylabel(_label(a))
    ax.set_title(title or "Stability map (white: |λ| = 1; grey: no fixed point"
                 + ("; ×: another branch)" if branched else ")"), fontsize=10)
    return _save(fig, path)


def _branch_id(row: Any) -> str | None:
    """A row's branch id as text, ``None`` when the sweep does not record one (older files, or
    sweeps that follow a single branch)."""
    try:
        v = row["branch"]
    except (KeyError, IndexError, TypeError):
        return None
    if v is None or (isinstance(v, float) and not np.isfinite(v)) or str(v).strip() in ("", "nan", "None"):
        return None
    try:
        return str(int(float(v)))
    except (TypeError, ValueError):
        return str(v)


def _mark_branches(ax: Any, rows: Any, a: str, b: str) -> bool:
    """Mark the cells whose fixed point lies on another branch than most of its row's: a colour
    alone cannot tell two gaits of similar stability apart. A map's row (one value of ``a``) is
    one task that continues its gait along ``b`` and starts its branch ids afresh, so ids are
    compared within a row only (across rows the same gait has different ids). Returns whether
    any cell was marked."""
    ids = [(_branch_id(r), r) for r in rows if r["status"] == "ok"]
    ids = [(k, r) for k, r in ids if k is not None]
    by_row: dict[str, list[tuple[str, Any]]] = {}
    for k, r in ids:
        by_row.setdefault(str(r["i"]), []).append((k, r))
    marked: dict[str, list[tuple[float, float]]] = {}
    for cells in by_row.values():
        values, counts = np.unique([k for k, _ in cells], return_counts=True)
        main = values[int(np.argmax(counts))]
        for k, r in cells:
            if k != main:
                marked.setdefault(k, []).append((float(r[b]), float(r[a])))
    for n, (k, pts) in enumerate(sorted(marked.items())):
        xy = np.array(pts)
        ax.scatter(xy[:, 0], xy[:, 1], marker="x", s=28, color=f"C{(n + 1) % 10}", linewidths=1.2,
                   label=f"branch {k} (not its row's main one)", gid="branch_change")
    return bool(marked)


def plot_continuation(result: Any, path: str | os.PathLike, *, coordinate: str | None = None,
                      title: str | None = None) -> Path:
    """Continued branches: top, one coordinate (default the first) of every post-impact state of
    each gait's orbit vs the parameter — a period-k branch draws k curves — solid where the gait
    is stable, dotted where not, folds (▲) and flips (●) marked; bottom, the largest multiplier
    modulus of each branch (log scale, |μ| = 1 dashed)."""
    plt = _plt()
    pname = result.params[0]
    names = list(result.state_names)
    coord = coordinate or (names[0] if names else None)
    ci = names.index(coord) if coord in names else 0
    ok = [r for r in result.rows if r["status"] == "ok"]
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(7, 6.5), sharex=True, gridspec_kw={"height_ratios": [2, 1]})
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for b in sorted({int(r["branch"]) for r in ok}):
        pts = [r for r in ok if int(r["branch"]) == b and r["row"] == "point"]
        if not pts:
            continue
        col = colours[b % len(colours)]
        v = np.array([float(r[pname]) for r in pts])
        orbit = [np.asarray(json.loads(r["orbit"]))[:, ci] for r in pts]
        stable = np.array([r["stable"] == "true" for r in pts])
        mod = np.array([float(r["max_modulus"]) for r in pts])
        k = min(len(o) for o in orbit)
        # each style's mask takes one neighbour more, so the curve has no gap where stability changes
        grow = np.convolve(~stable, [1, 1, 1], "same") > 0
        for j in range(k):
            y = np.array([o[j] for o in orbit])
            for mask, ls in ((stable, "-"), (grow, ":")):
                a1.plot(v, np.where(mask, y, np.nan), ls, color=col, lw=1.6,
                        label=(f"period {pts[0]['period']}" + ("" if ls == "-" else ", unstable"))
                        if j == 0 and mask.any() else None)
        a2.plot(v, mod, "-", color=col, lw=1.4)
        for r in ok:
            if int(r["branch"]) == b and r["row"] in _MARKERS:
                o = np.asarray(json.loads(r["orbit"]))[:, ci]
                a1.plot([float(r[pname])] * len(o), o, _MARKERS[r["row"]], color="k", ms=5)
                a2.axvline(float(r[pname]), color="0.6", lw=0.8)
    kinds = {r["row"] for r in ok}
    if "flip" in kinds:
        a1.plot([], [], "o", color="k", ms=5, label="period doubling (flip, μ = −1)")
    if "fold" in kinds:
        a1.plot([], [], "^", color="k", ms=5, label="fold (μ = +1)")
    if "torus" in kinds:
        a1.plot([], [], "s", color="k", ms=5, label="torus (Neimark–Sacker, |μ| = 1, μ complex)")
    branch_axes(a1, a2, coord, pname)
    a1.set_title(title or "Continuation: branches of gaits, stability and bifurcations")
    return _save(fig, path)


BASIN_COLOURS = ("#2a9d8f", "#e76f51", "#e9c46a", "#6c757d")


def plot_basin(result: Any, path: str | os.PathLike, *, title: str | None = None) -> Path:
    """Basin map: categorical colours per outcome, legend, fixed point marked with a star."""
    plt = _plt()
    from matplotlib.colors import BoundaryNorm, ListedColormap
    from matplotlib.patches import Patch

    a, b = result.names
    labels = list(result.labels)
    cmap = ListedColormap(list(BASIN_COLOURS[: len(labels)])).with_extremes(under="white")  # white: not computed
    norm = BoundaryNorm(np.arange(-0.5, len(labels) + 0.5), cmap.N)
    fig, ax = plt.subplots(figsize=(6.5, 5))
    av, bv = result.a_values, result.b_values
    ext = [bv[0], bv[-1], av[0], av[-1]]
    ax.imshow(np.ma.masked_less(result.outcome, 0), origin="lower", aspect="auto", extent=ext, cmap=cmap,
              norm=norm, interpolation="nearest")
    names = list(getattr(result, "state_names", []) or [])
    fp = result.fixed_point
    if names and a in names and b in names:
        ax.plot(fp[names.index(b)], fp[names.index(a)], "*", color="k", ms=12, label="fixed point")
    counts = result.counts()
    handles = [Patch(color=cmap(c), label=f"{lab} ({counts[lab]})") for c, lab in enumerate(labels)]
    ax.legend(handles=handles, loc="upper right", fontsize=8, framealpha=0.9)
    ax.set_xlabel(f"initial post-impact {_label(b)}")
    ax.set_ylabel(f"initial post-impact {_label(a)}")
    ax.set_title(title or "Basin of attraction of the period-1 gait")
    return _save(fig, path)


def plot_poincare(iterates: np.ndarray, path: str | os.PathLike, *, state_names: list[str] | None = None,
                  coordinates: tuple[int, int] = (0, 2), title: str | None = None) -> Path:
    """Poincaré-map iterates: left, ``x_{k+1}`` vs ``x_k`` of the first chosen coordinate with the
    diagonal (fixed points lie on it); right, the iterates in the plane of two coordinates,
    coloured by step number."""
    plt = _plt()
    X = np.asarray(iterates, float)
    names = state_names or [f"x{i}" for i in range(X.shape[1])]
    c0, c1 = coordinates
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(10, 4.5))
    u = X[:, c0]
    a1.plot(u[:-1], u[1:], ".", ms=3, color="k")
    lo, hi = (float(np.min(u)), float(np.max(u))) if u.size else (0.0, 1.0)
    a1.plot([lo, hi], [lo, hi], "--", color="0.5", lw=1, label="x_{k+1} = x_k")
    a1.set_xlabel(f"{_label(names[c0])} at footfall k")
    a1.set_ylabel(f"{_label(names[c0])} at footfall k+1")
    a1.legend(fontsize=8)
    a1.grid(alpha=0.3)
    sc = a2.scatter(X[:, c0], X[:, c1], c=np.arange(len(X)), s=6, cmap="plasma")
    fig.colorbar(sc, ax=a2, label="footfall k (1)")
    a2.set_xlabel(_label(names[c0]))
    a2.set_ylabel(_label(names[c1]))
    a2.grid(alpha=0.3)
    fig.suptitle(title or "Poincaré-map iterates (post-impact states)")
    return _save(fig, path)


__all__ = ["plot_basin", "plot_bifurcation", "plot_branch", "plot_continuation", "plot_parameter_map", "plot_poincare"]
