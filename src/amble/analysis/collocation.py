"""Hermite–Simpson direct collocation on a uniform mesh (the separated form).

A step of duration ``T`` is cut into ``N`` intervals of length ``h = T/N``. The state is kept at
the ``2N + 1`` points ``τ_j = j h / 2`` (mesh points at even ``j``, interval midpoints at odd
``j``); on interval ``i`` (points ``2i``, ``2i+1``, ``2i+2``, derivatives ``f``) the state is the
cubic Hermite interpolant, which holds when (Betts, *Practical Methods for Optimal Control*, 2010,
§4.6.4; Kelly, SIAM Review 59(4), 2017, Eq. 6.4–6.5)

* ``x_{2i+2} − x_{2i} − h/6 (f_{2i} + 4 f_{2i+1} + f_{2i+2}) = 0``   (Simpson's rule),
* ``x_{2i+1} − (x_{2i} + x_{2i+2})/2 − h/8 (f_{2i} − f_{2i+2}) = 0``  (the Hermite midpoint).

The local error is ``O(h⁵)``, the global error of the states ``O(h⁴)``; integrals of the running
cost use the same Simpson weights.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np


def defects(x: Sequence[Any], f: Sequence[Any], h: Any) -> tuple[Any, Any]:
    """The Simpson and the Hermite-midpoint defects of all intervals at once: ``x`` and ``f`` are
    ``(start, midpoint, end)`` of the states and their derivatives, one column per interval
    (CasADi or NumPy matrices), ``h`` the interval length."""
    (xa, xm, xb), (fa, fm, fb) = x, f
    return xb - xa - h / 6 * (fa + 4 * fm + fb), xm - (xa + xb) / 2 - h / 8 * (fa - fb)


def simpson_weights(intervals: int) -> np.ndarray:
    """Weights ``w_j`` with ``∫₀ᵀ c dt ≈ h Σ w_j c(τ_j)`` over the ``2N + 1`` points (``h = T/N``)."""
    w = np.zeros(2 * intervals + 1)
    for i in range(intervals):
        w[2 * i] += 1 / 6
        w[2 * i + 1] += 4 / 6
        w[2 * i + 2] += 1 / 6
    return w


def hermite(t: np.ndarray, T: float, x: np.ndarray, f: np.ndarray) -> np.ndarray:
    """The collocation solution at times ``t`` (s, in ``[0, T]``): on each interval the cubic
    Hermite interpolant through its mesh points with their derivatives (``x`` and ``f`` of shape
    ``(2N + 1, nx)``; the midpoint defect makes it pass through the midpoint state too)."""
    N = (len(x) - 1) // 2
    h = T / N
    i = np.clip((np.asarray(t, float) // h).astype(int), 0, N - 1)
    s = (np.asarray(t, float) - i * h) / h
    a, b = 2 * i, 2 * i + 2
    h00, h10 = 2 * s**3 - 3 * s**2 + 1, s**3 - 2 * s**2 + s
    h01, h11 = -2 * s**3 + 3 * s**2, s**3 - s**2
    return (h00[:, None] * x[a] + h10[:, None] * h * f[a] + h01[:, None] * x[b] + h11[:, None] * h * f[b])
