"""The ``continuation`` kind of :func:`amble.sweep`: branches of gaits traced by pseudo-arclength
(:mod:`amble.analysis.continuation`) written as the rows of a result file.

One row per branch point and one per located bifurcation. Key ``branch, row, i``: ``branch`` 0 is
the period-1 branch, ``branch`` b + 1 the period-doubled branch born at the first flip of branch
b; ``row`` is ``point``, ``fold``, ``flip`` or ``torus`` (a Neimark–Sacker point); ``i`` counts
along the branch (points in the order traced, bifurcations in the order found). Continuation is
sequential and deterministic, so it runs in this process (no Dask) and its rows are written when
the branches are done; a rerun on the same file keeps the stored rows and adds missing ones, and a
file holding another continuation (rows this one does not have, or another start) is refused with
``OutputError``.

Units: the parameter in its own units, states in the model's (rad, rad/s), times in s.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from ..errors import AmbleError, OutputError, StateError
from .branch import Branch, BranchPoint
from .continuation import cascade
from .defaults import FIXED_POINT_TOL, RESIDUAL_TOL
from .multipliers import KINDS, resonance, torus_pair
from .runner import sweep_values
from .store import ResultStore, SweepResult, fmt_value, state_columns
from .sweep_runner import RunOptions, deprecated, prepared

if TYPE_CHECKING:  # a compiled system (amble.backend.compiled) serves too, without SymPy
    from ..modelling.hybrid import HybridSystem


def continuation_columns(param: str, snames: Sequence[str]) -> dict[str, str]:
    """The columns of a continuation result file, in file order, and their types."""
    return {"branch": "int", "row": "str", "i": "int", param: "float", "period": "int", "status": "str",
            "reason": "str", **dict.fromkeys(state_columns(snames), "float"), "step_time": "float",
            "step_times": "json", "orbit": "json", "max_modulus": "float", "moduli": "json", "multipliers": "json",
            "stable": "bool", "residual": "float", "arclength": "float", "test": "float", "direction": "str"}


def _row(b: int, kind: str, i: int, param: str, period: int, pt: BranchPoint, snames: Sequence[str],
         test: float | str = "") -> dict[str, Any]:
    mods = np.abs(pt.multipliers)
    row: dict[str, Any] = {
        "branch": b, "row": kind, "i": i, param: pt.value, "period": period, "status": "ok", "reason": "",
        "step_time": float(np.mean(pt.step_times)), "step_times": json.dumps([float(v) for v in pt.step_times]),
        "orbit": json.dumps(pt.orbit.tolist()), "max_modulus": float(mods.max()),
        "moduli": json.dumps([float(m) for m in mods]),
        "multipliers": json.dumps([[float(m.real), float(m.imag)] for m in pt.multipliers]), "stable": pt.stable,
        "residual": pt.residual, "arclength": pt.s, "test": test}
    row.update({c: float(v) for c, v in zip(state_columns(snames), pt.state)})
    return row


def branch_rows(b: int, br: Branch, snames: Sequence[str]) -> list[dict[str, Any]]:
    """The rows of branch number ``b``: its points, then its bifurcations."""
    rows = [_row(b, "point", i, br.param, br.period, pt, snames) for i, pt in enumerate(br.points)]
    if rows:
        rows[-1]["reason"] = br.end  # why the branch ended, on its last point
    rows += [{**_row(b, bf.kind, i, br.param, br.period, bf.point, snames, bf.test),
              "reason": "" if bf.located else "not located: the nearest branch point", "direction": bf.direction}
             for i, bf in enumerate(br.bifurcations)]
    return rows


def continuation_kind(system: HybridSystem, over: Mapping[str, np.ndarray], params: Mapping[str, float] | None,
                      run: RunOptions, *, steps: int = 50, levels: int = 3, guess: Sequence[float] | None = None,
                      tol: float = RESIDUAL_TOL) -> SweepResult:
    """The ``continuation`` kind of :func:`amble.sweep`: ``over = {param: (start, stop)}``, the
    period-1 gait of ``system`` continued in ``param`` from ``start`` to ``stop`` (either way) by
    pseudo-arclength, following up to ``levels`` − 1 period doublings
    (:func:`~amble.analysis.continuation.cascade`).

    ``steps``: the largest parameter change per continuation step is |stop − start| / steps.
    The gait at ``start`` comes from ``guess`` (default: the model's); ``tol``: the residual
    ``|P(x) − x|∞`` of every point. A branch that cannot be started is one ``failed`` row with the
    reason. Continuation is sequential: it runs in this process (``scheduler``, ``workers`` and
    ``max_points`` do not apply). Rows: see the module docstring and :func:`continuation_columns`;
    the ``reason`` of a branch's last point says why it ended; ``SweepResult.params`` is ``[param]``.
    """
    (param, ends), = over.items()
    if len(ends) != 2:
        raise StateError(f"continuation: give {param!r} its two ends (start, stop), got {len(ends)} values")
    start, stop = (float(e) for e in ends)
    _, _, snames = prepared(system, params, [param])
    cols = continuation_columns(param, snames)
    with ResultStore(run.out, cols, ["branch", "row", "i"]) as store:  # typed: a damaged row is not trusted
        before = len(store.rows)
        try:
            branches = cascade(system, param, start, stop, levels=levels, params=params, guess=guess,
                               max_delta=abs(stop - start) / max(1, steps), rtol=run.rtol, atol=run.atol, tol=tol)
            rows = [r for b, br in enumerate(branches) for r in branch_rows(b, br, snames)]
        except AmbleError as e:
            rows = [{"branch": 0, "row": "point", "i": 0, param: start, "status": "failed",
                     "reason": f"{type(e).__name__}: {str(e).splitlines()[0] if str(e) else ''}"}]
        # a file of another continuation (other range, parameters or model) is refused, not mixed in
        store.check_keys([tuple(fmt_value(r[c]) for c in ("branch", "row", "i")) for r in rows])
        first = store.rows.get(("0", "point", "0"))
        if first is not None and first[param] != fmt_value(start):
            raise OutputError(f"{str(run.out)!r} holds a continuation from {param} = {first[param]}, not {start}; "
                              f"use another file")
        store.append(rows)
        store.compact()
        return SweepResult(kind="continuation", params=[param], rows=store.sorted_rows(),
                          path=str(run.out) if run.out else None, complete=True, computed=len(store.rows) - before,
                          reused=before, state_names=list(snames), types=dict(cols))


def sweep_continuation(
    system: HybridSystem,
    param: str,
    start: float,
    stop: float,
    *,
    params: Mapping[str, float] | None = None,
    guess: Sequence[float] | None = None,
    levels: int = 3,
    steps: int = 50,
    out: str | os.PathLike | None = None,
    progress: bool = True,
    rtol: float = FIXED_POINT_TOL,
    atol: float = FIXED_POINT_TOL,
    tol: float = RESIDUAL_TOL,
) -> SweepResult:
    """Deprecated: ``amble.sweep(system, "continuation", {param: (start, stop)}, ...)`` (the same rows)."""
    deprecated("sweep_continuation()", 'amble.sweep(system, "continuation", {param: (start, stop)})')
    ends = sweep_values([start, stop], param, system)  # finite, inside the parameter's domain
    return continuation_kind(system, {param: ends}, params, RunOptions(out, progress=progress, rtol=rtol, atol=atol),
                             steps=steps, levels=levels, guess=guess, tol=tol)


def bifurcation_rows(result: SweepResult) -> list[dict[str, Any]]:
    """The located folds, flips and torus points of a continuation result: branch, kind,
    period, parameter value, step times, multipliers, direction (stability before → after) and,
    for a torus point, the pair's angle θ (rad), rotation number θ/2π and strong resonance."""
    p = result.params[0]
    out = []
    for r in result.rows:
        if r["row"] not in KINDS or r["status"] != "ok":
            continue
        row = {"branch": int(r["branch"]), "kind": r["row"], "period": int(r["period"]), p: float(r[p]),
               "step_times": json.loads(r["step_times"]), "multipliers": json.loads(r["multipliers"]),
               "direction": r.get("direction", "")}
        if r["row"] == "torus":
            row.update(torus_fields([complex(a, b) for a, b in row["multipliers"]]))
        out.append(row)
    return out


def torus_fields(multipliers: Sequence[complex]) -> dict[str, Any]:
    """A torus point's pair as plain data: ``angle`` θ (rad), ``rotation`` θ/2π, ``resonance``."""
    pair = torus_pair(np.asarray(multipliers, complex))
    if pair is None:
        return {"angle": None, "rotation": None, "resonance": None}
    return {"angle": pair[1], "rotation": pair[1] / (2 * math.pi), "resonance": resonance(pair[1])}


__all__ = ["bifurcation_rows", "branch_rows", "continuation_columns", "continuation_kind", "sweep_continuation",
           "torus_fields"]
