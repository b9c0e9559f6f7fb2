"""How large a gait's basin of attraction is: the distance from the fixed point to the basin's
boundary along chosen directions, and the fraction of a box around the fixed point that returns
to the gait.

**Inside.** A post-impact state is *inside* the basin when a walk from it returns to the gait:
within ``steps`` footfalls its post-impact state comes within ``tol`` of the fixed point
(``|x − x*|∞``, criterion ``"converge"``, as the cells of :func:`amble.sweep`'s ``basin`` kind are
classified), or, with criterion ``"walk"``, when it just keeps walking ``steps`` footfalls
without falling (any end but a completed step is outside). A state the section has no point for
(a perturbation far from the gait) is outside.

**Directions.** A direction ``d`` is a vector over the state coordinates (a mapping name →
component, normalised to unit 2-norm); the state at distance ``s`` along it is ``x* + s d`` put
on the post-impact section (:meth:`amble.analysis.section.Section.project`) with a chart that
holds the coordinates ``d`` moves: the coordinates the section ties to those (e.g. the stance
angle of a compass gait to its swing angle, both feet on the slope) follow from the section. The
default directions are ``+e`` and ``−e`` for each section coordinate ``e``: their distances are
in that coordinate's unit (rad, rad/s). The *distance to the boundary* is the first ``s`` at
which the state leaves the basin: ``s`` is scanned on ``scan`` evenly spaced points up to
``reach``, and the first outside point and the inside point before it are closed in on by
k-section (``SPLIT`` − 1 points per round, all directions' walks in one compiled call) until they
are ``xtol`` apart. A boundary between two scan points that the scan steps over (a thin
excursion of the outside into the basin) is not seen; a direction with no outside point up to
``reach`` has no distance (``None``).

**Size.** ``samples`` states are drawn uniformly in the box ``x*[i] ± h_i`` over the section
coordinates (default ``h_i``: the larger finite distance along ``±e_i``, else ``reach``), put on
the section and walked, all in one compiled call. The fraction inside estimates the share of the
box in the basin (exact Clopper–Pearson interval of a binomial proportion); ``volume`` is that
fraction times the box's volume (in the product of the coordinates' units).

Units: those of the model's states (angles in rad, angular velocities in rad/s).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..backend.abi import CODE
from ..errors import ConvergenceError, StateError
from ..simulation.engine import Options, walk_many
from .defaults import BASIN_STEPS, BASIN_TOL
from .limit_cycle import LimitCycle
from .return_map import ReturnMap
from .section import Section

#: how a walk counts as inside the basin
CRITERIA = ("converge", "walk")
#: a round of the k-section splits a bracket into this many parts
SPLIT = 8


@dataclass(frozen=True)
class BasinMeasures:
    """Distances to the basin boundary and the basin's share of a box (module docstring).

    ``distances``: per direction, ``name`` (``"+swing_dot"``, or ``"d1"``… for given ones),
    ``direction`` (unit vector, name → component), ``distance`` (``None`` beyond ``reach``),
    ``inside`` and ``outside`` (the bracket: the farthest perturbation found inside and the nearest
    found outside, ``None`` when there is none), ``reason`` (why that nearest outside state is outside:
    ``"off the section"``, ``"not converged"`` — it kept walking elsewhere —, or how its walk
    ended, e.g. ``"fell"``; ``""`` when none was found), ``reach``. ``size``: ``fraction``, ``ci_low``,
    ``ci_high``, ``confidence``, ``samples``, ``inside``, ``box`` (name → [low, high]) and
    ``volume``; ``None`` when no samples were drawn.
    """

    distances: list[dict[str, Any]]
    size: dict[str, Any] | None
    criterion: str
    steps: int
    tol: float
    fixed_point: list[float]
    section_coordinates: list[str]

    def to_json(self) -> dict[str, Any]:
        return {"distances": self.distances, "size": self.size, "criterion": self.criterion, "steps": self.steps,
                "tol": self.tol, "fixed_point": self.fixed_point, "section_coordinates": self.section_coordinates}


class _Judge:
    """Which states are inside: puts raw states on the section and walks them in one call."""

    def __init__(self, cycle: LimitCycle, steps: int, tol: float, criterion: str, rtol: float, atol: float,
                 threads: int) -> None:
        system = cycle.hybrid_system
        rm = ReturnMap(system, cycle.parameters, rtol=rtol, atol=atol, mode=cycle.mode)
        self.k, self.p, self.mode = rm.k, rm.p, rm.mi
        self.xs = np.asarray(cycle.fixed_point, float)
        self.section = Section.of(rm, self.xs)
        self.names = list(cycle.state_names)
        self.steps, self.tol, self.criterion, self.threads = steps, tol, criterion, threads
        self.opts = Options(rtol=rtol, atol=atol, max_step_time=system.max_step_time)

    def chart(self, d: np.ndarray) -> np.ndarray:
        """Section coordinates holding as much of ``d`` as the section lets vary (largest first)."""
        keep: list[int] = []
        for j in np.argsort(-np.abs(d), kind="stable").tolist():
            if d[j] == 0:
                break
            try:
                self.section.coordinates(prefer=[*keep, j])
            except StateError:  # tied on the section to those already held
                continue
            keep.append(j)
        return self.section.coordinates(prefer=keep)

    def inside(self, raw: np.ndarray, S: np.ndarray) -> tuple[np.ndarray, list[str]]:
        """Whether each row of ``raw`` (states, its coordinates ``S`` kept) is inside the basin,
        and why each one outside is (``"off the section"``, ``"not converged"`` or the walk's status,
        e.g. ``"fell"``; ``""`` inside)."""
        x, off = self.section.project_array(raw, S, threads=self.threads)
        ok = ~off & np.isfinite(x).all(axis=1)
        res = np.zeros(len(raw), dtype=bool)
        why = ["off the section"] * len(raw)
        if ok.any():
            converge = self.criterion == "converge"
            w = walk_many(self.k, self.p, self.mode, x[ok], self.xs, steps=self.steps,
                          check_every=min(5, self.steps), tol=self.tol if converge else -1.0, opts=self.opts,
                          threads=self.threads)
            done = w["code"] == CODE["STEPS_DONE"]
            res[ok] = done & (w["distance"] < self.tol) if converge else done
            for r, st, d, i in zip(np.flatnonzero(ok).tolist(), w["status"], done.tolist(), res[ok].tolist()):
                why[r] = "" if i else "not converged" if d else st
        return res, why


def _unit(direction: Mapping[str, float], names: Sequence[str]) -> np.ndarray:
    d = np.zeros(len(names))
    for nm, v in direction.items():
        if nm not in names:
            raise StateError(f"direction: unknown coordinate {nm!r}; coordinates: {', '.join(names)}")
        d[list(names).index(nm)] = float(v)
    norm = float(np.linalg.norm(d))
    if not math.isfinite(norm) or norm == 0.0:
        raise StateError(f"direction {dict(direction)!r}: needs finite components, not all zero")
    return d / norm


def _distances(judge: _Judge, dirs: list[np.ndarray], charts: list[np.ndarray], reach: float, scan: int,
               xtol: float) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """The bracket (last inside, first outside) of every direction's first boundary crossing,
    first outside ``inf`` when none is found up to ``reach``, and why the first outside is."""
    m = len(dirs)
    lo, hi = np.zeros(m), np.full(m, math.inf)
    why = [""] * m

    def judge_points(rows: list[tuple[int, float]]) -> tuple[np.ndarray, list[str]]:
        raw = np.array([judge.xs + s * dirs[j] for j, s in rows])
        res, reasons = np.zeros(len(rows), dtype=bool), [""] * len(rows)
        groups: dict[bytes, list[int]] = {}
        for r, (j, _) in enumerate(rows):
            groups.setdefault(charts[j].tobytes(), []).append(r)
        for idx in groups.values():  # one compiled call per chart (the default directions: one per coordinate)
            res[idx], got = judge.inside(raw[idx], charts[rows[idx[0]][0]])
            for r, w in zip(idx, got):
                reasons[r] = w
        return res, reasons

    def narrow(points: dict[int, np.ndarray]) -> None:
        rows = [(j, float(s)) for j, ss in points.items() for s in ss]
        res, reasons = judge_points(rows)
        at = 0
        for j, ss in points.items():
            ins = res[at : at + len(ss)]
            out = np.flatnonzero(~ins)
            if out.size:
                hi[j], why[j] = ss[out[0]], reasons[at + int(out[0])]
                if out[0] > 0:
                    lo[j] = ss[out[0] - 1]
            else:
                lo[j] = ss[-1]
            at += len(ss)

    narrow({j: reach * np.arange(1, scan + 1) / scan for j in range(m)})
    for _ in range(200):
        open_ = [j for j in range(m) if math.isfinite(hi[j]) and hi[j] - lo[j] > xtol]
        if not open_:
            break
        narrow({j: lo[j] + (hi[j] - lo[j]) * np.arange(1, SPLIT) / SPLIT for j in open_})
    return lo, hi, why


def _size(judge: _Judge, S: np.ndarray, half: np.ndarray, samples: int, seed: int, confidence: float
          ) -> dict[str, Any]:
    from scipy.stats import binomtest

    rng = np.random.default_rng(seed)
    raw = np.tile(judge.xs, (samples, 1))
    raw[:, S] += rng.uniform(-1.0, 1.0, (samples, len(S))) * half
    n_in = int(judge.inside(raw, S)[0].sum())
    ci = binomtest(n_in, samples).proportion_ci(confidence_level=confidence, method="exact")
    frac = n_in / samples
    box = {judge.names[i]: [float(judge.xs[i] - h), float(judge.xs[i] + h)] for i, h in zip(S.tolist(), half)}
    return {"fraction": frac, "ci_low": float(ci.low), "ci_high": float(ci.high), "confidence": confidence,
            "samples": samples, "inside": n_in, "box": box, "volume": frac * float(np.prod(2 * half))}


def _check(steps: int, scan: int, samples: int, threads: int, reach: float, xtol: float, tol: float,
           criterion: str, confidence: float) -> None:
    for name, v, low in (("steps", steps, 1), ("scan", scan, 1), ("samples", samples, 0), ("threads", threads, 1)):
        if isinstance(v, bool) or not isinstance(v, int) or v < low:
            raise StateError(f"{name} must be an integer ≥ {low}, got {v!r}")
    for name, v in (("reach", reach), ("xtol", xtol), ("tol", tol)):
        if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
            raise StateError(f"{name} must be a finite number > 0, got {v!r}")
    if criterion not in CRITERIA:
        raise StateError(f"criterion must be one of {', '.join(CRITERIA)}, got {criterion!r}")
    if not 0 < confidence < 1:
        raise StateError(f"confidence must be in (0, 1), got {confidence!r}")


def basin_measures(cycle: LimitCycle, directions: Sequence[Mapping[str, float]] | None = None, *,
                   steps: int = BASIN_STEPS, tol: float = 1e-4, criterion: str = "converge", reach: float = 1.0,
                   scan: int = 32, xtol: float = 1e-6, samples: int = 1000,
                   box: float | Mapping[str, float] | None = None, seed: int = 0, confidence: float = 0.95,
                   threads: int = 1, rtol: float = BASIN_TOL, atol: float = BASIN_TOL) -> BasinMeasures:
    """Distances from the gait ``cycle`` to its basin's boundary and the basin's share of a box
    (module docstring).

    ``directions``: mappings coordinate name → component (default: ``±`` each section
    coordinate); ``steps``, ``tol``, ``criterion``: when a walk is inside; ``reach``, ``scan``,
    ``xtol``: how far out, how finely, and to what width (state units) the boundary is sought;
    ``samples`` (0: no size), ``box`` (half-width of the box, one for all section coordinates or
    per name; default from the distances), ``seed``, ``confidence``: the size estimate;
    ``threads``: walks share this many threads (the results do not depend on it); ``rtol``,
    ``atol``: integrator tolerances."""
    _check(steps, scan, samples, threads, reach, xtol, tol, criterion, confidence)
    if cycle.hybrid_system is None:
        raise StateError("the limit cycle does not carry its system: find it with find_fixed_point")
    if cycle.period != 1:
        raise StateError("basin measures are defined here for period-1 gaits")
    if not cycle.stable:
        raise ConvergenceError("the gait is unstable: it has no basin of attraction")
    judge = _Judge(cycle, steps, tol, criterion, rtol, atol, threads)
    names = judge.names
    S = judge.section.coordinates()
    if directions is None:
        labelled = [(f"{sign}{names[i]}", {names[i]: float(f"{sign}1")}) for i in S.tolist() for sign in "+-"]
    else:
        labelled = [(f"d{j + 1}", dict(d)) for j, d in enumerate(directions)]
    dirs = [_unit(d, names) for _, d in labelled]
    charts = [judge.chart(d) for d in dirs]
    lo, hi, why = _distances(judge, dirs, charts, float(reach), scan, float(xtol)) if dirs else ([], [], [])
    dist = []
    for (name, _), d, a, b, reason in zip(labelled, dirs, lo, hi, why):
        found = math.isfinite(b)
        dist.append({"name": name, "direction": {names[i]: float(d[i]) for i in np.flatnonzero(d).tolist()},
                     "distance": float(0.5 * (a + b)) if found else None, "inside": float(a),
                     "outside": float(b) if found else None, "reason": reason, "reach": float(reach)})
    size = None
    if isinstance(box, Mapping):
        stray = [nm for nm in box if nm not in [names[i] for i in S.tolist()]]
        if stray:
            raise StateError(f"box: {', '.join(map(repr, stray))} not section coordinates; section coordinates: "
                             f"{', '.join(names[i] for i in S.tolist())}")
    if samples:
        half = np.array([_half(box, names[i], i, dist, reach) for i in S.tolist()])
        size = _size(judge, S, half, samples, seed, confidence)
    return BasinMeasures(distances=dist, size=size, criterion=criterion, steps=steps, tol=tol,
                         fixed_point=[float(v) for v in judge.xs], section_coordinates=[names[i] for i in S.tolist()])


def _half(box: float | Mapping[str, float] | None, name: str, i: int, dist: list[dict[str, Any]],
          reach: float) -> float:
    """The box's half-width along section coordinate ``name``."""
    if box is None:
        along = [r["distance"] for r in dist if r["distance"] is not None and list(r["direction"]) == [name]]
        return max(along) if along else float(reach)
    h = box.get(name) if isinstance(box, Mapping) else box
    if h is None:
        raise StateError(f"box: no half-width for section coordinate {name!r}")
    if not (math.isfinite(float(h)) and float(h) > 0):
        raise StateError(f"box: the half-width of {name!r} must be a finite number > 0, got {h!r}")
    return float(h)


__all__ = ["CRITERIA", "BasinMeasures", "basin_measures"]
