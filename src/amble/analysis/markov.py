"""The mean first-passage time from a Markov chain on a mesh of the section (Byl & Tedrake 2009).

The terrain's law is replaced by a quadrature (the midpoints in probability of ``nodes`` equally
likely intervals; a tensor product for several drawn parameters), and the set of
post-impact states by a finite **mesh** grown from the gait: starting from the gait's post-impact
state at the terrain's mean, every new mesh state is walked one step on every quadrature node (all
of them in one compiled call per wave, :func:`amble.simulation.engine.walk_many`), and an image
farther than ``spacing`` from every mesh state (in the scaled distance below) becomes a new mesh
state, until no image is new or ``max_states`` is reached (Byl & Tedrake's sampled mesh: only
states the walker can reach are meshed, whatever the dimension of the section).

Distances are measured in each state coordinate divided by its spread over the images of the
gait (the standard deviation of two steps' images from the gait), so ``spacing`` is relative.
An image is assigned to the mesh by linear (barycentric) interpolation over a Delaunay
triangulation of the mesh when the section has at most :data:`LINEAR_MAX_DIM` coordinates that
vary, and to its nearest mesh state otherwise (or when it lies outside the triangulation).

**The fall.** Whether a step ends in a fall jumps with the drawn parameter, which no quadrature
integrates better than to a node's width (a 2 % error at 16 nodes on the rimless wheel). With one
drawn parameter, the parameter where the outcome changes between two neighbouring nodes is found
by bisection for every mesh state, and each node's weight is the probability of the part of its
interval on its own side of the change (:func:`_edges`).

The chain's states are the mesh states and an absorbing *fallen* state; ``Q`` is the chain among
the mesh states. The expected number of steps until a fall (the falling step counted, as the
Monte Carlo estimate counts it) solves ``(I − Q) m = 1``; ``mfpt`` is ``m`` at the gait's state.
Byl & Tedrake's estimate from the largest eigenvalue λ₂ of ``Q`` (the second of the whole chain,
whose first is the fallen state's 1), ``1 / (1 − λ₂)``, is the MFPT from the metastable
(quasi-stationary) distribution — the left eigenvector of ``Q`` for λ₂ — which a walker reaches
after its transient; it is reported as ``mfpt_eigen``, the distribution as ``metastable``.

**Convergence.** The chain is built at ``levels`` spacings, each half the one before; the
result carries the MFPT at every level, and its ``ci_low``/``ci_high`` are the two finest
levels' values — a measure of the discretisation's error, not a confidence interval. A level's
``complete`` is false when its mesh was cut at ``max_states`` before every reachable state was
meshed: images beyond it go to their nearest mesh state, and its value is not to be trusted.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..errors import ParameterError
from ..simulation.engine import CODE, Options, walk_many
from .mfpt import Terrain, terrain_start

#: sections with at most this many varying coordinates are interpolated linearly (Delaunay)
LINEAR_MAX_DIM = 3


def quadrature(terrain: Terrain, nodes: int) -> tuple[dict[str, np.ndarray], np.ndarray]:
    """Nodes and weights (summing to 1) of the terrain's law, ``nodes`` per drawn parameter: the
    midpoints (in probability) of ``nodes`` equally likely intervals, a tensor product for several."""
    u = (np.arange(nodes) + 0.5) / nodes
    axes = [np.full(nodes, float(a)) if _fixed(kind, a, b) else _law(kind, a, b).ppf(u)
            for kind, a, b in terrain.draws.values()]
    grids = np.meshgrid(*axes, indexing="ij")
    return {n: g.ravel() for n, g in zip(terrain.draws, grids)}, np.full(grids[0].size, 1.0 / grids[0].size)


def _fixed(kind: str, a: float, b: float) -> bool:
    """A law of one value (no spread): its nodes are that value, and no fall is located between them."""
    return b == 0 if kind == "normal" else a == b


def _law(kind: str, a: float, b: float) -> Any:
    from scipy.stats import norm, uniform

    return norm(a, b) if kind == "normal" else uniform(a, b - a)


def _finite(v: Any) -> Any:
    """JSON has no infinity: a walker that never falls has MFPT ``null``."""
    return None if isinstance(v, float) and not math.isfinite(v) else v


@dataclass
class MarkovPassage:
    """The MFPT (steps) from the chain at the finest spacing, with the coarser levels' values."""

    mfpt: float
    ci_low: float
    ci_high: float
    mfpt_eigen: float
    lambda2: float
    states: int
    spacing: float
    nodes: int
    levels: list[dict[str, float]]
    method: str
    terrain: dict[str, Any]
    #: mesh states (rows) and their metastable probabilities (not in the JSON)
    mesh: np.ndarray = field(repr=False, default_factory=lambda: np.empty((0, 0)))
    metastable: np.ndarray = field(repr=False, default_factory=lambda: np.empty(0))

    def to_json(self) -> dict[str, Any]:
        out = {k: getattr(self, k) for k in ("mfpt", "ci_low", "ci_high", "mfpt_eigen", "lambda2", "states",
                                               "spacing", "nodes", "levels", "method", "terrain")}
        out = {k: _finite(v) for k, v in out.items()}
        out["levels"] = [{k: _finite(v) for k, v in lv.items()} for lv in self.levels]
        return {**out, "metastable": self.metastable_summary()}

    def metastable_summary(self) -> dict[str, Any]:
        """Mean and standard deviation of each state coordinate under the metastable distribution,
        and the likeliest mesh state with its probability."""
        v, X = self.metastable, self.mesh
        if v.size == 0:
            return {}
        mean = v @ X
        top = int(np.argmax(v))
        return {"mean": mean.tolist(), "sd": np.sqrt(np.maximum(v @ (X - mean) ** 2, 0.0)).tolist(),
                "mode": X[top].tolist(), "mode_probability": float(v[top])}


