"""The picture of a period-doubling cascade (:func:`amble.period_doublings`): every branch's
orbit against the parameter, stable parts solid and unstable parts dotted, the flips marked, and
below it the largest multiplier modulus of each branch, so the cascade's geometric shrinking is
visible at a glance.

Units: the parameter and the coordinate in their own units (angles rad, speeds rad/s).
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from .sweep_plots import _plt, _save, branch_axes

if TYPE_CHECKING:
    from ..analysis.doublings import Cascade


def plot_cascade(cascade: Cascade, path: str | os.PathLike, *, coordinate: str | None = None,
                 title: str | None = None) -> Path:
    """Write the cascade's diagram to ``path`` (.png, .svg or .pdf) and return the path.

    ``coordinate``: the post-impact state coordinate drawn (default the first one that varies
    along the period-1 branch). A period-``k`` branch draws ``k`` curves, one per step of its orbit.
    """
    plt = _plt()
    branches = [b for b in cascade.branches if b.points]
    names = list(branches[0].state_names) if branches else []
    if coordinate is not None and coordinate not in names:
        from .errors import VizError

        raise VizError(f"coordinate {coordinate!r} is not one of {', '.join(names)}")
    if coordinate is None and branches:
        spread = np.ptp(np.array([p.state for p in branches[0].points]), axis=0)
        coordinate = names[int(np.argmax(spread))] if spread.size else None
    ci = names.index(coordinate) if coordinate in names else 0
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(7, 6.5), sharex=True, gridspec_kw={"height_ratios": [2, 1]})
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for n, br in enumerate(branches):
        col = colours[n % len(colours)]
        pts = sorted(br.points, key=lambda p: p.value)
        v = np.array([p.value for p in pts])
        stable = np.array([p.stable for p in pts])
        # each style's mask takes one neighbour more, so the curve has no gap where stability changes
        grow = np.convolve(~stable, [1, 1, 1], "same") > 0
        for j in range(br.period):
            y = np.array([p.orbit[j % len(p.orbit), ci] for p in pts])
            for mask, ls in ((stable, "-"), (grow, ":")):
                a1.plot(v, np.where(mask, y, np.nan), ls, color=col, lw=1.4,
                        label=(f"period {br.period}" + ("" if ls == "-" else ", unstable"))
                        if j == 0 and mask.any() else None)
        a2.plot(v, [p.max_modulus for p in pts], "-", color=col, lw=1.3)
    for f in cascade.flips:
        o = np.asarray(f.point.orbit)[:, ci]
        a1.plot([f.value] * len(o), o, "o", color="k", ms=4)
        a2.axvline(f.value, color="0.6", lw=0.8)
    if cascade.flips:
        a1.plot([], [], "o", color="k", ms=4, label="period doubling (μ = −1)")
    branch_axes(a1, a2, coordinate, cascade.param)
    a1.set_title(title or "Period-doubling cascade")
    return _save(fig, path)


__all__ = ["plot_cascade"]
