"""The metastable distribution of a walker on rough terrain, drawn on its Poincaré section.

The distribution is the one of :func:`amble.analysis.markov.markov_mfpt`: the probability, among
walkers that have not fallen after their transient, of each post-impact mesh state. The plot
shows the two coordinates of the section that vary most over the distribution (one dot per mesh
state, coloured by its probability), so a one-coordinate section (the rimless wheel's speed with
its angle set by the last ramp) reads as well as a four-coordinate one.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from .sweep_plots import _label, _plt, _save


def plot_metastable(result: Any, path: str | os.PathLike, *, state_names: Sequence[str] | None = None,
                    title: str | None = None) -> Path:
    """Mesh states coloured by their metastable probability, on the two coordinates of widest spread."""
    plt = _plt()
    X, v = np.asarray(result.mesh, float), np.asarray(result.metastable, float)
    names = list(state_names or [f"x{i}" for i in range(X.shape[1])])
    mean = v @ X
    spread = np.sqrt(v @ (X - mean) ** 2) / np.maximum(np.abs(X).max(axis=0), 1e-300)
    i, j = sorted(np.argsort(-spread)[:2]) if X.shape[1] > 1 else (0, 0)
    order = np.argsort(v)  # the likeliest drawn last, on top
    fig, ax = plt.subplots(figsize=(6.5, 4.5))
    sc = ax.scatter(X[order, i], X[order, j], c=v[order], s=6, cmap="viridis", lw=0)
    fig.colorbar(sc, ax=ax, label="metastable probability")
    ax.set_xlabel(f"post-impact {_label(names[i])}")
    ax.set_ylabel(f"post-impact {_label(names[j])}")
    ax.set_title(title or f"Metastable distribution (MFPT {result.mfpt:.4g} steps, {len(v)} mesh states)")
    ax.grid(alpha=0.3)
    return _save(fig, path)



def plot_mfpt_against(values: Sequence[float], results: Sequence[Any], path: str | os.PathLike, *,
                      label: str = "parameter", title: str | None = None) -> Path:
    """MFPT (steps, log scale) against a parameter: one result of :func:`amble.mfpt` or
    :func:`amble.markov_mfpt` per value, drawn with its ``ci_low``–``ci_high`` as an error bar
    (a confidence interval for Monte Carlo, the spread of the two finest meshes for the chain).
    A walker that never fell (MFPT ∞) is left out."""
    plt = _plt()
    x, y, lo, hi = [], [], [], []
    for v, r in zip(values, results):
        if np.isfinite(r.mfpt):
            x.append(float(v))
            y.append(r.mfpt)
            lo.append(r.mfpt - r.ci_low)
            hi.append((r.ci_high - r.mfpt) if np.isfinite(r.ci_high) else 0.0)
    fig, ax = plt.subplots(figsize=(6.5, 4.5))
    ax.errorbar(x, y, yerr=[lo, hi], fmt="o-", ms=4, capsize=3)
    ax.set_yscale("log")
    ax.set_xlabel(_label(label))
    ax.set_ylabel("mean first-passage time (steps)")
    ax.set_title(title or "Mean first-passage time to a fall")
    ax.grid(alpha=0.3, which="both")
    return _save(fig, path)


__all__ = ["plot_metastable", "plot_mfpt_against"]
