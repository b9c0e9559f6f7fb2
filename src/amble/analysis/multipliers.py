"""The test functions of a gait's Floquet multipliers, and what a torus crossing's pair says.

With ``A`` the return map's Jacobian on the section's tangent space (its eigenvalues μᵢ are the
nontrivial multipliers), three smooth functions of ``A`` change sign where a codimension-one
bifurcation of a fixed point of the map is crossed:

    ψ_fold  = det(A − I)         = ∏ (μᵢ − 1)             a real μ through +1 (fold),
    ψ_flip  = det(A + I)         = ∏ (μᵢ + 1)             a real μ through −1 (period doubling),
    ψ_torus = det(A ⊙ A − I)     = ∏_{i<j} (μᵢ μⱼ − 1)    a complex pair through |μ| = 1 (Neimark–Sacker).

``A ⊙ A`` is the bialternate product of ``A`` with itself, the second compound matrix
(:func:`second_compound`: the 2 × 2 minors of ``A``), whose eigenvalues are the products μᵢ μⱼ,
i < j. A complex pair μ, μ̄ contributes the real factor |μ|² − 1 to ψ_torus, which vanishes exactly
where the pair crosses the unit circle; ψ_torus is a polynomial in the entries of ``A``, so it is
smooth through the collision of two real multipliers into a complex pair, where a function of
the pair's modulus is not. It also vanishes at a *neutral saddle* (two real multipliers with
μᵢ μⱼ = 1, one inside and one outside the circle), which is no bifurcation of the fixed point:
:func:`torus_pair` tells the two apart at the located zero (Kuznetsov, *Elements of Applied
Bifurcation Theory*, 3rd ed., Springer 2004, §10.2 and §4.7).

At a Neimark–Sacker point the pair is ``e^{±iθ}``; an invariant circle (a torus of the flow) is born,
on which the map rotates by about θ per step: its rotation number is θ / 2π. The normal form
fails at the *strong resonances* θ = 0 (1:1), π (1:2), 2π/3 (1:3) and π/2 (1:4), which
:func:`resonance` names.

Units: multipliers and test functions are dimensionless; angles in rad.
"""

from __future__ import annotations

import math

import numpy as np

#: A crossing whose angle lies this close (rad) to a strong resonance is reported as that resonance.
RESONANCE_TOL = 1e-3
#: Two real multipliers closer than this are one double multiplier (the pair of a 1:1 or 1:2 point).
DOUBLE_TOL = 1e-6

#: The strong resonances of a Neimark–Sacker point: the name of each and its angle θ (rad)
STRONG_RESONANCES: dict[str, float] = {"1:1": 0.0, "1:2": math.pi, "1:3": 2 * math.pi / 3, "1:4": math.pi / 2}

#: The bifurcation kinds whose test functions are sign-checked along a branch, in this order
KINDS = ("fold", "flip", "torus")


def second_compound(A: np.ndarray) -> np.ndarray:
    """The second compound (bialternate product ``A ⊙ A``) of a square ``A`` (d × d): the matrix
    of its 2 × 2 minors over the index pairs (i < j), of size d(d−1)/2. Its eigenvalues are
    the products μᵢ μⱼ (i < j) of ``A``'s eigenvalues (0 × 0 for d = 1)."""
    A = np.asarray(A, float)
    d = A.shape[0]
    pairs = [(i, j) for i in range(d) for j in range(i + 1, d)]
    C = np.empty((len(pairs), len(pairs)))
    for r, (i, j) in enumerate(pairs):
        for c, (k, m) in enumerate(pairs):
            C[r, c] = A[i, k] * A[j, m] - A[i, m] * A[j, k]
    return C


def crossing_functions(A: np.ndarray) -> tuple[float, float, float]:
    """(ψ_fold, ψ_flip, ψ_torus) of the reduced Jacobian ``A`` (module docstring), in :data:`KINDS` order."""
    eye = np.eye(A.shape[0])
    C = second_compound(A)
    torus = float(np.linalg.det(C - np.eye(C.shape[0]))) if C.size else 1.0  # one multiplier: no pair
    return float(np.linalg.det(A - eye)), float(np.linalg.det(A + eye)), torus


def torus_pair(multipliers: np.ndarray) -> tuple[complex, float] | None:
    """The pair of multipliers whose product is nearest to 1, as ``(μ, θ)`` with ``θ = |arg μ|``
    (rad, in [0, π]) and ``μ`` the one with Im μ ≥ 0; ``None`` when that pair is real and
    distinct (a neutral saddle, μ₁ μ₂ = 1 with μ₁ ≠ μ₂: no bifurcation). A double real multiplier
    +1 or −1 (within :data:`DOUBLE_TOL`) is the pair at θ = 0 or π (the 1:1 or 1:2 resonance)."""
    mu = np.asarray(multipliers, complex)
    if mu.size < 2:
        return None
    i, j = min(((a, b) for a in range(mu.size) for b in range(a + 1, mu.size)),
               key=lambda ab: abs(mu[ab[0]] * mu[ab[1]] - 1))
    a, b = mu[i], mu[j]
    scale = max(1.0, abs(a))
    if abs(a.imag) > DOUBLE_TOL * scale and abs(a - np.conj(b)) < 1e-6 * scale:  # a complex-conjugate pair
        top = a if a.imag > 0 else b
        return complex(top), abs(math.atan2(top.imag, top.real))
    if abs(a - b) < DOUBLE_TOL * scale and abs(abs(a.real) - 1) < math.sqrt(DOUBLE_TOL):
        m = complex(0.5 * (a.real + b.real))
        return m, 0.0 if m.real > 0 else math.pi
    return None


def resonance(theta: float) -> str | None:
    """The strong resonance (``"1:1"``, ``"1:2"``, ``"1:3"``, ``"1:4"``) within :data:`RESONANCE_TOL`
    of the angle ``theta`` (rad, in [0, π]), or ``None``."""
    for name, at in STRONG_RESONANCES.items():
        if abs(theta - at) <= RESONANCE_TOL:
            return name
    return None


__all__ = ["DOUBLE_TOL", "KINDS", "RESONANCE_TOL", "STRONG_RESONANCES", "resonance", "second_compound",
           "crossing_functions", "torus_pair"]
