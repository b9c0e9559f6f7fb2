"""The mean first-passage time from a Markov chain on a mesh of the section (Byl & Tedrake 2009).

The terrain's law is replaced by a quadrature (``nodes`` equally likely intervals, each
represented by the law's conditional mean on it; a tensor product for several drawn parameters),
and the set of post-impact states by a finite **mesh** grown from the gait: starting from the
gait's post-impact state at the terrain's mean, every new mesh state is walked one step on every
quadrature node (all of them in one compiled call per wave,
:func:`amble.simulation.engine.walk_many`), and an image farther than ``spacing`` from every mesh
state (in the scaled distance below) becomes a new mesh state, until no image is new or
``max_states`` is reached (Byl & Tedrake's sampled mesh: only states the walker can reach are
meshed, whatever the dimension of the section).

**Where states are compared** (``mesh``). A post-impact state lies on the section of the step
that ended it, and when the drawn parameters enter that step's guard or reset (a footfall on a
ramp of angle γ: the legs' angles are tied by γ) each terrain node has a section of its own, of
one dimension less than the state. With ``mesh="section"`` (the default) the mesh is kept in
**slices**, one per node — the images of that node's steps — and states are compared, and images
interpolated, only within their slice, in the chart coordinates of the gait's section
(:func:`amble.analysis.section.chart`: derived from the model's guard and reset, nothing keyed on
a coordinate's name): the compass gait's four post-impact coordinates become three per slice,
and an image is interpolated exactly on the section it lies on. When the drawn parameters leave
the section where it is, or with ``mesh="state"``, every state coordinate that varies is used and
the mesh has one slice.

Distances are measured in each coordinate divided by its spread over the images of the gait (the
standard deviation of two steps' images from the gait), so ``spacing`` is relative. An image is
assigned to the mesh states of its slice by linear (barycentric) interpolation over a Delaunay
triangulation (between the two neighbours on a line) when the slice has at most
:data:`LINEAR_MAX_DIM` coordinates, and to its nearest mesh state otherwise (or when it lies
outside the triangulation).

**The fall.** Whether a step ends in a fall jumps with the drawn parameter, which no quadrature
integrates better than to a node's width (a 2 % error at 16 nodes on the rimless wheel). With one
drawn parameter, the parameter where the outcome changes between two neighbouring nodes is found
by bisection for every mesh state, and each node's weight is the probability of the part of its
interval on its own side of the change (:func:`_edges`); a fall in the law's tails beyond the
outer nodes is found the same way.

The chain's states are the mesh states and an absorbing *fallen* state; ``Q`` is the chain among
the mesh states. The expected number of steps until a fall (the falling step counted, as the
Monte Carlo estimate counts it) solves ``(I − Q) m = 1``; ``mfpt`` is ``m`` at the gait's state.
Byl & Tedrake's estimate from the largest eigenvalue λ₂ of ``Q`` (the second of the whole chain,
whose first is the fallen state's 1), ``1 / (1 − λ₂)``, is the MFPT from the metastable
(quasi-stationary) distribution — the left eigenvector of ``Q`` for λ₂ — which a walker reaches
after its transient; it is reported as ``mfpt_eigen``, the distribution as ``metastable``.

**Convergence.** The chain is built at ``levels`` spacings, each half the one before; the
result carries the MFPT at every level. When the last three levels' differences shrink without
changing sign, Richardson's extrapolation with the order they show gives ``extrapolated`` (the
limit of zero spacing) and ``order``. ``ci_low``/``ci_high`` span the two finest levels' values
and the extrapolated limit — the stated discretisation uncertainty, not a confidence interval. A
level's ``complete`` is false when its mesh was cut at ``max_states`` before every reachable
state was meshed: images beyond it go to their nearest mesh state, and its value is not to be
trusted (nor extrapolated from).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..errors import ParameterError, SimulationError
from ..simulation.engine import CODE, Options, walk_many
from .mfpt import Terrain, terrain_start, walk_options

#: how mesh states are compared: in the chart of each terrain node's section, or in every state coordinate
MESHES = ("section", "state")
#: sections with at most this many varying coordinates are interpolated linearly (Delaunay)
LINEAR_MAX_DIM = 3


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
    #: Richardson's limit of the last three levels and their order of convergence (None: not shown)
    extrapolated: float | None = None
    order: float | None = None
    #: mesh states (rows) and their metastable probabilities (not in the JSON)
    mesh: np.ndarray = field(repr=False, default_factory=lambda: np.empty((0, 0)))
    metastable: np.ndarray = field(repr=False, default_factory=lambda: np.empty(0))

    def to_json(self) -> dict[str, Any]:
        out = {k: getattr(self, k) for k in ("mfpt", "ci_low", "ci_high", "mfpt_eigen", "lambda2", "states",
                                               "spacing", "nodes", "levels", "method", "terrain", "extrapolated",
                                               "order")}
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


class _Chart:
    """Where mesh states are compared: their coordinates ``cols`` divided by ``scale``, within
    their slice. A *sliced* mesh keeps one slice per terrain node — the states that node's step
    ended on, which lie on that node's post-impact section — and ``cols`` are the section's chart
    coordinates; the first state (the gait at the terrain's mean) is a slice of its own."""

    #: distance put between slices in the comparison coordinates: far beyond any mesh spacing
    SEPARATION = 1e6

    def __init__(self, cols: np.ndarray, scale: np.ndarray, sliced: bool) -> None:
        self.cols, self.scale, self.sliced = cols, scale, sliced
        self.start = -1 if sliced else 0
        self.dim = len(cols)

    def coords(self, X: np.ndarray) -> np.ndarray:
        return X[:, self.cols] / self.scale

    def labels(self, n: int, nq: int) -> np.ndarray:
        """The slice of each of the ``n · nq`` images of :meth:`_Stepper.images` (state-major)."""
        return np.tile(np.arange(nq), n) if self.sliced else np.zeros(n * nq, int)

    def key(self, X: np.ndarray, lab: np.ndarray) -> np.ndarray:
        return np.c_[self.coords(X), self.SEPARATION * lab]


def _section_chart(system: Any, params: Mapping[str, float], cols: list[int], values: np.ndarray,
                   x0: np.ndarray) -> tuple[np.ndarray, bool]:
    """The chart coordinates of the gait's post-impact section and whether the section moves
    with the drawn parameters: whether the step guard or the reset at the gait's footfall changes
    when they take their extreme node values (a footfall on a ramp of another angle, say). Then the
    images of different nodes lie on different sections, each of the section's dimension."""
    from .poincare import ReturnMap
    from .section import Section

    rm = ReturnMap(system, params)
    try:
        sec = Section.of(rm, x0)
    except SimulationError:  # a start that falls on the mean terrain: no footfall to chart from
        return np.arange(x0.size), False
    g0, r0 = sec.guard(sec.pre), sec.reset(sec.pre)
    moved = False
    for row in (values.min(axis=0), values.max(axis=0)):
        p = rm.p.copy()
        p[cols] = row
        other = Section(rm.k, p, sec.tr, sec.t, sec.pre)
        moved |= not (np.isclose(other.guard(sec.pre), g0, rtol=0, atol=1e-12)
                      and np.allclose(other.reset(sec.pre), r0, rtol=0, atol=1e-12))
    return sec.coordinates(), moved


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


def _grow(step: _Stepper, x0: np.ndarray, chart: _Chart, spacing: float,
          max_states: int) -> tuple[np.ndarray, np.ndarray, bool]:
    """The mesh of reachable states and their slices: waves of new images farther than
    ``spacing`` from the mesh states of their own slice; and whether it is complete (no new image
    left when it stopped, not cut at ``max_states``)."""
    from scipy.spatial import cKDTree

    mesh, labs = [x0[None, :]], [np.array([chart.start])]
    frontier, flab = x0[None, :], labs[0]
    count = 1
    while len(frontier) and count < max_states:
        Y, ok = step.images(frontier)
        lab = chart.labels(len(frontier), step.nq)[ok]
        Y = Y[ok]
        tree = cKDTree(chart.key(np.vstack(mesh), np.concatenate(labs)))
        far = tree.query(chart.key(Y, lab), distance_upper_bound=spacing)[0] > spacing
        frontier, flab = Y[:0], lab[:0]
        if far.any():
            # thin the new images among themselves: one per cell of a grid of the spacing (per slice)
            cand, clab = Y[far], lab[far]
            keys = np.c_[np.floor(chart.coords(cand) / spacing).astype(np.int64), clab]
            taken = np.sort(np.unique(keys, axis=0, return_index=True)[1])[: max_states - count]
            frontier, flab = cand[taken], clab[taken]
        count += len(frontier)
        mesh.append(frontier)
        labs.append(flab)
    return np.vstack(mesh), np.concatenate(labs), len(frontier) == 0


def _assign(mesh: np.ndarray, mlab: np.ndarray, Y: np.ndarray, lab: np.ndarray,
            chart: _Chart) -> tuple[np.ndarray, np.ndarray]:
    """Mesh indices (rows × (d+1)) and weights of each image, among the mesh states of its own
    slice: barycentric in a Delaunay simplex of the slice (linear between neighbours when the
    chart has one coordinate) when the chart has at most :data:`LINEAR_MAX_DIM` coordinates;
    else, and outside the slice's triangulation, the nearest state."""
    from scipy.spatial import cKDTree

    d = chart.dim
    near = cKDTree(chart.key(mesh, mlab)).query(chart.key(Y, lab))[1]
    idx = np.repeat(near[:, None], d + 1, axis=1)
    wts = np.zeros((len(Y), d + 1))
    wts[:, 0] = 1.0
    if not 1 <= d <= LINEAR_MAX_DIM:
        return idx, wts
    Z, Yz = chart.coords(mesh), chart.coords(Y)
    for s in np.unique(lab):
        own = np.flatnonzero(mlab == s)
        rows = np.flatnonzero(lab == s)
        if len(own) <= d + 1:
            continue
        if d == 1:
            _linear(Z[own, 0], Yz[rows, 0], own, rows, idx, wts)
        else:
            _barycentric(Z[own], Yz[rows], own, rows, idx, wts)
    return idx, wts


def _linear(z: np.ndarray, y: np.ndarray, own: np.ndarray, rows: np.ndarray, idx: np.ndarray,
            wts: np.ndarray) -> None:
    """Linear interpolation between the two mesh states around each image on a line."""
    order = np.argsort(z)
    zs = z[order]
    i = np.searchsorted(zs, y)
    inside = (i > 0) & (i < len(zs))
    i = i[inside]
    t = (y[inside] - zs[i - 1]) / (zs[i] - zs[i - 1])
    r = rows[inside]
    idx[r, 0], idx[r, 1] = own[order[i - 1]], own[order[i]]
    wts[r, 0], wts[r, 1] = 1.0 - t, t


def _barycentric(Z: np.ndarray, Yz: np.ndarray, own: np.ndarray, rows: np.ndarray, idx: np.ndarray,
                 wts: np.ndarray) -> None:
    """Barycentric weights in the Delaunay simplex of the mesh states around each image."""
    from scipy.spatial import Delaunay, QhullError

    d = Z.shape[1]
    try:
        tri = Delaunay(Z)
    except QhullError:  # a degenerate slice (all states on a line, a plane): nearest only
        return
    s = tri.find_simplex(Yz)
    inside = s >= 0
    T = tri.transform[s[inside]]
    b = np.einsum("ijk,ik->ij", T[:, :d, :], Yz[inside] - T[:, d, :])
    r = rows[inside]
    idx[r] = own[tri.simplices[s[inside]]]
    wts[r] = np.c_[b, 1 - b.sum(axis=1)]


def _chain(step: _Stepper, mesh: np.ndarray, mlab: np.ndarray, weights: np.ndarray, chart: _Chart,
           law: Any, bisections: int) -> _Chain:
    from scipy.sparse import coo_matrix

    Y, ok = step.images(mesh)
    n, nq = len(mesh), step.nq
    src = np.repeat(np.arange(n), nq)
    lab = chart.labels(n, nq)
    if law is not None:
        w, beyond = _edges(step, law, mesh, ok.reshape(n, nq), bisections)
        w = w.ravel()
    else:
        w, beyond = np.tile(weights, n), np.zeros(n)
    idx, wts = _assign(mesh, mlab, Y[ok], lab[ok], chart)
    rows = np.repeat(src[ok], idx.shape[1])
    vals = (wts * w[ok][:, None]).ravel()
    Q = coo_matrix((vals, (rows, idx.ravel())), shape=(n, n)).tocsr()
    fall = np.bincount(src[~ok], weights=w[~ok], minlength=n) + beyond
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
                max_states: int = 20_000, bisections: int = 12, mesh: str = "section",
                params: Mapping[str, float] | None = None,
                start: Sequence[float] | None = None, threads: int = 1, opts: Options | None = None) -> MarkovPassage:
    """The mean first-passage time to a fall on ``terrain`` from a Markov chain on a mesh of the
    section (module docstring).

    ``spacing``: the finest mesh spacing, relative to the spread of the gait's images;
    ``levels``: chains built at ``spacing · 2^(levels−1)``, …, ``spacing`` (the convergence
    shown; three or more for a Richardson limit); ``nodes``: quadrature nodes per drawn
    parameter; ``max_states``: the mesh's cap; ``bisections``: walks that locate each change of
    outcome between nodes; ``mesh``: ``"section"`` (slices on each node's section, the chart's
    coordinates) or ``"state"`` (every state coordinate), see the module docstring;
    ``params``, ``start``, ``threads``, ``opts`` as for :func:`amble.analysis.mfpt.mfpt`."""
    for name, v, low in (("levels", levels, 1), ("nodes", nodes, 1), ("max_states", max_states, 2),
                         ("bisections", bisections, 0), ("threads", threads, 1)):
        if isinstance(v, bool) or not isinstance(v, int) or v < low:
            raise ParameterError(f"{name} must be an integer ≥ {low}, got {v!r}")
    if mesh not in MESHES:
        raise ParameterError(f"mesh must be one of {', '.join(MESHES)}, got {mesh!r}")
    if not (isinstance(spacing, (int, float)) and math.isfinite(spacing) and spacing > 0):
        raise ParameterError(f"spacing must be a number > 0, got {spacing!r}")
    k, names, p0, x0, mode = terrain_start(system, terrain, params, start)
    draws, weights = quadrature(terrain, nodes)
    one = next(iter(terrain.draws.values()))
    law = _law(*one) if len(terrain.draws) == 1 and not _fixed(*one) else None
    step = _Stepper(k, p0, [names.index(n) for n in terrain.draws], draws, mode, x0, walk_options(system, opts),
                    threads)
    # the scale of each coordinate: the spread of two steps' images of the gait
    Y1, ok1 = step.images(x0[None, :])
    Y2, ok2 = step.images(Y1[ok1]) if ok1.any() else (Y1[:0], ok1[:0])
    spread = np.vstack([Y1[ok1], Y2[ok2]]).std(axis=0) if ok1.any() else np.zeros_like(x0)
    ref = max(float(np.max(spread)), 1e-12)
    varying = spread > 1e-9 * ref
    if not varying.any():  # every image is the gait: distances in every coordinate
        varying[:] = True
    scale = np.where(varying, spread, ref)
    chart = _Chart(np.flatnonzero(varying), scale[varying], False)
    if mesh == "section":
        S, sliced = _section_chart(system, {**(params or {}), **terrain.mean()}, step.cols, step.values, x0)
        if sliced:
            chart = _Chart(S, scale[S], True)
    out, chain = [], None
    for lev in range(levels - 1, -1, -1):
        h = spacing * 2.0**lev
        states, labels, complete = _grow(step, x0, chart, h, max_states)
        chain = _chain(step, states, labels, weights, chart, law, bisections)
        m, lam, v = _solve(chain)
        out.append({"spacing": h, "states": len(states), "complete": complete, "mfpt": m,
                    "mfpt_eigen": 1.0 / (1.0 - lam) if lam < 1 else math.inf, "metastable": v})
    fine = out[-1]
    values = [o["mfpt"] for o in out]
    limit, order = _extrapolate(values if all(o["complete"] for o in out[-3:]) else [])
    span = values[-2:] + ([limit] if limit is not None else [])
    assert chain is not None
    return MarkovPassage(mfpt=fine["mfpt"], ci_low=min(span), ci_high=max(span), extrapolated=limit, order=order,
                         mfpt_eigen=fine["mfpt_eigen"], lambda2=1.0 - 1.0 / fine["mfpt_eigen"],
                         states=fine["states"], spacing=spacing, nodes=nodes,
                         levels=[{k: v for k, v in o.items() if k != "metastable"} for o in out],
                         method="markov", terrain=terrain.to_json(), mesh=chain.mesh, metastable=fine["metastable"])


def _extrapolate(values: Sequence[float]) -> tuple[float | None, float | None]:
    """Richardson's extrapolation of the last three levels' values to zero spacing, with the order
    of convergence they show: ``d₁, d₂`` the last two differences, ``p = log₂(d₁/d₂)`` and the
    limit ``m + d₂/(2^p − 1)``. ``(None, None)`` unless the differences shrink without changing
    sign (the levels are not yet where the error falls as a power of the spacing)."""
    if len(values) < 3 or not all(math.isfinite(v) for v in values[-3:]):
        return None, None
    d1, d2 = values[-2] - values[-3], values[-1] - values[-2]
    if d2 == 0.0:
        return values[-1], None
    if d1 * d2 < 0 or abs(d2) >= abs(d1):
        return None, None
    return values[-1] + d2 * d2 / (d1 - d2), math.log2(d1 / d2)


__all__ = ["LINEAR_MAX_DIM", "MESHES", "MarkovPassage", "markov_mfpt", "quadrature"]
