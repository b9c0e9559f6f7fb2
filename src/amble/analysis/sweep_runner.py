"""The one pipeline of every sweep kind: store → keys → budget → chunks → execute → compact → filter.

A sweep is a list of *points*, each identified by one or more keys (a fixed-point or
bifurcation point has one, a basin grid row one per cell), cut into *groups* (chunks whose
boundaries depend only on the grid). The pending points of a group, up to the ``max_points``
budget, become one task (or several of at most ``split`` points); a kind supplies only how to
build a task from those points (with the continuation seed read back exactly from the store,
:func:`seed_before`), the task function, and its columns. Only the client process writes the
result file; when every key is present the file is compacted (sorted by key, atomically).
"""

from __future__ import annotations

import os
import warnings
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from ..backend.kernels import compiled
from ..simulation.simulate import parameter_vector
from .defaults import FIXED_POINT_TOL
from .runner import check_params, execute, open_client
from .store import ResultStore, SweepResult, fmt_value, state_from_row

if TYPE_CHECKING:  # a compiled system (amble.backend.compiled) serves too, without SymPy
    from ..modelling.hybrid import HybridSystem

Key = tuple[str, ...]


@dataclass(frozen=True)
class RunOptions:
    """How a sweep runs, the same for every kind: the result file ``out`` (.csv/.parquet, resumed if
    it exists), where its tasks run (``scheduler``: ``None`` local worker processes, ``"synchronous"``
    this process, else a Dask scheduler's address; ``workers``: local processes), the progress bar,
    the budget ``max_points`` (compute at most this many missing keys in this call: a deliberately
    partial run) and the integrator tolerances ``rtol``, ``atol`` (already the kind's default when
    not given)."""

    out: str | os.PathLike | None = None
    scheduler: Any = None
    workers: int | None = None
    progress: bool = True
    max_points: int | None = None
    rtol: float = FIXED_POINT_TOL
    atol: float = FIXED_POINT_TOL


def deprecated(old: str, new: str, stacklevel: int = 3) -> None:
    """Warn that ``old`` is an alias kept for one release: ``new`` replaces it."""
    warnings.warn(f"{old} is deprecated and will be removed in the next release; use {new}",
                  DeprecationWarning, stacklevel=stacklevel)


def prepared(system: HybridSystem, params: Mapping[str, float] | None,
             swept: Sequence[str] = ()) -> tuple[Any, np.ndarray, list[str]]:
    """The compiled kernels (built once here, so workers only load them from the disk cache), the
    parameter vector of ``params`` and the state names of the first mode; ``swept`` must be
    parameters of ``system``."""
    k = compiled(system)
    pvec = parameter_vector(k, params, system)
    check_params(system, swept)
    return k, pvec, list(k.meta["state_names"][k.meta["modes"][0]])


def point_key(*fields: int | float) -> Key:
    """A key: integers (grid indices) as decimal text, floats by ``repr`` (exact)."""
    return tuple(str(f) if isinstance(f, int) else fmt_value(float(f)) for f in fields)


def seed_before(store: ResultStore, keys: Sequence[Sequence[Key]], group: Sequence[int], first: int,
                state_names: Sequence[str], back: int | None = None) -> list[float] | None:
    """Continuation seed of a task starting at point ``first`` of ``group``: the stored state of
    the last ``ok`` point before it (looking back at most ``back`` points), read back exactly."""
    before = list(group[:group.index(first)])
    if back is not None:
        before = before[len(before) - back:] if back else []
    for g in reversed(before):
        r = store.rows.get(keys[g][0])
        if r is not None and r["status"] == "ok":
            x = state_from_row(r, state_names)
            return None if x is None else x.tolist()
    return None


