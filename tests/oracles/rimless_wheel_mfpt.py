"""The rimless wheel on stochastic slopes, from its closed-form step map: a Markov chain on a
fine grid and a Monte Carlo of the map. Nothing here comes from amble.

Wheel of spokes of length l, half-angle alpha between spokes, hub mass only. A step on a ramp of
angle gamma_n starts just after the impact that ended the step before, on the ramp gamma_{n-1}:
the stance spoke is at theta+ = gamma_{n-1} - alpha from the vertical with speed w. It must carry
the hub over the top, w^2 > 2 (g/l)(1 - cos theta+) (else the wheel rocks back: a fall); it then
falls to the next footfall at theta = gamma_n + alpha,

    w-^2 = w^2 + 2 (g/l) (cos theta+ - cos(gamma_n + alpha)),

and the plastic impact leaves w' = cos(2 alpha) w- (Coleman, Chatterjee & Ruina 1997; Byl &
Tedrake 2009). The state after a step is (w', gamma_n).

The chain: w on a grid of nw nodes, gamma on nq Gauss–Hermite nodes of the slope's normal law
(the drawn slope becomes the next state's previous slope, so the chain's slopes are those
nodes); an image w' between two nodes is split between them linearly. Q is the chain among the
walking states; the mean number of steps until a fall from a state is (I - Q)^{-1} 1 there.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.sparse import coo_matrix, identity
from scipy.sparse.linalg import spsolve

G, L, ALPHA = 9.81, 1.0, math.pi / 8


def step(w: np.ndarray, prev: np.ndarray, gamma: np.ndarray) -> np.ndarray:
    """Post-impact speed after a step on ``gamma`` from speed ``w`` after a step on ``prev``; NaN: a fall."""
    top = 2 * G / L * (1 - np.cos(prev - ALPHA))
    pre2 = w**2 + 2 * G / L * (np.cos(prev - ALPHA) - np.cos(gamma + ALPHA))
    return np.where((w > 0) & (w**2 > top), math.cos(2 * ALPHA) * np.sqrt(np.maximum(pre2, 0.0)), np.nan)


def fixed_point(gamma: float) -> float:
    """Tedrake's closed form of the rolling fixed point on a constant slope."""
    return 1 / math.tan(2 * ALPHA) * math.sqrt(4 * G / L * math.sin(ALPHA) * math.sin(gamma))


def markov_mfpt(mean: float, sd: float, nw: int = 1500, nq: int = 24, wmax: float = 3.0) -> float:
    """Mean steps until a fall from the fixed point of the mean slope (after a step on the mean slope)."""
    x, wq = np.polynomial.hermite_e.hermegauss(nq)
    gam, pg = mean + sd * x, wq / wq.sum()
    grid = np.linspace(0.0, wmax, nw)
    W, Prev, Next = np.meshgrid(grid, np.arange(nq), np.arange(nq), indexing="ij")  # (w, prev, next)
    w2 = step(W, gam[Prev], gam[Next])
    prob = pg[Next]
    ok = np.isfinite(w2) & (w2 < wmax)
    pos = np.where(ok, w2, 0.0) / (wmax / (nw - 1))
    lo = np.minimum(np.floor(pos).astype(int), nw - 2)
    f = pos - lo
    src = (W / (wmax / (nw - 1))).round().astype(int) * nq + Prev
    rows = np.concatenate([src[ok], src[ok]])
    cols = np.concatenate([(lo * nq + Next)[ok], ((lo + 1) * nq + Next)[ok]])
    vals = np.concatenate([(prob * (1 - f))[ok], (prob * f)[ok]])
    n = nw * nq
    Q = coo_matrix((vals, (rows, cols)), shape=(n, n)).tocsr()
    t = spsolve((identity(n, format="csr") - Q).tocsc(), np.ones(n))
    # the start: the fixed point of the mean slope, after a step on the mean slope (interpolated)
    w0 = fixed_point(mean)
    tw = t.reshape(nw, nq)
    at_prev = np.array([np.interp(w0, grid, tw[:, j]) for j in range(nq)])
    # the previous slope is the mean, between nodes: interpolate in gamma too
    return float(np.interp(mean, gam, at_prev))


def monte_carlo_mfpt(mean: float, sd: float, runs: int, seed: int = 0, max_steps: int = 100_000) -> float:
    """Mean steps until a fall (the falling step counted) of ``runs`` walks of the map."""
    rng = np.random.default_rng(seed)
    w = np.full(runs, fixed_point(mean))
    prev = np.full(runs, mean)
    steps = np.zeros(runs)
    alive = np.ones(runs, bool)
    for _ in range(max_steps):
        if not alive.any():
            break
        g = rng.normal(mean, sd, alive.sum())
        nw = step(w[alive], prev[alive], g)
        idx = np.flatnonzero(alive)
        steps[idx] += 1
        w[idx], prev[idx] = nw, g
        alive[idx[~np.isfinite(nw)]] = False
    return float(steps.mean())


if __name__ == "__main__":
    for sd in (0.02, 0.03, 0.04):
        print(sd, markov_mfpt(0.08, sd), monte_carlo_mfpt(0.08, sd, 200_000))
