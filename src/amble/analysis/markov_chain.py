"""The Markov chain on a mesh (:func:`amble.analysis.markov.markov_mfpt`): the transitions ``Q``
among the mesh states and each state's probability of falling, and from them the mean
first-passage time, λ₂ and the metastable distribution."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from .markov_interpolation import _assign
from .markov_mesh import _Chart, _Stepper
from .markov_quadrature import _edges


@dataclass
class _Chain:
    mesh: np.ndarray
    Q: Any  # scipy.sparse csr
    fall: np.ndarray


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