@dataclass
class _Chain:
    mesh: np.ndarray
    Q: Any  # scipy.sparse csr
    fall: np.ndarray


class _Stepper:
    """One step of many states on many terrain nodes, in one compiled call."""

    def __init__(self, k: Any, p0: np.ndarray, cols: list[int], draws: dict[str, np.ndarray], mode: int,
                 xref: np.ndarray, opts: Options, threads: int) -> None:
        self.k, self.p0, self.cols, self.mode = k, p0, cols, mode
        self.xref, self.opts, self.threads = xref, opts, threads
        self.values = np.column_stack(list(draws.values()))
        self.nq = len(self.values)

    def walk(self, X: np.ndarray, values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """One step of each row of ``X`` on its own row of drawn values: images and the mask of
        steps that ended in a footfall."""
        P = np.tile(self.p0, (len(X), 1))
        P[:, self.cols] = values
        out = walk_many(self.k, P, self.mode, X, self.xref, steps=1, check_every=1, tol=-1.0, opts=self.opts,
                        threads=self.threads)
        return out["x"][:, : X.shape[1]], out["code"] == CODE["STEPS_DONE"]

    def images(self, X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Images of every state on every node (len(X) · nq rows, state-major) and their mask."""
        return self.walk(np.repeat(X, self.nq, axis=0), np.tile(self.values, (len(X), 1)))


def _edges(step: _Stepper, law: Any, X: np.ndarray, ok: np.ndarray, bisections: int) -> np.ndarray:
    """Node weights of one drawn parameter with the fall located between the nodes (rows: states).

    A node owns its equally likely interval; where a node walks and its neighbour falls, the
    parameter where the outcome changes is found by bisection (``bisections`` walks) and the
    walking node owns the probability up to it, the falling one the rest: the fall, a jump in the
    drawn parameter, is integrated to the bisection's resolution instead of to a node's width."""
    n = step.nq
    g = step.values[:, 0]
    # the edges of the nodes' intervals, for every state: moved to the outcome's change below
    cut = np.tile(law.ppf(np.arange(1, n) / n), (len(X), 1))
    i, j = np.nonzero(ok[:, :-1] != ok[:, 1:])
    if len(i):
        lo, hi = np.full(len(i), g[j]), np.full(len(i), g[j + 1])
        for _ in range(bisections):
            mid = 0.5 * (lo + hi)
            walks = step.walk(X[i], mid[:, None])[1]
            same = walks == ok[i, j]  # the outcome of the left node: the change is to the right
            lo, hi = np.where(same, mid, lo), np.where(same, hi, mid)
        cut[i, j] = 0.5 * (lo + hi)
    cdf = np.c_[np.zeros(len(X)), law.cdf(cut), np.ones(len(X))]
    return np.diff(cdf, axis=1)


def _grow(step: _Stepper, x0: np.ndarray, scale: np.ndarray, spacing: float,
          max_states: int) -> tuple[np.ndarray, bool]:
    """The mesh of reachable states: waves of new images farther than ``spacing`` from the mesh;
    and whether it is complete (no new image left when it stopped, not cut at ``max_states``)."""
    from scipy.spatial import cKDTree

    mesh = [x0[None, :]]
    frontier = x0[None, :]
    count = 1
    while len(frontier) and count < max_states:
        Y, ok = step.images(frontier)
        Y = Y[ok]
        tree = cKDTree(np.vstack(mesh) / scale)
        far = tree.query(Y / scale, distance_upper_bound=spacing)[0] > spacing
        new: list[np.ndarray] = []
        if far.any():
            # thin the new images among themselves: one per cell of a grid of the spacing
            cand = Y[far]
            keys = np.floor(cand / (scale * spacing)).astype(np.int64)
            taken = np.sort(np.unique(keys, axis=0, return_index=True)[1])
            new = [cand[taken][: max_states - count]]
        frontier = np.vstack(new) if new else np.empty((0, x0.size))
        count += len(frontier)
        mesh.append(frontier)
    return np.vstack(mesh), len(frontier) == 0


def _assign(mesh: np.ndarray, Y: np.ndarray, scale: np.ndarray, varying: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Mesh indices (rows × m) and weights of each image: barycentric in a Delaunay simplex when
    the section is low-dimensional, else (and outside the triangulation) the nearest state."""
    from scipy.spatial import cKDTree

    Z, Yz = mesh[:, varying] / scale[varying], Y[:, varying] / scale[varying]
    near = cKDTree(Z).query(Yz)[1]
    d = int(varying.sum())
    idx = np.repeat(near[:, None], d + 1, axis=1)
    wts = np.zeros((len(Y), d + 1))
    wts[:, 0] = 1.0
    if 1 <= d <= LINEAR_MAX_DIM and len(mesh) > d + 1:
        from scipy.spatial import Delaunay, QhullError

        try:
            tri = Delaunay(Z)
        except QhullError:  # a degenerate mesh (all states on a line, a plane): nearest only
            return idx, wts
        s = tri.find_simplex(Yz)
        inside = s >= 0
        T = tri.transform[s[inside]]
        b = np.einsum("ijk,ik->ij", T[:, :d, :], Yz[inside] - T[:, d, :])
        idx[inside] = tri.simplices[s[inside]]
        wts[inside] = np.c_[b, 1 - b.sum(axis=1)]
    return idx, wts


def _chain(step: _Stepper, mesh: np.ndarray, weights: np.ndarray, scale: np.ndarray, varying: np.ndarray,
           law: Any, bisections: int) -> _Chain:
    from scipy.sparse import coo_matrix

    Y, ok = step.images(mesh)
    n, nq = len(mesh), step.nq
    src = np.repeat(np.arange(n), nq)
    if law is not None:
        w = _edges(step, law, mesh, ok.reshape(n, nq), bisections).ravel()
    else:
        w = np.tile(weights, n)
    idx, wts = _assign(mesh, Y[ok], scale, varying)
    rows = np.repeat(src[ok], idx.shape[1])
    vals = (wts * w[ok][:, None]).ravel()
    Q = coo_matrix((vals, (rows, idx.ravel())), shape=(n, n)).tocsr()
    fall = np.bincount(src[~ok], weights=w[~ok], minlength=n)
    return _Chain(mesh, Q, fall)


def _falling(c: _Chain) -> np.ndarray:
    """The states that fall with probability 1 (a finite MFPT): those that reach a fall and
    cannot reach a state that never falls (on a mesh too coarse to see any fall, for one)."""
    from scipy.sparse.csgraph import breadth_first_order

    def reach(targets: np.ndarray, G: Any) -> np.ndarray:
        # the states from which one of ``targets`` is reached: a search from a new node joined to them
        n = G.shape[0]
        from scipy.sparse import bmat, csr_matrix

        link = csr_matrix((np.ones(int(targets.sum())), (np.zeros(int(targets.sum()), int),
                                                          np.flatnonzero(targets))), shape=(1, n))
        H = bmat([[csr_matrix((1, 1)), link], [csr_matrix((n, 1)), G]], format="csr")
        order = breadth_first_order(H, 0, directed=True, return_predecessors=False)
        out = np.zeros(n, bool)
        out[order[order > 0] - 1] = True
        return out

    back = (c.Q.T > 0).astype(float).tocsr()  # edges reversed: a search finds predecessors
    never = ~reach(c.fall > 0, back)
    return ~reach(never, back) if never.any() else np.ones(len(never), bool)


def _solve(c: _Chain) -> tuple[float, float, np.ndarray]:
    """MFPT from state 0, λ₂ (the largest eigenvalue of Q) and its left eigenvector, normalised."""
    from scipy.sparse import identity
    from scipy.sparse.linalg import eigs, spsolve

    n = c.Q.shape[0]
    finite = _falling(c)
    m = np.full(n, math.inf)
    if finite.any():
        Qf = c.Q[finite][:, finite]
        m[finite] = spsolve((identity(int(finite.sum()), format="csc") - Qf.tocsc()), np.ones(int(finite.sum())))
    if n > 2:
        vals, vecs = eigs(c.Q.T.tocsc(), k=1, which="LR", tol=1e-12, maxiter=20 * n)
        lam, v = float(vals[0].real), np.abs(vecs[:, 0].real)
    else:
        vals, vecs = np.linalg.eig(c.Q.T.toarray())
        j = int(np.argmax(vals.real))
        lam, v = float(vals[j].real), np.abs(vecs[:, j].real)
    return float(m[0]), lam, v / v.sum()


def markov_mfpt(system: Any, terrain: Terrain, *, spacing: float = 0.05, levels: int = 3, nodes: int = 32,
                max_states: int = 20_000, bisections: int = 12, params: Mapping[str, float] | None = None,
                start: Sequence[float] | None = None, threads: int = 1, opts: Options | None = None) -> MarkovPassage:
    """The mean first-passage time to a fall on ``terrain`` from a Markov chain on a mesh of the
    section (module docstring).

    ``spacing``: the finest mesh spacing, relative to the spread of the gait's images;
    ``levels``: chains built at ``spacing · 2^(levels−1)``, …, ``spacing`` (the convergence
    shown); ``nodes``: quadrature nodes per drawn parameter; ``max_states``: the mesh's cap;
    ``params``, ``start``, ``threads``, ``opts`` as for :func:`amble.analysis.mfpt.mfpt`."""
    for name, v, low in (("levels", levels, 1), ("nodes", nodes, 1), ("max_states", max_states, 2),
                         ("bisections", bisections, 0), ("threads", threads, 1)):
        if isinstance(v, bool) or not isinstance(v, int) or v < low:
            raise ParameterError(f"{name} must be an integer ≥ {low}, got {v!r}")
    if not (isinstance(spacing, (int, float)) and math.isfinite(spacing) and spacing > 0):
        raise ParameterError(f"spacing must be a number > 0, got {spacing!r}")
    k, names, p0, x0, mode = terrain_start(system, terrain, params, start)
    draws, weights = quadrature(terrain, nodes)
    one = next(iter(terrain.draws.values()))
    law = _law(*one) if len(terrain.draws) == 1 and not _fixed(*one) else None
    step = _Stepper(k, p0, [names.index(n) for n in terrain.draws], draws, mode, x0, opts or Options(), threads)
    # the scale of each coordinate: the spread of two steps' images of the gait
    Y1, ok1 = step.images(x0[None, :])
    Y2, ok2 = step.images(Y1[ok1]) if ok1.any() else (Y1[:0], ok1[:0])
    spread = np.vstack([Y1[ok1], Y2[ok2]]).std(axis=0) if ok1.any() else np.zeros_like(x0)
    ref = max(float(np.max(spread)), 1e-12)
    varying = spread > 1e-9 * ref
    if not varying.any():  # every image is the gait: distances in every coordinate
        varying[:] = True
    scale = np.where(varying, spread, ref)
    out, chain = [], None
    for lev in range(levels - 1, -1, -1):
        h = spacing * 2.0**lev
        mesh, complete = _grow(step, x0, scale, h, max_states)
        chain = _chain(step, mesh, weights, scale, varying, law, bisections)
        m, lam, v = _solve(chain)
        out.append({"spacing": h, "states": len(mesh), "complete": complete, "mfpt": m,
                    "mfpt_eigen": 1.0 / (1.0 - lam) if lam < 1 else math.inf, "metastable": v})
    fine = out[-1]
    other = out[-2]["mfpt"] if len(out) > 1 else fine["mfpt"]
    assert chain is not None
    return MarkovPassage(mfpt=fine["mfpt"], ci_low=min(fine["mfpt"], other), ci_high=max(fine["mfpt"], other),
                         mfpt_eigen=fine["mfpt_eigen"], lambda2=1.0 - 1.0 / fine["mfpt_eigen"],
                         states=fine["states"], spacing=spacing, nodes=nodes,
                         levels=[{k: v for k, v in o.items() if k != "metastable"} for o in out],
                         method="markov", terrain=terrain.to_json(), mesh=chain.mesh, metastable=fine["metastable"])


__all__ = ["LINEAR_MAX_DIM", "MarkovPassage", "markov_mfpt", "quadrature"]
