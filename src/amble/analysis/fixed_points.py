"""Fixed-point branches and maps: the period-1 gait continued along one parameter or over a grid
of two, with step time and Floquet multipliers (the ``fixed-point`` kind of :func:`amble.sweep`).

Inside a chunk the points are solved in order, warm-started: the fixed point of the previous point seeds the next
(Newton from a nearby solution converges in a few iterations and stays on the same branch). A
resumed chunk is seeded from the last converged row stored before it, read back exactly, so a
resumed sweep equals an uninterrupted one byte for byte (:mod:`amble.analysis.store`).

Units: angles in rad, angular velocities in rad/s, times in s; parameters in the model's units.
"""

from __future__ import annotations

import json
import os
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from ..backend.kernels import compiled
from ..errors import AmbleError, StateError
from .defaults import FIXED_POINT_TOL, RESIDUAL_TOL
from .doubling import period_doubling
from .runner import chunks, sweep_values
from .store import ResultStore, SweepResult, state_columns
from .sweep_runner import RunOptions, deprecated, point_key, prepared, run_sweep, seed_before

if TYPE_CHECKING:  # a compiled system (amble.backend.compiled) serves too, without SymPy
    from ..modelling.hybrid import HybridSystem


def _fp_columns(pnames: Sequence[str], snames: Sequence[str]) -> dict[str, str]:
    return {"i": "int", "j": "int", **dict.fromkeys(pnames, "float"), "status": "str", "reason": "str",
            **dict.fromkeys(state_columns(snames), "float"), "step_time": "float", "max_modulus": "float",
            "moduli": "json", "multipliers": "json", "stable": "bool", "residual": "float", "seeded": "bool",
            "branch": "int", "branch_break": "str"}


def _first_line(e: Exception) -> str:
    return f"{type(e).__name__}: {str(e).splitlines()[0] if str(e) else ''}"


def _fp_task(system: HybridSystem, base: dict[str, float], pnames: list[str], points: list[tuple[int, int, tuple]],
             seed: tuple[list[float], dict[str, float], int] | None, kw: dict[str, Any],
             flat: list[int] | None = None) -> list[dict[str, Any]]:
    """One chunk: each point continued from the last gait before it (its neighbour) along the
    branch (:func:`continue_fixed_point`: predictor, step control, branch jumps refused), keeping
    that gait's branch id; a point that cannot be continued is searched afresh from the model's
    guess and, if found, starts a new branch (id: its index in the grid), with ``branch_break``
    saying why the old branch did not reach it. ``seed``: (gait, its parameters, its branch)."""
    from .poincare import continue_fixed_point, find_fixed_point

    snames = compiled(system).meta["state_names"][compiled(system).meta["modes"][0]]
    prev = None if seed is None else (np.asarray(seed[0], float), dict(seed[1]), int(seed[2]))
    out = []
    for n, (i, j, vals) in enumerate(points):
        params = {**base, **dict(zip(pnames, vals))}
        row: dict[str, Any] = {"i": i, "j": j, **dict(zip(pnames, vals))}
        lc, broke, reason, branch = None, "", "", -1
        if prev is not None:
            try:
                lc = continue_fixed_point(system, prev[0], prev[1], params, **kw)
                branch = prev[2]
            except AmbleError as e:
                broke = _first_line(e)
        if lc is None:
            try:
                lc = find_fixed_point(system, None, params=params, collocation=False, **kw)
                branch = flat[n] if flat is not None else i
            except AmbleError as e:
                reason = broke or _first_line(e)
        if lc is None:
            row.update(status="failed", reason=reason, seeded=prev is not None, branch_break=broke)
        else:
            mods = np.abs(lc.multipliers)
            row.update(status="ok", reason="", step_time=lc.step_time, max_modulus=float(mods.max()),
                       moduli=json.dumps([float(m) for m in mods]),
                       multipliers=json.dumps([[float(m.real), float(m.imag)] for m in lc.multipliers]),
                       stable=lc.stable, residual=lc.residual, seeded=not broke and prev is not None,
                       branch=branch, branch_break=broke)
            row.update({c: float(v) for c, v in zip(state_columns(snames), lc.fixed_point)})
            prev = (lc.fixed_point, params, branch)
        out.append(row)
    return out


