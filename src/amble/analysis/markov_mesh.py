"""The mesh of a Markov chain's states (:func:`amble.analysis.markov.markov_mfpt`): one step of
many states on many terrain nodes in one compiled call, where mesh states are compared (the chart
of each node's post-impact section, or every state coordinate), and the mesh grown from the gait
in waves of images farther than the spacing from every mesh state of their slice."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from ..errors import SimulationError
from ..simulation.engine import CODE, Options, walk_many

#: how mesh states are compared: in the chart of each terrain node's section, or in every state coordinate
MESHES = ("section", "state")


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
