"""The terrain's law on the nodes of a Markov chain (:func:`amble.analysis.markov.markov_mfpt`):
equally likely intervals, each represented by the law's conditional mean on it, and, with one
drawn parameter, each node's weight cut where the outcome of a step (walking on or falling)
changes between the nodes and beyond the outer ones."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from .markov_mesh import _Stepper
from .mfpt import Terrain


def quadrature(terrain: Terrain, nodes: int) -> tuple[dict[str, np.ndarray], np.ndarray]:
    """Nodes and weights (summing to 1) of the terrain's law, ``nodes`` per drawn parameter: the
    conditional means of ``nodes`` equally likely intervals (a tensor product for several).

    Each node is the mean of the law on its own interval, so the discrete law has the terrain's
    mean and loses only the spread within each interval; the midpoints in probability lose more
    of the tails (their variance is smaller), which makes a walker look more robust than it is."""
    axes = [np.full(nodes, float(a)) if _fixed(kind, a, b) else _interval_means(kind, a, b, nodes)
            for kind, a, b in terrain.draws.values()]
    grids = np.meshgrid(*axes, indexing="ij")
    return {n: g.ravel() for n, g in zip(terrain.draws, grids)}, np.full(grids[0].size, 1.0 / grids[0].size)


def _interval_means(kind: str, a: float, b: float, nodes: int) -> np.ndarray:
    """The law's mean on each of its ``nodes`` equally likely intervals."""
    if kind == "uniform":
        return a + (b - a) * (np.arange(nodes) + 0.5) / nodes
    from scipy.stats import norm

    # E[Z | u < Z < v] = (φ(u) − φ(v)) / (Φ(v) − Φ(u)) for a standard normal Z
    edges = norm.ppf(np.arange(nodes + 1) / nodes)
    return a + b * (norm.pdf(edges[:-1]) - norm.pdf(edges[1:])) * nodes


def _fixed(kind: str, a: float, b: float) -> bool:
    """A law of one value (no spread): its nodes are that value, and no fall is located between them."""
    return b == 0 if kind == "normal" else a == b


def _law(kind: str, a: float, b: float) -> Any:
    from scipy.stats import norm, uniform

    return norm(a, b) if kind == "normal" else uniform(a, b - a)


#: the probability beyond the tail probes of :func:`_edges`: a fall beyond them is not looked for
TAIL = 1e-7


def _edges(step: _Stepper, law: Any, X: np.ndarray, ok: np.ndarray,
           bisections: int) -> tuple[np.ndarray, np.ndarray]:
    """Node weights of one drawn parameter with the fall located between the nodes (rows: states),
    and the probability of falling beyond the outer nodes.

    A node owns its equally likely interval; where a node walks and its neighbour falls, the
    parameter where the outcome changes is found by bisection (``bisections`` walks) and the
    walking node owns the probability up to it, the falling one the rest: the fall, a jump in the
    drawn parameter, is integrated to the bisection's resolution instead of to a node's width.
    The outer nodes own the law's tails: each state is also walked at the quantiles :data:`TAIL`
    and ``1 − TAIL``, and where an outer node walks and its probe falls, the change between them
    is found by bisection in the logarithm of the probability beyond (half as many walks) and that
    probability is a fall (else a tail that falls beyond the outer node, up to ``1/nodes`` of the
    law, would count as walking)."""
    n, rows = step.nq, np.arange(len(X))
    g = step.values[:, 0]
    probe = law.ppf([TAIL, 1.0 - TAIL])
    walks_lo = step.walk(X, np.full((len(X), 1), probe[0]))[1]
    walks_hi = step.walk(X, np.full((len(X), 1), probe[1]))[1]
    # the edges of the nodes' intervals (the outer ones at ±∞), for every state: moved to the
    # outcome's change below
    cut = np.c_[np.full(len(X), -np.inf), np.tile(law.ppf(np.arange(1, n) / n), (len(X), 1)),
                np.full(len(X), np.inf)]
    i, j = np.nonzero(ok[:, :-1] != ok[:, 1:])
    if len(i):
        lo, hi = np.full(len(i), g[j]), np.full(len(i), g[j + 1])
        for _ in range(bisections):
            mid = 0.5 * (lo + hi)
            # the outcome of the left node: the change is to the right
            same = step.walk(X[i], mid[:, None])[1] == ok[i, j]
            lo, hi = np.where(same, mid, lo), np.where(same, hi, mid)
        cut[i, j + 1] = 0.5 * (lo + hi)
    # the tails: bisected in the logarithm of the probability beyond, where a few halvings place
    # the change to a fraction of that probability (most of it is far out, and tiny)
    for rows_t, node, col, upper in ((rows[ok[:, 0] & ~walks_lo], 0, 0, False),
                                     (rows[ok[:, -1] & ~walks_hi], n - 1, n, True)):
        if not len(rows_t):
            continue
        near = law.sf(g[node]) if upper else law.cdf(g[node])
        lo, hi = np.full(len(rows_t), math.log(near)), np.full(len(rows_t), math.log(TAIL))
        for _ in range(max(bisections // 2, 1) if bisections else 0):
            mid = 0.5 * (lo + hi)
            at = law.isf(np.exp(mid)) if upper else law.ppf(np.exp(mid))
            walks = step.walk(X[rows_t], at[:, None])[1]
            lo, hi = np.where(walks, mid, lo), np.where(walks, hi, mid)
        beyond = np.exp(0.5 * (lo + hi))
        cut[rows_t, col] = law.isf(beyond) if upper else law.ppf(beyond)
    cdf = law.cdf(cut)
    return np.diff(cdf, axis=1), cdf[:, 0] + 1.0 - cdf[:, -1]
