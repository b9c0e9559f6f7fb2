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
That chain integrates the fall, a jump in the drawn slope, with Gauss nodes: it converges slowly.

The converged oracle is :func:`energy_mfpt`. The state (w, gamma_{n-1}) enters the map only
through the energy e = w^2 + 2 (g/l) cos(gamma_{n-1} - alpha) (the hub's energy per m l^2/2 with
its height counted from the stance foot): the wheel gets over the top iff e > 2 g/l, and

    e' = c e + phi(gamma_n),   c = cos^2(2 alpha),   phi(g) = 2 (g/l) (cos(g - alpha) - c cos(g + alpha)),

a scalar chain (phi is increasing for |gamma| < 0.8, where the normal laws here live). With e on a
fine grid of cells, the probability of each next cell, and of the fall e' <= 2 g/l, is a
difference of the normal CDF at phi^{-1} of the cell's ends: the fall's jump is integrated
exactly, and the mean steps t solve a dense (I - Q) t = 1 + (fall) with every attempted step
counted, the falling one too.
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


def _phi(g: np.ndarray) -> np.ndarray:
    c = math.cos(2 * ALPHA) ** 2
    return 2 * G / L * (np.cos(g - ALPHA) - c * np.cos(g + ALPHA))


def _phi_inverse(y: np.ndarray, lo: float = -0.8, hi: float = 0.8) -> np.ndarray:
    """gamma with phi(gamma) = y, clipped to [lo, hi] (phi increases there), by bisection."""
    a, b = np.full(y.shape, lo), np.full(y.shape, hi)
    for _ in range(60):
        m = 0.5 * (a + b)
        below = _phi(m) < y
        a, b = np.where(below, m, a), np.where(below, b, m)
    return 0.5 * (a + b)


def energy_mfpt(mean: float, sd: float, cells: int = 2000) -> float:
    """Mean steps until a fall from the fixed point of the mean slope, the falling step counted
    (the scalar energy chain of the module docstring, ``cells`` cells of e)."""
    from scipy.special import ndtr

    c = math.cos(2 * ALPHA) ** 2
    ef = 2 * G / L
    # e beyond the stationary level of the steepest slope the law draws (10 sd) is never reached
    emax = max(float(_phi(np.array(mean + 10 * sd))) / (1 - c), ef) * 1.02
    edges = np.linspace(ef, emax, cells + 1)
    mid = 0.5 * (edges[1:] + edges[:-1])
    # P(e' <= edge | e = mid): the CDF of gamma at phi^{-1}(edge - c mid)
    cdf = ndtr((_phi_inverse(edges[None, :] - c * mid[:, None]) - mean) / sd)
    cdf[:, -1] = 1.0  # images beyond emax (none of weight) kept in the last cell
    Q = np.diff(cdf, axis=1)
    fall = cdf[:, 0]
    # t = 1 + fall * 1 + Q t: the next step is counted if it falls, and from a cell if it walks
    t = np.linalg.solve(np.eye(cells) - Q, 1 + fall)
    e0 = fixed_point(mean) ** 2 + 2 * G / L * math.cos(mean - ALPHA)
    return float(np.interp(e0, mid, t))


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
        print(sd, energy_mfpt(0.08, sd, 1000), energy_mfpt(0.08, sd), monte_carlo_mfpt(0.08, sd, 200_000))
