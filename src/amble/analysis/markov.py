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
interval on its own side of the change (:func:`~amble.analysis.markov_quadrature._edges`); a fall
in the law's tails beyond the outer nodes is found the same way.

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

from ..errors import ParameterError
from ..simulation.engine import Options
from .markov_chain import _chain, _solve
from .markov_interpolation import LINEAR_MAX_DIM
from .markov_mesh import MESHES, _Chart, _grow, _section_chart, _Stepper
from .markov_quadrature import _fixed, _law, quadrature
from .mfpt import Terrain, terrain_start, walk_options


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
