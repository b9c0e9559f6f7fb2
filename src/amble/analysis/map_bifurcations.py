"""The bifurcation curves of a two-parameter stability map: where, between two neighbouring cells
of one branch, a real multiplier crosses +1 (fold) or −1 (flip, period doubling), or a complex
pair crosses the unit circle (torus, Neimark–Sacker).

For each pair of grid neighbours (along the first parameter ``a``: cells ``(i, j)`` and
``(i + 1, j)``; along the second ``b``: ``(i, j)`` and ``(i, j + 1)``) that both converged and lie
on one branch, the test functions ψ_fold = ∏(μᵢ − 1), ψ_flip = ∏(μᵢ + 1) and
ψ_torus = ∏_{i<j}(μᵢμⱼ − 1) (:func:`~amble.analysis.branch_bifurcations.multiplier_tests`) are
evaluated from the two cells' stored multipliers; a sign change says the curve of that kind runs
between the two cells. A complex pair never changes the sign of ψ_fold or ψ_flip; ψ_torus also
vanishes at a *neutral saddle* (a real pair with μᵢμⱼ = 1), so a torus crossing is kept only when
the pair with product nearest 1 is a complex-conjugate pair in both cells (it crosses the circle
as a pair; :func:`~amble.analysis.multipliers.torus_pair`). A grid too coarse to see a pair turn
complex between two cells is not reported as a torus crossing.

**One branch.** A sign change between two different gaits (where the map's warm start lost its
branch and a new one was found) is no bifurcation, so two cells count only when they lie on one
branch:

- along ``b`` within a row (one task, warm-started cell to cell): the same ``branch`` id (rows of
  files written before branch ids: the later cell was continued from the earlier, ``seeded`` and
  no ``branch_break``);
- otherwise (along ``a``: each row is its own task and starts its own ids; or ids that differ):
  with the ``system``, the gait of one cell continued to the other's parameters
  (:func:`~amble.analysis.poincare.continue_fixed_point`, branch jumps refused) lands on the
  other's gait to :data:`~amble.analysis.branch_bifurcations.SAME_GAIT`; without it, the two
  fixed points lie within :data:`NEAR_GAIT` of each other (a heuristic: pass the system to
  decide exactly). Only neighbours whose test functions change sign are checked.

Units: the parameters in their own units; multipliers dimensionless.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from typing import TYPE_CHECKING, Any, NamedTuple

import numpy as np

from ..errors import AmbleError, StateError
from .branch_bifurcations import SAME_GAIT, multiplier_tests
from .defaults import FIXED_POINT_TOL, RESIDUAL_TOL
from .multipliers import KINDS, torus_pair
from .store import state_from_row

if TYPE_CHECKING:  # a compiled system (amble.backend.compiled) serves too, without SymPy
    from ..modelling.hybrid import HybridSystem

#: Without the system, two neighbouring cells of different rows (or branch ids) are one branch when
#: their fixed points differ by at most this, ∞-norm relative to max(1, |x|∞): far above the change
#: of a gait between grid neighbours of a map that resolves its curves, below the distance between
#: distinct gaits of one walker (a heuristic; the system decides exactly).
NEAR_GAIT = 0.05


class MapCrossing(NamedTuple):
    """A bifurcation curve crossing the boundary between two neighbouring cells of a map.

    ``(i, j)`` and ``(i2, j2)``: the two cells' grid indices (``i2 = i + 1`` along the first
    parameter, ``j2 = j + 1`` along the second); ``kind``: ``"fold"``, ``"flip"`` or ``"torus"``;
    ``a_mid``, ``b_mid``: the midpoint of the two cells' parameter values (the first, the
    second parameter), where the curve is drawn; ``link``: how the two were found to be one
    branch (``"branch"``: the same id; ``"continued"``: the system carried one gait to the other;
    ``"near"``: their fixed points are within :data:`NEAR_GAIT`)."""

    i: int
    j: int
    i2: int
    j2: int
    kind: str
    a_mid: float
    b_mid: float
    link: str


def _ok(row: Mapping[str, Any] | None) -> bool:
    return row is not None and str(row.get("status")) == "ok" and bool(row.get("multipliers"))


def _multipliers(row: Mapping[str, Any]) -> np.ndarray:
    raw = row["multipliers"]
    pairs = json.loads(raw) if isinstance(raw, str) else raw
    return np.array([complex(float(re), float(im)) for re, im in pairs])


def _text(v: Any) -> str:
    """A cell's value as stored text ('' for empty, ints without '.0')."""
    if v is None or (isinstance(v, float) and not np.isfinite(v)):
        return ""
    s = str(v).strip()
    try:
        f = float(s)
        return str(int(f)) if f == int(f) else s
    except (TypeError, ValueError, OverflowError):
        return "" if s in ("nan", "None") else s


def same_branch_id(ra: Mapping[str, Any], rb: Mapping[str, Any]) -> bool:
    """Whether cell ``rb`` (the later one in its row) carries ``ra``'s branch: the same ``branch``
    id, or for rows without ids, ``rb`` continued (``seeded``) with no ``branch_break``."""
    ia, ib = _text(ra.get("branch")), _text(rb.get("branch"))
    if ia and ib:
        return ia == ib
    return _text(rb.get("seeded")).lower() == "true" and not _text(rb.get("branch_break"))


def _state(row: Mapping[str, Any], names: list[str]) -> np.ndarray | None:
    """A cell's fixed point (its ``x_<state>`` columns), ``None`` if missing or not finite."""
    if names:
        return state_from_row(row, names)
    cols = [k for k in row if k.startswith("x_")]
    return state_from_row(row, [k[2:] for k in cols]) if cols else None


