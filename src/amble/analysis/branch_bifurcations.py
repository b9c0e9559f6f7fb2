"""Every bifurcation a sweep's branch crosses — folds, flips and torus (Neimark–Sacker) points —
read from the result by one mechanism.

Along a branch of period-1 gaits, three test functions of the multipliers change sign where a
codimension-one bifurcation is crossed (:mod:`amble.analysis.multipliers`): ψ_fold (a real μ
through +1), ψ_flip (a real μ through −1) and ψ_torus (a complex pair through |μ| = 1). For a
fixed-point branch they are evaluated from each row's stored multipliers; between two
neighbouring converged gaits of one branch where one changes sign, the bifurcation is located on
the branch by :func:`~amble.analysis.bifurcation_location.locate_bifurcation` (secant with bisection,
each iterate corrected onto the branch, to 1e-12 in the parameter) when the system is given.
A continuation locates them as it traces its branches; its result holds them as rows.

Units: the swept parameter in its own units; angles in rad.
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING

import numpy as np

from ..errors import StateError
from .bifurcation_location import locate_bifurcation
from .branch import BifurcationPoint, BranchPoint
from .defaults import FIXED_POINT_TOL, RESIDUAL_TOL
from .multipliers import KINDS, torus_pair
from .store import SweepResult, state_from_row

if TYPE_CHECKING:  # a compiled system (amble.backend.compiled) serves too, without SymPy
    from ..modelling.hybrid import HybridSystem


def multiplier_tests(multipliers: Sequence[complex]) -> tuple[float, float, float]:
    """(ψ_fold, ψ_flip, ψ_torus) from the multipliers themselves: ∏(μᵢ − 1), ∏(μᵢ + 1) and
    ∏_{i<j}(μᵢμⱼ − 1) (real for a real map's spectrum; equal to the determinants of
    :func:`~amble.analysis.multipliers.crossing_functions`)."""
    mu = np.asarray(multipliers, complex)
    pairs = [mu[i] * mu[j] - 1 for i in range(mu.size) for j in range(i + 1, mu.size)]
    return float(np.prod(mu - 1).real), float(np.prod(mu + 1).real), float(np.prod(pairs).real)


def _multipliers(row: Mapping[str, str]) -> np.ndarray:
    return np.array([complex(re, im) for re, im in json.loads(row["multipliers"])])


def _point(row: Mapping[str, str], p: str, names: Sequence[str]) -> BranchPoint:
    """A stored row as a branch point (its orbit and step times when the row has them)."""
    x = state_from_row(row, names)
    state = x if x is not None else np.full(len(names), np.nan)
    orbit = np.asarray(json.loads(row["orbit"])) if row.get("orbit") else state[None, :]
    times = json.loads(row["step_times"]) if row.get("step_times") else [float(row.get("step_time") or "nan")]
    return BranchPoint(value=float(row[p]), state=state, orbit=orbit, step_times=times,
                       multipliers=_multipliers(row), residual=float(row.get("residual") or "nan"))


def _fixed_point(result: SweepResult, system: HybridSystem | None, params: Mapping[str, float] | None,
                 tol: float) -> list[BifurcationPoint]:
    """A fixed-point branch: each sign change of a test function between two neighbouring
    converged gaits of one branch, located (with ``system``) or its nearer grid point (without)."""
    if len(result.params) != 1:
        raise StateError(f"bifurcations reads a branch over one parameter, not a map over {len(result.params)}")
    p = result.params[0]
    rows = sorted(result.rows, key=lambda r: int(r["i"]))
    out: list[BifurcationPoint] = []
    for ra, rb in zip(rows, rows[1:]):
        if ra["status"] != "ok" or rb["status"] != "ok":
            continue  # a failed point between them: no branch joins the two
        ta, tb = multiplier_tests(_multipliers(ra)), multiplier_tests(_multipliers(rb))
        crossed = [(kind, fa, fb) for kind, fa, fb in zip(KINDS, ta, tb) if fa * fb < 0]
        if not crossed or not _one_branch(result, system, params, tol, p, ra, rb):
            continue
        for kind, fa, fb in crossed:
            bp = _between(result, system, params, tol, p, kind, (ra, fa), (rb, fb))
            if bp is not None:
                out.append(bp)
    return sorted(out, key=lambda b: b.value)


#: How close (∞-norm, in the state's units) the branch continued from one row must come to the
#: next row's gait for the two to be one branch: far above the corrected gaits' residual (1e-12),
#: far below the distance between distinct gaits of one parameter value.
SAME_GAIT = 1e-7


def _one_branch(result: SweepResult, system: HybridSystem | None, params: Mapping[str, float] | None, tol: float,
                p: str, ra: Mapping[str, str], rb: Mapping[str, str]) -> bool:
    """Whether two neighbouring converged rows lie on one branch: the same ``branch`` id, or —
    with ``system`` — ``rb`` began its chunk from the model's guess (not continued from the row
    before: a task's first point, ``seeded`` false, no ``branch_break``) and the branch continued
    from ``ra``'s gait reaches ``rb``'s. Chunks are computed independently, so a branch that runs
    through a chunk boundary gets a new id there without being broken."""
    if ra.get("branch") == rb.get("branch"):
        return True
    if system is None or rb.get("seeded") != "false" or rb.get("branch_break"):
        return False  # without the system, or a branch the continuation could not carry on
    from ..errors import AmbleError
    from .poincare import continue_fixed_point

    xa, xb = (state_from_row(r, result.state_names) for r in (ra, rb))
    if xa is None or xb is None:
        return False
    base = dict(params or {})
    try:
        lc = continue_fixed_point(system, xa, {**base, p: float(ra[p])}, {**base, p: float(rb[p])},
                                  rtol=FIXED_POINT_TOL, atol=FIXED_POINT_TOL, tol=tol)
    except AmbleError:
        return False
    return bool(np.max(np.abs(np.asarray(lc.fixed_point) - xb)) <= SAME_GAIT)


def _between(result: SweepResult, system: HybridSystem | None, params: Mapping[str, float] | None, tol: float,
             p: str, kind: str, a: tuple[Mapping[str, str], float], b: tuple[Mapping[str, str], float]
             ) -> BifurcationPoint | None:
    (ra, fa), (rb, fb) = a, b
    if system is not None:
        xa, xb = (state_from_row(r, result.state_names) for r in (ra, rb))
        if xa is None or xb is None:
            raise StateError("the result's rows lack their states: the bifurcation cannot be located")
        return locate_bifurcation(system, p, (xa, float(ra[p])), (xb, float(rb[p])), kind, params=params,
                                  rtol=FIXED_POINT_TOL, atol=FIXED_POINT_TOL, tol=tol)
    near = ra if abs(fa) < abs(fb) else rb
    pt = _point(near, p, result.state_names)
    if kind == "torus" and torus_pair(pt.multipliers) is None:
        return None  # the pair with μᵢμⱼ nearest 1 is real: a neutral saddle
    direction = "→".join("stable" if r["stable"] == "true" else "unstable" for r in (ra, rb))
    return BifurcationPoint(kind, pt, fa if near is ra else fb, located=False, direction=direction)


def _continuation(result: SweepResult) -> list[BifurcationPoint]:
    """A continuation: the bifurcation rows it wrote, branch by branch."""
    p = result.params[0]
    out = []
    for r in result.rows:
        if r["row"] in KINDS and r["status"] == "ok":
            bp = BifurcationPoint(r["row"], _point(r, p, result.state_names), float(r["test"] or "nan"),
                                  located=not r["reason"], direction=r.get("direction", ""))
            out.append(bp)
    return out


def bifurcations(result: SweepResult, system: HybridSystem | None = None, *,
                 params: Mapping[str, float] | None = None, tol: float = RESIDUAL_TOL) -> list[BifurcationPoint]:
    """The folds, flips and torus (Neimark–Sacker) points a sweep's branch crosses.

    - a fixed-point branch over one parameter (``amble.sweep(system, "fixed-point", {param: values})``):
      between two neighbouring converged gaits of one branch (same ``branch`` id, or — with
      ``system`` — a chunk's first gait that the branch continued from the gait before reaches;
      no failure between them) where ψ_fold, ψ_flip or ψ_torus changes sign, the bifurcation is located on
      the branch with ``system`` (and ``params``, the sweep's other parameters; ``tol`` the
      residual of each corrected gait), in order of the parameter; without the system, the
      bracketing grid point with the smaller |ψ| stands for it (``located=False``);
    - a continuation: the bifurcations located as its branches were traced (branch by branch).

    Each is a :class:`~amble.analysis.branch.BifurcationPoint`: ``kind`` (``"fold"``,
    ``"flip"``, ``"torus"``), ``value``, the gait and multipliers there (``point``),
    ``direction`` (stability before → after, in grid order), and for a torus point ``angle``
    θ = |arg μ| (rad), ``rotation`` θ/2π and ``resonance`` (a strong resonance 1:1, 1:2, 1:3,
    1:4, or ``None``). A zero of ψ_torus where the pair is real (a neutral saddle) is dropped.
    A bifurcation diagram holds no multipliers and is refused (:func:`period_doubling` reads
    where it doubles).
    """
    kind = getattr(result, "kind", type(result).__name__)
    if kind == "fixed-point":
        return _fixed_point(result, system, params, tol)
    if kind == "continuation":
        return _continuation(result)
    raise StateError(f"bifurcations reads a result of kind fixed-point or continuation, not {kind!r}")


__all__ = ["bifurcations", "multiplier_tests"]
