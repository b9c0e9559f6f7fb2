"""Basins of attraction (the ``basin`` kind of :func:`amble.sweep`): which initial post-impact
states of a grid walk into the period-1 gait.

Each cell of a grid over two coordinates of the post-impact state is walked with the compiled
run loop (no recording) for a bounded number of footfalls and classified as ``converged``
(reached the fixed point), ``fell``, ``not converged`` (kept walking elsewhere) or ``failed``
(any other run outcome, with its reason). Cells are independent, so a resumed basin equals an
uninterrupted one exactly; one Dask task covers a few grid rows.

Units: angles in rad, angular velocities in rad/s; parameters in the model's units.
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from operator import itemgetter
from typing import TYPE_CHECKING, Any

import numpy as np

from ..backend.abi import CODE
from ..backend.kernels import compiled
from ..errors import ConvergenceError, StateError
from ..simulation.engine import Options, walk_many
from .basin_setup import setup
from .cells import TextRows, fmt_floats, fmt_ints
from .defaults import BASIN_STEPS, BASIN_TOL
from .runner import sweep_values
from .section import Section
from .sweep_runner import RunOptions, deprecated, prepared, run_sweep

if TYPE_CHECKING:  # a compiled system (amble.backend.compiled) serves too, without SymPy
    from ..modelling.hybrid import HybridSystem

#: Basin outcome categories (index = code stored in ``BasinResult.outcome``).
BASIN_LABELS = ("converged", "fell", "not converged", "failed")
#: Columns of a basin result file besides the two axis columns, which are named after the chosen
#: coordinates (e.g. ``i, j, stance, stance_dot, outcome, ...``), and their types
#: (:data:`amble.analysis.store.COLUMN_TYPES`). A file of another pair of coordinates, or of the
#: older format whose axis columns were ``a, b``, has other columns and is refused on resume.
BASIN_COLUMNS = {"i": "int", "j": "int", "outcome": "str", "reason": "str", "steps": "int", "distance": "float"}


def basin_columns(x_names: Sequence[str]) -> dict[str, str]:
    """The columns of a basin over coordinates ``x_names``, in file order."""
    cols = {"i": "int", "j": "int", x_names[0]: "float", x_names[1]: "float"}
    cols.update({k: v for k, v in BASIN_COLUMNS.items() if k not in ("i", "j")})
    return cols


@dataclass
class BasinResult:
    """Basin of attraction on a grid of two initial-condition coordinates.

    ``outcome[i, j]`` is an index into ``labels`` for initial values ``a_values[i]``,
    ``b_values[j]``; ``steps[i, j]`` footfalls taken; ``distance[i, j]`` final
    ``|x − x*|∞`` (NaN if the walk did not complete); ``reasons[i, j]`` why a walk ended early
    (``""`` when it did not, e.g. ``"fell"``, ``"integrator_failure"``). ``computed``: cells
    computed by this call (the others were read back from the result file).
    """

    names: tuple[str, str]
    a_values: np.ndarray
    b_values: np.ndarray
    outcome: np.ndarray
    steps: np.ndarray
    distance: np.ndarray
    fixed_point: np.ndarray
    labels: tuple[str, ...] = BASIN_LABELS
    path: str | None = None
    computed: int = 0
    state_names: list[str] = field(default_factory=list)
    reasons: np.ndarray | None = None

    def counts(self) -> dict[str, int]:
        return {lab: int(np.sum(self.outcome == c)) for c, lab in enumerate(self.labels)}

def _embed(k: Any, p: np.ndarray, section: tuple | None, idx: Sequence[int], S: Sequence[int]
           ) -> Callable[[float, float, np.ndarray], np.ndarray]:
    """The default map (a, b) → full state: the two values in the base state's section coordinates,
    the rest of the state from the section (:meth:`Section.project`)."""
    sec = None if section is None else Section(k, p, *section)

    def to_state(a: float, b: float, base: np.ndarray) -> np.ndarray:
        x = base.copy()
        x[idx[0]], x[idx[1]] = a, b
        return x if sec is None else sec.project(x, S)

    return to_state


def _basin_task(system: HybridSystem, pvec: list[float], rows: list[tuple[int, float]], b_values: list[float],
                base: list[float], fixed: list[float], to_state: Callable | None, steps: int, check_every: int,
                tol: float, rtol: float, atol: float, x_names: Sequence[str], section: tuple | None = None,
                threads: int = 1) -> TextRows:
    """One or more grid rows: walk each cell with the compiled run loop, no recording; the rows
    of the result file, already as text (:class:`~amble.analysis.cells.TextRows`).

    ``to_state`` ``None``: cells are put on the section (``section``: transition, time, pre-impact
    state and the section coordinates; built here, in the worker, from the compiled kernels).
    Python work per cell is kept to a few vectorised passes over the task's block: the GIL it
    holds is what keeps threads (and a Dask client receiving rows) from scaling with cores."""
    k = compiled(system, derivatives=section is not None)
    mi = 0
    n = k.meta["nx"][mi]
    p = np.asarray(pvec, float)
    b0 = np.asarray(base, float)
    opts = Options(rtol=rtol, atol=atol, max_step_time=system.max_step_time)
    nb = len(b_values)
    ii = np.repeat(np.array([i for i, _ in rows], dtype=np.int64), nb)  # the cells, row by row
    aa = np.repeat(np.array([a for _, a in rows], dtype=float), nb)
    bb = np.tile(np.asarray(b_values, dtype=float), len(rows))
    m = len(ii)
    x0 = np.full((m, n), np.nan)
    why = [""] * m  # why a cell has no initial state
    if to_state is None and section is not None:
        # the default embedding on the section: every cell's Newton solve in one compiled call
        # (the GIL released, shared by the threads), not one Python iteration per cell
        idx = [list(k.meta["state_names"][k.meta["modes"][mi]]).index(nm) for nm in x_names]
        raw = np.tile(b0, (m, 1))
        raw[:, idx[0]], raw[:, idx[1]] = aa, bb
        x0, off = Section(k, p, *section[:3]).project_array(raw, section[3], threads=threads)
        for c in np.flatnonzero(off).tolist():  # no state of the section has these coordinates
            why[c] = "off the section"
        # a NaN or ±inf anywhere (or entries near 1e308) makes the sum non-finite
        bad = ~np.isfinite(x0.sum(axis=1))
    else:
        if to_state is None:
            idx = [list(k.meta["state_names"][k.meta["modes"][mi]]).index(nm) for nm in x_names]
            to_state = _embed(k, p, None, idx, [])
        bad = np.zeros(m, dtype=bool)
        for c, (a, b) in enumerate(zip(aa.tolist(), bb.tolist())):
            try:
                x = np.asarray(to_state(a, b, b0), float)
            except ConvergenceError:  # no state of the section has these two coordinates here
                why[c] = "off the section"
                continue
            if x.shape == (n,) and bool(np.all(np.isfinite(x))):
                x0[c] = x
            else:
                bad[c] = True
    for c in np.flatnonzero(bad).tolist():
        why[c] = why[c] or "invalid initial state"
    valid = np.flatnonzero(~bad & np.array([w == "" for w in why], dtype=bool))
    code = np.full(m, 3, dtype=np.int64)  # failed, unless walked
    done = np.zeros(m, dtype=np.int64)
    dist = np.full(m, math.nan)
    if len(valid):
        # every valid cell of the task in one compiled call (amble_walk_batch): the walks and their
        # convergence checks run in C with the GIL released, so threads and workers scale with cores
        walks = walk_many(k, p, mi, x0[valid], np.asarray(fixed, float), steps=steps, check_every=check_every,
                          tol=tol, opts=opts, threads=threads)
        finished = walks["code"] == CODE["STEPS_DONE"]
        fell = np.array([st == "fell" for st in walks["status"]], dtype=bool)
        d = walks["distance"]
        code[valid] = np.where(finished, np.where(d < tol, 0, 2), np.where(fell, 1, 3))
        done[valid], dist[valid] = walks["steps"], d
        for c, st, f in zip(valid.tolist(), walks["status"], finished.tolist()):
            if not f:
                why[c] = st
    # a grid row's i and a, and the j and b of its columns, are the same text in every row: written once
    ti, ta = fmt_ints([i for i, _ in rows]), fmt_floats([a for _, a in rows])
    tj, tb = fmt_ints(range(nb)), fmt_floats(b_values)
    cols = {"i": [t for t in ti for _ in range(nb)], "j": tj * len(rows),
            x_names[0]: [t for t in ta for _ in range(nb)], x_names[1]: tb * len(rows),
            "outcome": [BASIN_LABELS[c] for c in code.tolist()], "reason": why, "steps": fmt_ints(done),
            "distance": fmt_floats(dist)}
    return TextRows(zip(*(cols[c] for c in basin_columns(x_names))))


def _arrays(rows: list[dict[str, str]], shape: tuple[int, int]) -> tuple[np.ndarray, ...]:
    """Outcome codes, footfalls, distances and reasons on the grid from the stored rows (in key
    order: row by row), column by column; cells without a row are −1, 0, NaN and ``""``."""
    outcome = np.full(shape, -1, dtype=int)
    st = np.zeros(shape, dtype=int)
    dist = np.full(shape, math.nan)
    why = np.full(shape, "", dtype=object)
    if not rows:
        return outcome, st, dist, why
    if len(rows) == outcome.size:  # the whole grid, row by row: no indices to read
        at: Any = np.s_[:]
    else:
        at = np.array([int(r["i"]) for r in rows]) * shape[1] + np.array([int(r["j"]) for r in rows])
    label = {lab: c for c, lab in enumerate(BASIN_LABELS)}
    codes, done, far, reasons = zip(*map(itemgetter("outcome", "steps", "distance", "reason"), rows))
    outcome.ravel()[at] = list(map(label.__getitem__, codes))
    st.ravel()[at] = list(map(int, done))
    dist.ravel()[at] = [float(d) if d else math.nan for d in far]
    why.ravel()[at] = reasons
    return outcome, st, dist, why


def basin_kind(system: HybridSystem, over: Mapping[str, np.ndarray], params: Mapping[str, float] | None,
               run: RunOptions, *, base_state: Sequence[float] | None = None,
               to_state: Callable[[float, float, np.ndarray], np.ndarray] | None = None, steps: int = BASIN_STEPS,
               check_every: int = 5, tol: float = 1e-4, rows_per_task: int = 5, threads: int = 1) -> BasinResult:
    """The ``basin`` kind of :func:`amble.sweep`: the basin of attraction of the period-1 gait over
    two post-impact coordinates, ``over = {name_a: values_a, name_b: values_b}``.

    The grid is ``values_a`` × ``values_b`` (row ``i``, column ``j``); the other section coordinates
    come from ``base_state`` (default: the fixed point at ``params``) and the dependent coordinates
    from the section (:meth:`amble.analysis.section.Section.project`: the cell's state lies on the
    post-impact section of the step transition, whatever the model). The two coordinates must chart
    the section together (:class:`StateError` otherwise: e.g. the two angles of a compass gait, tied
    by both feet on the slope). A cell with no section state near the gait is ``failed`` with reason
    ``off the section``. ``to_state(a, b, base) → full state`` overrides the embedding. Each cell
    walks up to ``steps`` footfalls (checked every ``check_every``) and is ``converged`` if
    ``|x − x*|∞ < tol`` (default 1e-4), ``fell`` if a terminal/fall event ended it, ``not converged`` if it
    kept walking elsewhere (another attractor or too slow), ``failed`` for any other run status. One
    Dask task per ``rows_per_task`` grid rows (default 5). ``rtol``/``atol``: integrator tolerances
    (looser than for fixed points: only the outcome category matters here). ``threads``: with
    ``scheduler='synchronous'``, this many tasks run side by side on threads of this process (one
    task's Python work overlaps the others' compiled walks, which release the GIL), or, for a grid
    of one task, its walks share them; on Dask, each task's walks share this many threads of its
    worker. Two threads on two cores walk a map in about half the time; the result does not depend
    on it (each cell is walked whole by one thread; the compacted file is sorted by key). The fixed
    point and the section are found once per system and parameters in a process
    (:mod:`amble.analysis.basin_setup`): another map of the same gait starts walking at once.
    """
    k, pvec, snames = prepared(system, params)
    x_names = tuple(over)
    for nm in x_names:
        if nm not in snames:
            raise StateError(f"unknown coordinate {nm!r}; known: {', '.join(snames)}")
    if len(x_names) != 2:
        raise StateError(f"basin: two different coordinates are needed, got {', '.join(x_names)}")
    if isinstance(threads, bool) or not isinstance(threads, int) or threads < 1:
        raise StateError(f"threads must be an integer ≥ 1, got {threads!r}")
    if steps < 1 or check_every < 1 or rows_per_task < 1:
        raise StateError("need steps ≥ 1, check_every ≥ 1, rows_per_task ≥ 1")
    av, bv = (np.asarray(over[nm], float) for nm in x_names)
    rtol, atol, scheduler = run.rtol, run.atol, run.scheduler
    # the fixed point and the section depend on the system and parameters only: a second map of
    # the same gait in this process reuses them (:mod:`amble.analysis.basin_setup`)
    xs, section = setup(system, params, pvec, x_names, snames, rtol, atol, section=to_state is None)
    base = xs if base_state is None else np.asarray(base_state, float)
    if base.shape != xs.shape:
        raise StateError(f"base_state needs {xs.size} values ({', '.join(snames)})")
    # the cells' keys (as :func:`point_key` writes them), each column's text made once
    ti, tj, ta, tb = fmt_ints(range(len(av))), fmt_ints(range(len(bv))), fmt_floats(av), fmt_floats(bv)
    keys = [[(ti[i], tj[j], ta[i], tb[j]) for j in range(len(bv))] for i in range(len(av))]

    # in this process, with two or more tasks, the threads run whole tasks side by side (the Python
    # part of one overlaps the compiled walks of another); else they share each task's walks
    side_by_side = scheduler == "synchronous" and threads > 1 and len(av) > rows_per_task
    per_task = 1 if side_by_side else threads

    def shrinking(left: int) -> int:
        # side by side, tasks shrink as the grid runs out (at most rows_per_task rows, a
        # (threads + 1)-th of the rows left): rows differ in cost, and a large task started last
        # leaves the other threads idle at the end; smaller still, each task's own set-up (~0.1 ms)
        # costs more than the balance gains (12 rows on 2 threads: 4 + 3 + 2 + 1 + 1 + 1)
        return min(rows_per_task, -(-left // (threads + 1)))

    def make_task(rows: list[int], grp: Sequence[int], store: Any) -> tuple:
        return (system, pvec.tolist(), [(i, float(av[i])) for i in rows], bv.tolist(), base.tolist(), xs.tolist(),
                to_state, steps, check_every, tol, rtol, atol, list(x_names), section, per_task)

    res = run_sweep(kind="basin", columns=basin_columns(x_names), key=["i", "j", *x_names], keys=keys,
                    groups=[list(range(len(av)))], split=shrinking if side_by_side else rows_per_task,
                    make_task=make_task, fn=_basin_task, run=run, params=list(x_names), state_names=snames,
                    threads=threads if side_by_side else 1, ordered=True)  # keys listed row by row: key order
    outcome, st, dist, why = _arrays(res.rows, (len(av), len(bv)))
    return BasinResult(names=tuple(x_names), a_values=av, b_values=bv, outcome=outcome, steps=st, distance=dist,
                       fixed_point=xs, path=str(run.out) if run.out else None, computed=res.computed,
                       state_names=snames, reasons=why)


def basin(
    system: HybridSystem,
    x_names: tuple[str, str],
    ranges: tuple[tuple[float, float], tuple[float, float]],
    n: tuple[int, int] = (100, 100),
    *,
    params: Mapping[str, float] | None = None,
    base_state: Sequence[float] | None = None,
    to_state: Callable[[float, float, np.ndarray], np.ndarray] | None = None,
    steps: int = BASIN_STEPS,
    check_every: int = 5,
    tol: float = 1e-4,
    rows_per_task: int = 5,
    out: str | os.PathLike | None = None,
    scheduler: Any = None,
    workers: int | None = None,
    progress: bool = True,
    max_points: int | None = None,
    rtol: float = BASIN_TOL,
    atol: float = BASIN_TOL,
    threads: int = 1,
) -> BasinResult:
    """Deprecated: ``amble.sweep(system, "basin", {a: np.linspace(*ranges[0], n[0]), b:
    np.linspace(*ranges[1], n[1])}, ...)`` (the same cells)."""
    deprecated("basin()", 'amble.sweep(system, "basin", {a: values_a, b: values_b})')
    if len(set(x_names)) != 2:
        raise StateError(f"basin: two different coordinates are needed, got {', '.join(x_names)}")
    if len(n) != 2 or min(n) < 1:
        raise StateError("need n = (na ≥ 1, nb ≥ 1), steps ≥ 1, check_every ≥ 1, rows_per_task ≥ 1")
    over = {nm: sweep_values(np.linspace(r[0], r[1], int(c)), nm) for nm, r, c in zip(x_names, ranges, n)}
    return basin_kind(system, over, params, RunOptions(out, scheduler, workers, progress, max_points, rtol, atol),
                      base_state=base_state, to_state=to_state, steps=steps, check_every=check_every, tol=tol,
                      rows_per_task=rows_per_task, threads=threads)


__all__ = ["BASIN_COLUMNS", "BASIN_LABELS", "BasinResult", "basin", "basin_columns", "basin_kind"]
