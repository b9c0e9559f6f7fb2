"""Fixed-point branches and maps: the period-1 gait continued along one parameter or over a grid
of two, with step time and Floquet multipliers, and where the branch period-doubles.

Inside a chunk continuation is sequential: the fixed point of the previous point seeds the next
(Newton from a nearby solution converges in a few iterations and stays on the same branch). A
resumed chunk is seeded from the last converged row stored before it, read back exactly, so a
resumed sweep equals an uninterrupted one byte for byte (:mod:`amble.analysis.store`).

Units: angles in rad, angular velocities in rad/s, times in s; parameters in the model's units.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from ..backend.kernels import build
from ..errors import AmbleError, StateError
from .defaults import FIXED_POINT_TOL, RESIDUAL_TOL
from .runner import chunks, sweep_values
from .store import ResultStore, SweepResult, state_columns
from .sweep_runner import compiled, point_key, run_sweep, seed_before

if TYPE_CHECKING:  # a compiled system (amble.backend.compiled) serves too, without SymPy
    from ..modelling.hybrid import HybridSystem


def _fp_columns(pnames: Sequence[str], snames: Sequence[str]) -> dict[str, str]:
    return {"i": "int", "j": "int", **dict.fromkeys(pnames, "float"), "status": "str", "reason": "str",
            **dict.fromkeys(state_columns(snames), "float"), "step_time": "float", "max_modulus": "float",
            "moduli": "json", "multipliers": "json", "stable": "bool", "residual": "float", "seeded": "bool"}


def _fp_task(system: HybridSystem, base: dict[str, float], pnames: list[str], points: list[tuple[int, int, tuple]],
             seed: list[float] | None, kw: dict[str, Any]) -> list[dict[str, Any]]:
    """Continuation along one chunk: each converged fixed point seeds the next point."""
    from .poincare import find_fixed_point

    snames = build(system).meta["state_names"][build(system).meta["modes"][0]]
    guess = None if seed is None else np.asarray(seed, float)
    out = []
    for i, j, vals in points:
        params = {**base, **dict(zip(pnames, vals))}
        row: dict[str, Any] = {"i": i, "j": j, **dict(zip(pnames, vals))}
        lc, reason, seeded = None, "", guess is not None
        attempts = [guess, None] if guess is not None else [None]
        for g in attempts:  # a lost branch is retried from the model's own guess
            try:
                lc = find_fixed_point(system, g, params=params, **kw)
                seeded = g is not None
                break
            except AmbleError as e:
                reason = f"{type(e).__name__}: {str(e).splitlines()[0] if str(e) else ''}"
        if lc is None:
            row.update(status="failed", reason=reason, seeded=seeded)
        else:
            mods = np.abs(lc.multipliers)
            row.update(status="ok", reason="", step_time=lc.step_time, max_modulus=float(mods.max()),
                       moduli=json.dumps([float(m) for m in mods]),
                       multipliers=json.dumps([[float(m.real), float(m.imag)] for m in lc.multipliers]),
                       stable=lc.stable, residual=lc.residual, seeded=seeded)
            row.update({c: float(v) for c, v in zip(state_columns(snames), lc.fixed_point)})
            guess = lc.fixed_point
        out.append(row)
    return out


def _fp_sweep(system: HybridSystem, pnames: list[str], grid: list[tuple[int, int, tuple]],
              groups: list[list[int]], *, params: Mapping[str, float] | None, continuation: bool, kind: str,
              fp_kw: dict[str, Any], **run: Any) -> SweepResult:
    _, _, snames = compiled(system, params, pnames)
    keys = [[point_key(i, j, *vals)] for i, j, vals in grid]

    def make_task(pts: list[int], grp: Sequence[int], store: ResultStore) -> tuple:
        # continuation: seeded by the last converged point before this one in the chunk, as stored (exact)
        seed = seed_before(store, keys, grp, pts[0], snames) if continuation else None
        return (system, dict(params or {}), pnames, [grid[g] for g in pts], seed, fp_kw)

    return run_sweep(kind=kind, columns=_fp_columns(pnames, snames), key=["i", "j", *pnames], keys=keys,
                     groups=groups, make_task=make_task, fn=_fp_task, split=None if continuation else 1,
                     params=pnames, state_names=snames, **run)


def sweep_fixed_points(
    system: HybridSystem,
    param: str,
    values: Sequence[float],
    *,
    params: Mapping[str, float] | None = None,
    continuation: bool = True,
    chunk: int = 32,
    out: str | os.PathLike | None = None,
    scheduler: Any = None,
    workers: int | None = None,
    progress: bool = True,
    max_points: int | None = None,
    rtol: float = FIXED_POINT_TOL,
    atol: float = FIXED_POINT_TOL,
    tol: float = RESIDUAL_TOL,
) -> SweepResult:
    """Fixed-point branch of the return map along ``param`` (1D continuation).

    Each chunk of ``chunk`` consecutive values is one Dask task; inside it the fixed point at
    one value is the Newton guess at the next (``continuation=False``: every point from the
    model's guess). A point that does not converge is recorded ``failed`` with its reason and
    the next point is seeded from the last converged one (then from the model's guess).
    Rows: ``i`` (index in ``values``), ``j`` = 0, the parameter value, ``status``, ``reason``,
    fixed point ``x_<state>``, ``step_time`` (s), multipliers (JSON ``[[re, im], ...]``) and
    their moduli, ``max_modulus``, ``stable``, ``residual``.
    ``out``: result file (.csv/.parquet), resumed if it exists. ``max_points``: compute at most
    this many missing points in this call (a deliberately partial run).
    """
    v = sweep_values(values, param, system)
    if chunk < 1:
        raise StateError(f"chunk must be at least 1, got {chunk}")
    grid = [(i, 0, (float(x),)) for i, x in enumerate(v)]
    groups = chunks(list(range(len(grid))), chunk)
    return _fp_sweep(system, [param], grid, groups, params=params, continuation=continuation, out=out,
                     scheduler=scheduler, workers=workers, progress=progress, max_points=max_points,
                     kind="fixed-point", fp_kw={"rtol": rtol, "atol": atol, "tol": tol})


def sweep_fixed_points_2d(
    system: HybridSystem,
    params2: tuple[str, str],
    values: tuple[Sequence[float], Sequence[float]],
    *,
    params: Mapping[str, float] | None = None,
    continuation: bool = True,
    out: str | os.PathLike | None = None,
    scheduler: Any = None,
    workers: int | None = None,
    progress: bool = True,
    max_points: int | None = None,
    rtol: float = FIXED_POINT_TOL,
    atol: float = FIXED_POINT_TOL,
    tol: float = RESIDUAL_TOL,
) -> SweepResult:
    """Parameter map: fixed points on the grid ``values[0] × values[1]`` of two parameters.

    One Dask task per row ``i`` (first parameter fixed), continuation along the second
    parameter ``j``. Rows as in :func:`sweep_fixed_points` with both indices and values.
    """
    a, b = params2
    if a == b:
        raise StateError(f"the two swept parameters must differ, got {a!r} twice")
    va, vb = sweep_values(values[0], a, system), sweep_values(values[1], b, system)
    grid = [(i, j, (float(x), float(y))) for i, x in enumerate(va) for j, y in enumerate(vb)]
    groups = [list(range(i * len(vb), (i + 1) * len(vb))) for i in range(len(va))]
    return _fp_sweep(system, [a, b], grid, groups, params=params, continuation=continuation, out=out,
                     scheduler=scheduler, workers=workers, progress=progress, max_points=max_points,
                     kind="fixed-point-map", fp_kw={"rtol": rtol, "atol": atol, "tol": tol})


def period_doubling(result: SweepResult) -> float | None:
    """First parameter value where a real multiplier crosses −1 along a 1D branch (linear
    interpolation between the two neighbouring converged points), or ``None``."""
    prev = None
    p = result.params[0]
    for r in result.rows:
        if r["status"] != "ok":
            prev = None
            continue
        mults = json.loads(r["multipliers"])
        real = [re for re, im in mults if abs(im) < 1e-9 * max(1.0, abs(re))]
        lo = min(real) if real else math.inf
        cur = (float(r[p]), lo)
        if prev is not None and math.isfinite(prev[1]) and math.isfinite(lo) and (prev[1] + 1) * (lo + 1) < 0:
            (x0, y0), (x1, y1) = prev, cur
            return x0 + (-1 - y0) * (x1 - x0) / (y1 - y0)
        prev = cur
    return None


__all__ = ["period_doubling", "sweep_fixed_points", "sweep_fixed_points_2d"]