def _seed_row(store: ResultStore, keys: list[list[tuple]], grp: Sequence[int], first: int,
              base: dict[str, float], pnames: list[str], snames: Sequence[str]
              ) -> tuple[list[float], dict[str, float], int] | None:
    """The last converged row stored before point ``first`` of its group, read back exactly: its
    gait, its parameters and its branch (a row from before branch ids: its own index)."""
    x = seed_before(store, keys, grp, first, snames)
    if x is None:
        return None
    for g in reversed(list(grp[:grp.index(first)])):
        r = store.rows.get(keys[g][0])
        if r is not None and r["status"] == "ok":
            b = r.get("branch", "")
            return x, {**base, **{nm: float(r[nm]) for nm in pnames}}, int(b) if b not in ("", None) else g
    return None


def _fp_sweep(system: HybridSystem, pnames: list[str], grid: list[tuple[int, int, tuple]],
              groups: list[list[int]], *, params: Mapping[str, float] | None, warm_start: bool, kind: str,
              fp_kw: dict[str, Any], run: RunOptions) -> SweepResult:
    _, _, snames = prepared(system, params, pnames)
    keys = [[point_key(i, j, *vals)] for i, j, vals in grid]

    def make_task(pts: list[int], grp: Sequence[int], store: ResultStore) -> tuple:
        # warm start: continued from the last converged point before this one in the chunk, as stored (exact)
        seed = _seed_row(store, keys, grp, pts[0], dict(params or {}), pnames, snames) if warm_start else None
        return (system, dict(params or {}), pnames, [grid[g] for g in pts], seed, fp_kw, list(pts))

    return run_sweep(kind=kind, columns=_fp_columns(pnames, snames), key=["i", "j", *pnames], keys=keys,
                     groups=groups, make_task=make_task, fn=_fp_task, split=None if warm_start else 1,
                     params=pnames, state_names=snames, run=run)


