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


__all__ = ["plot_metastable"]