class _Linker:
    """Decides whether two cells of different rows (or ids) are one branch (module docstring)."""

    def __init__(self, result: Any, system: HybridSystem | None, params: Mapping[str, float] | None, tol: float,
                 near: float) -> None:
        self.names = list(getattr(result, "state_names", []) or [])
        self.a, self.b = result.params
        self.system, self.params, self.tol, self.near = system, dict(params or {}), tol, near

    def __call__(self, ra: Mapping[str, Any], rb: Mapping[str, Any]) -> str | None:
        xa, xb = _state(ra, self.names), _state(rb, self.names)
        if xa is None or xb is None:
            return None
        if self.system is None:
            scale = max(1.0, float(np.max(np.abs(xa))))
            return "near" if float(np.max(np.abs(xa - xb))) <= self.near * scale else None
        from .poincare import continue_fixed_point

        pa = {**self.params, self.a: float(ra[self.a]), self.b: float(ra[self.b])}
        pb = {**self.params, self.a: float(rb[self.a]), self.b: float(rb[self.b])}
        try:
            lc = continue_fixed_point(self.system, xa, pa, pb, rtol=FIXED_POINT_TOL, atol=FIXED_POINT_TOL,
                                      tol=self.tol)
        except AmbleError:
            return None
        return "continued" if float(np.max(np.abs(np.asarray(lc.fixed_point) - xb))) <= SAME_GAIT else None


def crossed_kinds(mu_a: np.ndarray, mu_b: np.ndarray) -> list[str]:
    """The kinds (of :data:`~amble.analysis.multipliers.KINDS`) whose test function changes sign
    between two gaits' multipliers; a torus only when both gaits' pair with product nearest 1 is
    complex (a pair crossing the circle, not a neutral saddle)."""
    ta, tb = multiplier_tests(mu_a), multiplier_tests(mu_b)
    out = []
    for kind, fa, fb in zip(KINDS, ta, tb):
        if not fa * fb < 0:
            continue
        if kind == "torus" and not all(_complex_pair(mu) for mu in (mu_a, mu_b)):
            continue
        out.append(kind)
    return out


def _complex_pair(mu: np.ndarray) -> bool:
    pair = torus_pair(mu)
    return pair is not None and abs(pair[0].imag) > 0


def map_crossings(result: Any, system: HybridSystem | None = None, *, params: Mapping[str, float] | None = None,
                  tol: float = RESIDUAL_TOL, near: float = NEAR_GAIT) -> list[MapCrossing]:
    """The fold, flip and torus crossings between neighbouring cells of a two-parameter
    fixed-point map (``amble.sweep(system, "fixed-point", {a: values_a, b: values_b})``, kind
    ``fixed-point-map``), in grid order: each a :class:`MapCrossing` ``(i, j, i2, j2, kind,
    a_mid, b_mid, link)``. Together they trace the map's bifurcation curves on the cell
    boundaries (module docstring: which neighbours count as one branch, and why a branch
    change is none).

    ``system`` (and ``params``, the sweep's other parameters; ``tol`` the residual of a
    continued gait): decides exactly whether two cells of different rows lie on one branch by
    continuing one to the other; without it their fixed points must lie within ``near``
    (relative, :data:`NEAR_GAIT`). Rows without multipliers (failed cells) cross nothing."""
    kind = getattr(result, "kind", "fixed-point-map")
    if kind != "fixed-point-map" or len(result.params) != 2:
        raise StateError(f"map_crossings reads a two-parameter fixed-point map, not a result of kind {kind!r}")
    if near < 0:
        raise StateError(f"near must be at least 0, got {near}")
    a, b = result.params
    cells = {(int(float(r["i"])), int(float(r["j"]))): r for r in result.rows}
    link = _Linker(result, system, params, tol, near)
    out: list[MapCrossing] = []
    for (i, j), ra in sorted(cells.items()):
        if not _ok(ra):
            continue
        for i2, j2 in ((i + 1, j), (i, j + 1)):
            rb = cells.get((i2, j2))
            if not _ok(rb):
                continue
            kinds = crossed_kinds(_multipliers(ra), _multipliers(rb))
            if not kinds:
                continue
            how = "branch" if i2 == i and same_branch_id(ra, rb) else link(ra, rb)
            if how is None:
                continue  # another gait: the sign change is a branch change, not a bifurcation
            am, bm = 0.5 * (float(ra[a]) + float(rb[a])), 0.5 * (float(ra[b]) + float(rb[b]))
            out.extend(MapCrossing(i, j, i2, j2, k, am, bm, how) for k in kinds)
    return out


def branch_boundaries(result: Any) -> list[tuple[int, int, int, int]]:
    """The neighbouring pairs ``(i, j, i2, j2)`` of converged cells of one row (along the second
    parameter) whose branch changed between them (another ``branch`` id, or no continuation):
    where the map's colour may jump without a bifurcation."""
    cells = {(int(float(r["i"])), int(float(r["j"]))): r for r in result.rows}
    out = []
    for (i, j), ra in sorted(cells.items()):
        rb = cells.get((i, j + 1))
        if ra.get("status") == "ok" and rb is not None and rb.get("status") == "ok" \
                and (_text(ra.get("branch")) or _text(rb.get("seeded"))) and not same_branch_id(ra, rb):
            out.append((i, j, i, j + 1))
    return out


__all__ = ["NEAR_GAIT", "MapCrossing", "branch_boundaries", "crossed_kinds", "map_crossings", "same_branch_id"]