def run_sweep(*, kind: str, columns: Mapping[str, str], key: Sequence[str], keys: Sequence[Sequence[Key]],
              groups: Sequence[Sequence[int]], make_task: Callable[[list[int], Sequence[int], ResultStore], tuple],
              fn: Callable[..., list[dict[str, Any]]], run: RunOptions,
              split: int | Callable[[int], int] | None = None,
              params: Sequence[str] = (), state_names: Sequence[str] = (), threads: int = 1,
              ordered: bool = False) -> SweepResult:
    """Run the pending points of a sweep and return every stored row of its grid, sorted by key.

    ``columns``: column name → type (:data:`amble.analysis.store.COLUMN_TYPES`), in file order;
    ``key``: the key columns; ``keys[g]``: the keys of point ``g`` (it is pending while one is
    missing); ``groups``: the chunks of point indices. The pending points of a group, cut to the
    budget (``max_points`` keys) and into runs of ``split`` points (default: all; a callable:
    ``split(n)`` points for the next task while ``n`` points are left to schedule), become the
    task ``make_task(points, group, store)``, run as ``fn(*task)``. ``computed`` / ``reused``
    of the result count keys. ``threads``: with ``scheduler='synchronous'``, tasks run this many
    at a time on threads of this process (:func:`amble.analysis.runner.execute`); the journal's
    rows are then in the order tasks finish, the compacted file sorted as always. ``ordered``:
    the keys, point by point, are already in key order (a grid listed row by row), so the rows are
    taken in that order instead of sorted (the same rows, in the same order). ``run``: the file,
    scheduler, workers, progress bar and budget (:class:`RunOptions`).
    """
    out, max_points = run.out, run.max_points
    # the column types let the store ignore a damaged row instead of counting it ok
    with ResultStore(out, dict(columns), key) as store:  # holds the file's lock until the end
        flat = [kk for ks in keys for kk in ks]
        fresh = not store.rows  # nothing stored yet (no file, or a new one): every point is pending
        if not fresh:
            store.check_keys(flat)
        per = max(1, max((len(ks) for ks in keys), default=1))  # keys per point (a basin row: its cells)
        missing = len(flat) if fresh else sum(1 for kk in flat if not store.has(kk))
        pending = [True] * len(keys) if fresh else [not all(store.has(kk) for kk in ks) for ks in keys]
        pending_points = sum(pending)
        budget = pending_points if max_points is None else max(0, min(pending_points, int(max_points) // per))
        tasks, n_sched = [], 0
        for grp in groups:
            pts = [g for g in grp if pending[g]]
            at = 0
            while at < len(pts) and n_sched < budget:
                step = split(budget - n_sched) if callable(split) else split or len(pts)
                part = pts[at:at + max(1, step)][: budget - n_sched]
                tasks.append(make_task(part, grp, store))
                at += len(part)
                n_sched += len(part)
        computed = n_sched * per
        client, close = open_client(run.scheduler, run.workers) if tasks else (None, lambda: None)
        try:
            execute(client, fn, tasks, store, run.progress, computed, kind, threads=threads)
        finally:
            close()
        if ordered:  # one pass over the grid: its rows, in key order
            rows = [r for r in map(store.rows.get, flat) if r is not None]
            inside = len(rows)
        else:
            rows = store.sorted_rows()  # sorted once, for the file and the result
            inside = sum(1 for kk in flat if kk in store.rows)
        complete = inside == len(flat)
        if complete:
            # the file keeps every stored row: ``rows`` are all of them unless some lie outside the grid
            store.compact(rows if inside == len(store.rows) else store.sorted_rows())
        if not ordered and inside != len(store.rows):  # rows outside the grid: left out
            wanted = set(flat)
            rows = [r for r in rows if tuple(r[c] for c in key) in wanted]
        return SweepResult(kind=kind, params=list(params), rows=rows, path=str(out) if out else None, complete=complete,
                           computed=computed, reused=len(flat) - missing, state_names=list(state_names),
                           types=dict(columns))


__all__ = ["RunOptions", "deprecated", "point_key", "prepared", "run_sweep", "seed_before"]
