"""An image of a step assigned to the mesh states of its own slice (:mod:`amble.analysis.markov`):
barycentric weights in a Delaunay simplex, linear ones between two neighbours on a line, else the
nearest mesh state."""

from __future__ import annotations

import numpy as np

from .markov_mesh import _Chart

#: sections with at most this many varying coordinates are interpolated linearly (Delaunay)
LINEAR_MAX_DIM = 3


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