def default_chunk(points: int) -> int:
    """Values per task of a branch of ``points`` values: about a sixteenth of the branch, at
    least 8 and at most 32.

    A function of the grid only (never of the workers), so a result does not depend on where it
    ran. Sixteen or more tasks keep two to four workers busy to the end (seven tasks of 32 values,
    a 200-point branch before, left one of two workers idle for most of a task); 8 values or
    more keep the warm start (each point continued from the one before) doing most of the work."""
    return min(32, max(8, -(-int(points) // 16)))


def fixed_point_kind(system: HybridSystem, over: Mapping[str, np.ndarray], params: Mapping[str, float] | None,
                     run: RunOptions, *, warm_start: bool = True, chunk: int | None = None,
                     tol: float = RESIDUAL_TOL) -> SweepResult:
    """The ``fixed-point`` kind of :func:`amble.sweep`: the period-1 fixed point of the return map
    at every value of one parameter (a branch), or on the grid of two (a map).

    One parameter: each chunk of ``chunk`` consecutive values is one task (default
    :func:`default_chunk`: a sixteenth of the branch, 8 to 32 values); inside
    it the gait at one value is continued along its branch to the next (``warm_start=False``:
    every point from the model's guess). A point the branch does not reach is searched from the
    model's guess and, if found, starts a new branch; one with no gait is recorded ``failed`` with
    the reason (the branch folds, the walker fell, the branch was lost), and the next point is
    continued from the last converged one.
    Two parameters ``{a: …, b: …}``: one task per value of ``a`` (``i``), warm-started along ``b``
    (``j``); ``chunk`` does not apply. ``tol``: the residual ``|P(x) − x|∞`` of a fixed point.
    Rows: ``i`` (index of the first parameter's value), ``j`` (of the second; 0 for a branch), the
    parameter values, ``status``, ``reason``, fixed point ``x_<state>``, ``step_time`` (s),
    multipliers (JSON ``[[re, im], ...]``) and their moduli, ``max_modulus``, ``stable``,
    ``residual``, ``seeded`` (continued from the point before), ``branch`` (the grid index of the
    point where its branch was first found) and ``branch_break`` (why the branch of the point
    before did not reach this one; empty when it did). ``SweepResult.kind``: ``fixed-point`` or
    ``fixed-point-map``.
    """
    fp_kw = {"rtol": run.rtol, "atol": run.atol, "tol": tol}
    names = list(over)
    if len(names) == 1:
        size = default_chunk(len(over[names[0]])) if chunk is None else chunk
        if size < 1:
            raise StateError(f"chunk must be at least 1, got {size}")
        grid = [(i, 0, (float(x),)) for i, x in enumerate(over[names[0]])]
        groups = chunks(list(range(len(grid))), size)
        kind = "fixed-point"
    else:
        if chunk is not None:
            raise StateError("chunk applies to a branch of one parameter: a map's task is one row of its grid")
        va, vb = over[names[0]], over[names[1]]
        grid = [(i, j, (float(x), float(y))) for i, x in enumerate(va) for j, y in enumerate(vb)]
        groups = [list(range(i * len(vb), (i + 1) * len(vb))) for i in range(len(va))]
        kind = "fixed-point-map"
    return _fp_sweep(system, names, grid, groups, params=params, warm_start=warm_start, kind=kind, fp_kw=fp_kw,
                     run=run)


def _warm_start(continuation: bool | None, warm_start: bool) -> bool:
    """``warm_start``, or the value of its old name ``continuation`` (with a warning)."""
    if continuation is None:
        return warm_start
    deprecated("the keyword continuation=", "warm_start=", stacklevel=4)
    return bool(continuation)


def sweep_fixed_points(
    system: HybridSystem,
    param: str,
    values: Sequence[float],
    *,
    params: Mapping[str, float] | None = None,
    warm_start: bool = True,
    continuation: bool | None = None,
    chunk: int | None = None,
    out: str | os.PathLike | None = None,
    scheduler: Any = None,
    workers: int | None = None,
    progress: bool = True,
    max_points: int | None = None,
    rtol: float = FIXED_POINT_TOL,
    atol: float = FIXED_POINT_TOL,
    tol: float = RESIDUAL_TOL,
) -> SweepResult:
    """Deprecated: ``amble.sweep(system, "fixed-point", {param: values}, ...)`` (the same rows).
    ``continuation=``: the old name of ``warm_start=``."""
    deprecated("sweep_fixed_points()", 'amble.sweep(system, "fixed-point", {param: values})')
    v = sweep_values(values, param, system)
    return fixed_point_kind(system, {param: v}, params, RunOptions(out, scheduler, workers, progress, max_points,
                                                                   rtol, atol),
                            warm_start=_warm_start(continuation, warm_start), chunk=chunk, tol=tol)


def sweep_fixed_points_2d(
    system: HybridSystem,
    params2: tuple[str, str],
    values: tuple[Sequence[float], Sequence[float]],
    *,
    params: Mapping[str, float] | None = None,
    warm_start: bool = True,
    continuation: bool | None = None,
    out: str | os.PathLike | None = None,
    scheduler: Any = None,
    workers: int | None = None,
    progress: bool = True,
    max_points: int | None = None,
    rtol: float = FIXED_POINT_TOL,
    atol: float = FIXED_POINT_TOL,
    tol: float = RESIDUAL_TOL,
) -> SweepResult:
    """Deprecated: ``amble.sweep(system, "fixed-point", {a: values_a, b: values_b}, ...)`` (the
    same rows). ``continuation=``: the old name of ``warm_start=``."""
    deprecated("sweep_fixed_points_2d()", 'amble.sweep(system, "fixed-point", {a: values_a, b: values_b})')
    a, b = params2
    if a == b:
        raise StateError(f"the two swept parameters must differ, got {a!r} twice")
    over = {a: sweep_values(values[0], a, system), b: sweep_values(values[1], b, system)}
    return fixed_point_kind(system, over, params, RunOptions(out, scheduler, workers, progress, max_points, rtol, atol),
                            warm_start=_warm_start(continuation, warm_start), tol=tol)


__all__ = ["fixed_point_kind", "period_doubling", "sweep_fixed_points", "sweep_fixed_points_2d"]
