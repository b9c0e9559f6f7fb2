"""Parameter sweeps on Dask: fixed-point branches and maps, bifurcation diagrams, basins of attraction.

Work is cut into *chunks* (a run of consecutive parameter values, one row of a 2D map, one row
of a basin grid); each chunk is one Dask task, so a task amortises its overhead over many
return-map evaluations (~20 µs per compass-gait step) instead of one task per point. Inside a
chunk, continuation is sequential: the fixed point (or last state) of the previous point seeds
the next. Chunk boundaries depend only on the grid and ``chunk`` (never on the number of
workers), so a result does not depend on how many processes computed it.

Result files
------------
Rows go to an **append-only CSV journal** as chunks finish, one ``write`` + ``fsync`` per
chunk, written by the client process only (single writer, no locks). Why CSV rather than
Parquet part files: a row is a few hundred bytes that must be durable the moment it exists;
appending to one text file is atomic enough (a crash leaves at most one torn last line, which
the reader detects by its field count / missing newline and drops), needs no manifest, and is
readable by anything. Every row carries its key (grid indices + parameter values written with
``repr``, which round-trips floats exactly; a file holding points of another grid is refused).
On reading, the first row of each key wins, so an interrupted sweep run again with the same file
recomputes only missing keys, duplicates cannot appear, and seeds read back from the file are
bit-identical to the in-memory ones (the resumed result equals the uninterrupted one byte for
byte). When every requested point is present the file is *compacted*: sorted by key and
atomically replaced (temporary file + ``os.replace``). For ``FILE.parquet`` the journal is
``FILE.parquet.journal.csv``; the Parquet file is written (atomically) at compaction, then the
journal is removed. Resume with the same options (tolerances, ``chunk``, ``transient``...):
they are not part of the key.

Units: angles in rad, angular velocities in rad/s, times in s; parameters in the model's units.
"""

from __future__ import annotations

import csv
import io
import json
import math
import os
import time
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import AmbleError, ParameterError, StateError
from ..hybrid import HybridSystem
from ..kernels import CTX_X, build
from ..simulate import Options, parameter_vector, run

# Run status codes of amble.simulate.run that matter here.
_COMPLETED, _TERMINAL, _FELL = 2, 3, 4
_RUN_STATUS = {1: "end_time", 2: "completed", 3: "terminal", 4: "fell", 5: "zeno", 6: "integrator_failure",
               7: "integrator_failure", 8: "max_events", 9: "singular_mass", 10: "reset_failed"}

#: Basin outcome categories (index = code stored in ``BasinResult.outcome``).
BASIN_LABELS = ("converged", "fell", "not converged", "failed")


# ============================================================================ result store
class ResultStore:
    """Append-only CSV journal of sweep rows keyed by ``key`` columns (see module docstring)."""

    def __init__(self, path: str | os.PathLike | None, columns: Sequence[str], key: Sequence[str]) -> None:
        self.columns = list(columns)
        self.key = list(key)
        self.final: Path | None = Path(path) if path is not None else None
        if self.final is not None and self.final.suffix.lower() not in (".csv", ".parquet"):
            raise StateError(f"result file {str(self.final)!r} must end with .csv or .parquet")
        self.parquet = self.final is not None and self.final.suffix.lower() == ".parquet"
        self.journal = (self.final.with_name(self.final.name + ".journal.csv") if self.parquet else self.final)
        self.rows: dict[tuple[str, ...], dict[str, str]] = {}
        self._load()

    def _load(self) -> None:
        if self.final is None:
            return
        if self.parquet and self.final.exists() and self.final.stat().st_size > 0:
            import pyarrow.parquet as pq

            tab = pq.read_table(self.final)
            if tab.column_names != self.columns:
                raise StateError(f"{str(self.final)!r} holds a different kind of sweep (columns differ)")
            for r in tab.to_pylist():
                self._add({c: "" if r[c] is None else str(r[c]) for c in self.columns})
        if self.journal is None or not self.journal.exists() or self.journal.stat().st_size == 0:
            return
        data = self.journal.read_bytes()
        good = data[: data.rfind(b"\n") + 1]  # a torn last line (killed mid-write) is dropped ...
        if len(good) < len(data):  # ... and cut off, so the next append starts on a fresh line
            with open(self.journal, "r+b") as f:
                f.truncate(len(good))
                os.fsync(f.fileno())
        lines = good.decode().split("\n")[:-1]
        reader = csv.reader(lines)
        header = next(reader, None)
        if header != self.columns:
            raise StateError(f"{str(self.journal)!r} holds a different kind of sweep (columns differ); "
                             "use another file")
        for fields in reader:
            if len(fields) == len(self.columns):
                self._add(dict(zip(self.columns, fields)))

    def _add(self, row: Mapping[str, str]) -> bool:
        k = tuple(row[c] for c in self.key)
        if k in self.rows:
            return False
        self.rows[k] = dict(row)
        return True

    def check_keys(self, wanted: Iterable[tuple[str, ...]]) -> None:
        """Refuse a file holding points outside the requested grid (another sweep's results)."""
        w = set(wanted)
        extra = [k for k in self.rows if k not in w]
        if extra:
            shown = dict(zip(self.key, extra[0]))
            raise StateError(f"{str(self.final)!r} holds {len(extra)} point(s) of another sweep (e.g. {shown}); "
                             "use another file or the same grid")

    def has(self, key: tuple[str, ...]) -> bool:
        return key in self.rows

    def append(self, rows: Iterable[Mapping[str, Any]]) -> None:
        """Add rows (values formatted exactly); durable on return when the store has a file."""
        fresh = []
        for r in rows:
            s = {c: _fmt(r.get(c, "")) for c in self.columns}
            if self._add(s):
                fresh.append(s)
        if self.journal is None or not fresh:
            return
        new = not self.journal.exists() or self.journal.stat().st_size == 0
        buf = io.StringIO()
        w = csv.writer(buf, lineterminator="\n")
        if new:
            w.writerow(self.columns)
        for s in fresh:
            w.writerow([s[c] for c in self.columns])
        with open(self.journal, "a", newline="") as f:
            f.write(buf.getvalue())
            f.flush()
            os.fsync(f.fileno())

    def sorted_rows(self) -> list[dict[str, str]]:
        return [self.rows[k] for k in sorted(self.rows, key=_sort_key)]

    def compact(self) -> None:
        """Rewrite the file sorted by key, atomically (deterministic content for equal results)."""
        if self.final is None:
            return
        rows = self.sorted_rows()
        tmp = self.final.with_name(f".{self.final.name}.{os.getpid()}.tmp")
        if self.parquet:
            import pyarrow as pa
            import pyarrow.parquet as pq

            pq.write_table(pa.table({c: [r[c] for r in rows] for c in self.columns}), tmp)
        else:
            with open(tmp, "w", newline="") as f:
                w = csv.writer(f, lineterminator="\n")
                w.writerow(self.columns)
                for r in rows:
                    w.writerow([r[c] for c in self.columns])
                f.flush()
                os.fsync(f.fileno())
        os.replace(tmp, self.final)
        if self.parquet and self.journal is not None and self.journal.exists():
            self.journal.unlink()


def _fmt(v: Any) -> str:
    if isinstance(v, bool) or v is None:
        return "" if v is None else str(v).lower()
    if isinstance(v, (float, np.floating)):
        return repr(float(v))
    if isinstance(v, (int, np.integer)):
        return str(int(v))
    return str(v)


def _sort_key(k: tuple[str, ...]) -> tuple:
    return tuple(int(x) if x.lstrip("-").isdigit() else x for x in k)


# ============================================================================ Dask execution
class _Serial:
    """In-process stand-in for a Dask client (``scheduler='synchronous'``): runs tasks on submit."""

    class _Done:
        def __init__(self, value: Any) -> None:
            self.value = value

        def result(self) -> Any:
            return self.value

    def submit(self, fn: Callable, *args: Any, **kw: Any) -> Any:
        return self._Done(fn(*args, **kw))

    def scatter(self, obj: Any, broadcast: bool = True) -> Any:
        return obj

    def close(self) -> None:
        pass


def open_client(scheduler: Any = None, workers: int | None = None) -> tuple[Any, Callable[[], None]]:
    """A Dask client and its closer.

    ``scheduler``: ``None`` → a :class:`dask.distributed.LocalCluster` of ``workers`` processes
    (default: CPU count) with one thread each (the compiled integrator holds the GIL);
    ``"synchronous"`` → run in this process (tests, debugging); a ``distributed.Client`` → used
    as is; any other string → address of an existing scheduler.
    """
    if scheduler == "synchronous":
        c = _Serial()
        return c, c.close
    from dask.distributed import Client, LocalCluster

    if isinstance(scheduler, Client):
        return scheduler, lambda: None
    if scheduler:
        try:
            client = Client(scheduler, timeout="10s")
        except (OSError, TimeoutError, ValueError) as e:
            raise StateError(f"cannot connect to the Dask scheduler at {scheduler!r} ({e})") from None
        return client, client.close
    n = workers or os.cpu_count() or 1
    if n < 1:
        raise StateError(f"workers must be at least 1, got {n}")
    cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True, dashboard_address=None)
    client = Client(cluster)

    def close() -> None:
        client.close()
        cluster.close()

    return client, close


def _execute(client: Any, fn: Callable, tasks: list[tuple], store: ResultStore, progress: bool, total: int,
             desc: str) -> None:
    """Submit ``fn(*task)`` for each task; append each returned row list to the store as it lands.

    Every task's first argument is the same :class:`HybridSystem`."""
    if not tasks:
        return
    from tqdm.auto import tqdm

    bar = tqdm(total=total, desc=desc, unit="pt", disable=not progress, leave=False)
    try:
        if isinstance(client, _Serial):
            for t in tasks:
                rows = fn(*t)
                store.append(rows)
                bar.update(len(rows))
            return
        from dask.distributed import as_completed

        # the system (sympy expressions) is shipped and unpickled once per worker, not once per task
        shared = client.scatter(tasks[0][0], broadcast=True, hash=False)
        futures = [client.submit(fn, shared, *t[1:], pure=False) for t in tasks]
        for fut in as_completed(futures):
            rows = fut.result()
            store.append(rows)
            bar.update(len(rows))
    finally:
        bar.close()


# ============================================================================ shared helpers
def _check_param(system: HybridSystem, names: Sequence[str]) -> None:
    known = list(build(system).meta["params"])
    for n in names:
        if n not in known:
            raise ParameterError(f"unknown parameter {n!r}; known: {', '.join(known)}")


def _values(values: Sequence[float], what: str) -> np.ndarray:
    v = np.asarray(values, dtype=float).ravel()
    if v.size == 0:
        raise StateError(f"{what}: no values to sweep")
    if not np.all(np.isfinite(v)):
        raise StateError(f"{what}: values must be finite")
    return v


def _chunks(idx: Sequence[int], size: int) -> list[list[int]]:
    return [list(idx[i:i + size]) for i in range(0, len(idx), size)]


def _status_name(k: Any, st: int, ctx: np.ndarray) -> str:
    if st == _TERMINAL:
        return str(k.meta["transitions"][int(ctx[10])]["terminal"])
    return _RUN_STATUS.get(st, "integrator_failure")


def _state_cols(names: Sequence[str]) -> list[str]:
    return [f"x_{n}" for n in names]


def _state_from_row(row: Mapping[str, str], names: Sequence[str]) -> np.ndarray | None:
    try:
        x = np.array([float(row[c]) for c in _state_cols(names)])
    except (KeyError, ValueError):
        return None
    return x if np.all(np.isfinite(x)) else None


@dataclass
class SweepResult:
    """Rows of a finished (or partial) sweep, sorted by key; values as written in the file (str)."""

    kind: str
    params: list[str]
    rows: list[dict[str, str]]
    path: str | None
    complete: bool
    computed: int
    reused: int
    state_names: list[str] = field(default_factory=list)

    def column(self, name: str) -> np.ndarray:
        """A numeric column (NaN where empty)."""
        return np.array([float(r[name]) if r[name] not in ("", "nan") else math.nan for r in self.rows])

    def ok(self) -> np.ndarray:
        return np.array([r["status"] == "ok" for r in self.rows])

    def counts(self) -> dict[str, int]:
        ok = int(self.ok().sum())
        return {"ok": ok, "failed": len(self.rows) - ok}


# ============================================================================ fixed points
def _fp_columns(pnames: Sequence[str], snames: Sequence[str]) -> list[str]:
    return (["i", "j"] + list(pnames) + ["status", "reason"] + _state_cols(snames)
            + ["step_time", "max_modulus", "moduli", "multipliers", "stable", "residual", "seeded"])


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
            row.update({c: float(v) for c, v in zip(_state_cols(snames), lc.fixed_point)})
            guess = lc.fixed_point
        out.append(row)
    return out


def _fp_sweep(system: HybridSystem, pnames: list[str], grid: list[tuple[int, int, tuple]],
              groups: list[list[int]], *, params: Mapping[str, float] | None, continuation: bool, out: Any,
              scheduler: Any, workers: int | None, progress: bool, max_points: int | None,
              kind: str, fp_kw: dict[str, Any]) -> SweepResult:
    k = build(system)  # compile once here, so workers only load from the disk cache
    parameter_vector(k, params)
    _check_param(system, pnames)
    snames = k.meta["state_names"][k.meta["modes"][0]]
    cols = _fp_columns(pnames, snames)
    store = ResultStore(out, cols, ["i", "j", *pnames])
    keyof = [(str(i), str(j), *(_fmt(float(x)) for x in vals)) for i, j, vals in grid]
    store.check_keys(keyof)
    total = sum(1 for key in keyof if not store.has(key))
    budget = total if max_points is None else max(0, min(total, int(max_points)))
    tasks, n_sched = [], 0
    for grp in groups:
        pts = [g for g in grp if not store.has(keyof[g])]
        if not continuation:
            pts_chunks = [[g] for g in pts]
        else:
            pts_chunks = [pts] if pts else []
        for pc in pts_chunks:
            if n_sched >= budget:
                break
            pc = pc[: budget - n_sched]
            seed = None
            if continuation:  # last converged point before this one in the chunk, as stored (exact)
                first = grp.index(pc[0])
                for g in reversed(grp[:first]):
                    r = store.rows.get(keyof[g])
                    if r is not None and r["status"] == "ok":
                        x = _state_from_row(r, snames)
                        seed = None if x is None else x.tolist()
                        break
            tasks.append((system, dict(params or {}), pnames, [grid[g] for g in pc], seed, fp_kw))
            n_sched += len(pc)
    client, close = open_client(scheduler, workers) if tasks else (None, lambda: None)
    try:
        _execute(client, _fp_task, tasks, store, progress, n_sched, kind)
    finally:
        close()
    complete = all(store.has(key) for key in keyof)
    if complete:
        store.compact()
    wanted = set(keyof)
    rows = [r for r in store.sorted_rows() if (r["i"], r["j"], *(r[p] for p in pnames)) in wanted]
    return SweepResult(kind=kind, params=pnames, rows=rows, path=str(out) if out else None, complete=complete,
                       computed=n_sched, reused=len(keyof) - total, state_names=list(snames))


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
    rtol: float = 1e-12,
    atol: float = 1e-12,
    tol: float = 1e-10,
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
    v = _values(values, param)
    if chunk < 1:
        raise StateError(f"chunk must be at least 1, got {chunk}")
    grid = [(i, 0, (float(x),)) for i, x in enumerate(v)]
    groups = _chunks(list(range(len(grid))), chunk)
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
    rtol: float = 1e-12,
    atol: float = 1e-12,
    tol: float = 1e-10,
) -> SweepResult:
    """Parameter map: fixed points on the grid ``values[0] × values[1]`` of two parameters.

    One Dask task per row ``i`` (first parameter fixed), continuation along the second
    parameter ``j``. Rows as in :func:`sweep_fixed_points` with both indices and values.
    """
    a, b = params2
    if a == b:
        raise StateError(f"the two swept parameters must differ, got {a!r} twice")
    va, vb = _values(values[0], a), _values(values[1], b)
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


# ============================================================================ bifurcation
def _bif_columns(param: str, snames: Sequence[str]) -> list[str]:
    return ["i", param, "status", "reason", "coordinate", "iterates", "step_times", "period"] + _state_cols(snames)


def _period(vals: Sequence[float], tol: float) -> int:
    """Smallest p ≤ len/2 with v[n+p] ≈ v[n] for all n, else 0 (aperiodic / chaotic).

    A period-1 orbit approached slowly (a multiplier near −1 just before the flip) alternates
    with a shrinking amplitude and would pass as period 2: if the step-to-step differences
    shrink by half or more over the kept iterates, it is reported as period 1."""
    v = np.asarray(vals, float)
    for p in range(1, len(v) // 2 + 1):
        if np.all(np.abs(v[p:] - v[:-p]) < tol):
            d = np.abs(np.diff(v))
            if p > 1 and d.size >= 2 and d[-1] < 0.5 * d[0]:
                return 1
            return p
    return 0


def _bif_task(system: HybridSystem, base: dict[str, float], param: str, points: list[tuple[int, float]],
              seed: list[float] | None, coord: int, transient: int, keep: int, rtol: float, atol: float,
              period_tol: float) -> list[dict[str, Any]]:
    """Iterate the return map at each value of a chunk, starting from the previous value's last state."""
    from .poincare import default_guess, find_fixed_point

    k = build(system)
    mode = k.meta["modes"][0]
    snames = k.meta["state_names"][mode]
    mi = k.mode_index(mode)
    n = k.meta["nx"][mi]
    opts = Options(rtol=rtol, atol=atol, max_step_time=getattr(system, "max_step_time", 0.0) or 0.0)
    x = None if seed is None else np.asarray(seed, float)
    out = []
    for i, val in points:
        params = {**base, param: val}
        p = parameter_vector(k, params)
        if x is not None:  # the carried state must sit on the section of the new parameters
            x = on_section(snames, dict(zip(k.meta["params"], p.tolist())), x)
        row: dict[str, Any] = {"i": i, param: val, "coordinate": snames[coord]}
        x0 = x
        if x0 is None:  # no state to carry: start on the period-1 fixed point (it exists past the flip)
            try:
                x0 = find_fixed_point(system, params=params, rtol=rtol, atol=atol, tol=1e-9).fixed_point
            except AmbleError:
                try:
                    x0 = np.asarray(default_guess(system, params), float)
                except AmbleError:
                    x0 = np.asarray(system.fixed_point_guess or system.default_start[mode], float)
        st, ctx, _ = run(k, p, mi, x0, steps=transient, opts=opts) if transient > 0 else (_COMPLETED, None, None)
        kept, times, fail = [], [], ""
        if st != _COMPLETED:
            fail = f"{_status_name(k, st, ctx)} during the transient"
        else:
            y = x0 if ctx is None else ctx[CTX_X:CTX_X + n].copy()
            for _ in range(keep):
                st, ctx, _ = run(k, p, mi, y, steps=1, opts=opts)
                if st != _COMPLETED or int(ctx[1]) != mi:
                    fail = f"{_status_name(k, st, ctx)} after {transient + len(kept)} steps"
                    break
                y = ctx[CTX_X:CTX_X + n].copy()
                kept.append(float(y[coord]))
                times.append(float(ctx[0]))
        if fail:
            row.update(status="failed", reason=fail, iterates=json.dumps(kept), step_times=json.dumps(times),
                       period="")
            x = None  # the walker fell: the next value starts from the model's guess again
        else:
            row.update(status="ok", reason="", iterates=json.dumps(kept), step_times=json.dumps(times),
                       period=_period(kept, period_tol))
            row.update({c: float(v) for c, v in zip(_state_cols(snames), y)})
            x = y
        out.append(row)
    return out


def bifurcation(
    system: HybridSystem,
    param: str,
    values: Sequence[float],
    *,
    params: Mapping[str, float] | None = None,
    coordinate: str | int = 0,
    transient: int = 300,
    keep: int = 64,
    chunk: int = 16,
    out: str | os.PathLike | None = None,
    scheduler: Any = None,
    workers: int | None = None,
    progress: bool = True,
    max_points: int | None = None,
    rtol: float = 1e-10,
    atol: float = 1e-10,
    period_tol: float = 1e-6,
) -> SweepResult:
    """Bifurcation diagram: post-transient return-map iterates of one coordinate along ``param``.

    At each value the walker takes ``transient`` steps from the previous value's last
    post-impact state, then ``keep`` more steps whose post-impact ``coordinate`` (name or state index; default the
    first, the stance angle of a walker, rad) is kept. A chunk's first value starts on its
    period-1 fixed point when one is found (else the model's guess walked in); a carried state
    is first put on the new section (:func:`on_section`). ``period`` in a row: smallest p with
    iterates repeating within ``period_tol`` (0 = no period found: chaos or slow transient).
    A value where the walker falls is recorded ``failed`` with the reason.
    """
    v = _values(values, param)
    k = build(system)
    parameter_vector(k, params)
    _check_param(system, [param])
    snames = k.meta["state_names"][k.meta["modes"][0]]
    if isinstance(coordinate, str):
        if coordinate not in snames:
            raise StateError(f"unknown coordinate {coordinate!r}; known: {', '.join(snames)}")
        coord = snames.index(coordinate)
    else:
        coord = int(coordinate)
        if not 0 <= coord < len(snames):
            raise StateError(f"coordinate index {coord} out of range 0..{len(snames) - 1}")
    if transient < 0 or keep < 1 or chunk < 1:
        raise StateError("need transient ≥ 0, keep ≥ 1 and chunk ≥ 1")
    store = ResultStore(out, _bif_columns(param, snames), ["i", param])
    keys = [(str(i), _fmt(float(x))) for i, x in enumerate(v)]
    store.check_keys(keys)
    total = sum(1 for key in keys if not store.has(key))
    budget = total if max_points is None else max(0, min(total, int(max_points)))
    tasks, n_sched = [], 0
    for grp in _chunks(list(range(len(v))), chunk):
        pts = [g for g in grp if not store.has(keys[g])]
        if not pts or n_sched >= budget:
            continue
        pts = pts[: budget - n_sched]
        first = grp.index(pts[0])
        seed = None
        if first > 0:  # previous value's last state, exactly as stored
            r = store.rows.get(keys[grp[first - 1]])
            x = None if r is None or r["status"] != "ok" else _state_from_row(r, snames)
            seed = None if x is None else x.tolist()
        tasks.append((system, dict(params or {}), param, [(g, float(v[g])) for g in pts], seed, coord, transient,
                      keep, rtol, atol, period_tol))
        n_sched += len(pts)
    client, close = open_client(scheduler, workers) if tasks else (None, lambda: None)
    try:
        _execute(client, _bif_task, tasks, store, progress, n_sched, "bifurcation")
    finally:
        close()
    complete = all(store.has(key) for key in keys)
    if complete:
        store.compact()
    wanted = set(keys)
    rows = [r for r in store.sorted_rows() if (r["i"], r[param]) in wanted]
    return SweepResult(kind="bifurcation", params=[param], rows=rows, path=str(out) if out else None,
                       complete=complete, computed=n_sched, reused=len(keys) - total, state_names=list(snames))


def first_period_doubling_iterates(result: SweepResult) -> float | None:
    """First swept value whose post-transient iterates repeat with a period ≥ 2, or ``None``
    (period 0 is skipped: near the flip the transient decays too slowly to show a period)."""
    p = result.params[0]
    for r in result.rows:
        if r["status"] == "ok" and r["period"] not in ("", "0", "1"):
            return float(r[p])
    return None


# ============================================================================ basins
@dataclass
class BasinResult:
    """Basin of attraction on a grid of two initial-condition coordinates.

    ``outcome[i, j]`` is an index into ``labels`` for initial values ``a_values[i]``,
    ``b_values[j]``; ``steps[i, j]`` footfalls taken; ``distance[i, j]`` final
    ``|x − x*|∞`` (NaN if the walk did not complete).
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

    def counts(self) -> dict[str, int]:
        return {lab: int(np.sum(self.outcome == c)) for c, lab in enumerate(self.labels)}


def on_section(state_names: Sequence[str], params: Mapping[str, float], x: np.ndarray) -> np.ndarray:
    """Put a post-impact state of a compass-like walker (coordinates ``stance``, ``swing``,
    parameter ``slope``) on the section of ``params``: ``swing = 2·slope − stance`` (both feet on
    the slope, rad). Other systems: ``x`` unchanged."""
    sn = list(state_names)
    if "stance" in sn and "swing" in sn and "slope" in params:
        x = np.array(x, float)
        x[sn.index("swing")] = 2.0 * float(params["slope"]) - x[sn.index("stance")]
    return x


class SetCoordinates:
    """Default map (a, b) → full state: put the two values into the base state.

    For a compass-like walker (coordinates ``stance`` and ``swing``, parameter ``slope``) with
    ``swing`` not among the varied coordinates, the post-impact section constraint (both feet on
    the slope) ``swing = 2·slope − stance`` is enforced (rad).
    """

    def __init__(self, state_names: Sequence[str], names: tuple[str, str], slope: float | None) -> None:
        self.idx = [list(state_names).index(n) for n in names]
        sn = list(state_names)
        self.pair = (sn.index("stance"), sn.index("swing")) if (
            slope is not None and "stance" in sn and "swing" in sn and "swing" not in names) else None
        self.slope = slope

    def __call__(self, a: float, b: float, base: np.ndarray) -> np.ndarray:
        x = base.copy()
        x[self.idx[0]], x[self.idx[1]] = a, b
        if self.pair is not None:
            x[self.pair[1]] = 2.0 * self.slope - x[self.pair[0]]
        return x


def _basin_task(system: HybridSystem, pvec: list[float], rows: list[tuple[int, float]], b_values: list[float],
                base: list[float], fixed: list[float], to_state: Callable, steps: int, check_every: int, tol: float,
                rtol: float, atol: float) -> list[dict[str, Any]]:
    """One or more grid rows: walk each cell with the compiled run loop, no recording."""
    k = build(system)
    mi = 0
    n = k.meta["nx"][mi]
    p = np.asarray(pvec, float)
    xs = np.asarray(fixed, float)
    b0 = np.asarray(base, float)
    opts = Options(rtol=rtol, atol=atol, max_step_time=getattr(system, "max_step_time", 0.0) or 0.0)
    out = []
    for i, a in rows:
        for j, b in enumerate(b_values):
            x = np.asarray(to_state(a, b, b0), float)
            done, code, dist, reason = 0, 0, math.nan, ""
            if x.shape != (n,) or not np.all(np.isfinite(x)):
                code, reason = 3, "invalid initial state"
            else:
                while done < steps:
                    m = min(check_every, steps - done)
                    st, ctx, _ = run(k, p, mi, x, steps=m, opts=opts)
                    if st != _COMPLETED:
                        done += int(ctx[3])
                        name = _status_name(k, st, ctx)
                        code, reason = (1 if name == "fell" else 3), name
                        break
                    done += m
                    x = ctx[CTX_X:CTX_X + n].copy()
                    dist = float(np.max(np.abs(x - xs)))
                    if dist < tol:
                        break
                if not reason:
                    code = 0 if dist < tol else 2
            out.append({"i": i, "j": j, "a": float(a), "b": float(b), "outcome": BASIN_LABELS[code],
                        "reason": reason, "steps": done, "distance": dist})
    return out


def basin(
    system: HybridSystem,
    x_names: tuple[str, str],
    ranges: tuple[tuple[float, float], tuple[float, float]],
    n: tuple[int, int] = (100, 100),
    *,
    params: Mapping[str, float] | None = None,
    base_state: Sequence[float] | None = None,
    to_state: Callable[[float, float, np.ndarray], np.ndarray] | None = None,
    steps: int = 60,
    check_every: int = 5,
    tol: float = 1e-4,
    rows_per_task: int = 5,
    out: str | os.PathLike | None = None,
    scheduler: Any = None,
    workers: int | None = None,
    progress: bool = True,
    max_points: int | None = None,
    rtol: float = 1e-8,
    atol: float = 1e-8,
) -> BasinResult:
    """Basin of attraction of the period-1 gait over two post-impact coordinates.

    The grid is ``n[0]`` values of ``x_names[0]`` over ``ranges[0]`` × ``n[1]`` values of
    ``x_names[1]`` over ``ranges[1]``; the other coordinates come from ``base_state`` (default:
    the fixed point at ``params``). ``to_state(a, b, base) → full state`` overrides the
    embedding (default :class:`SetCoordinates`, which respects the compass gait's section). Each
    cell walks up to ``steps`` footfalls (checked every ``check_every``) and is ``converged`` if
    ``|x − x*|∞ < tol``, ``fell`` if a terminal/fall event ended it, ``not converged`` if it kept
    walking elsewhere (another attractor or too slow), ``failed`` for any other run status.
    One Dask task per ``rows_per_task`` grid rows. ``rtol``/``atol``: integrator tolerances
    (looser than for fixed points: only the outcome category matters here).
    """
    from .poincare import find_fixed_point

    k = build(system)
    pvec = parameter_vector(k, params)
    mode = k.meta["modes"][0]
    snames = list(k.meta["state_names"][mode])
    for nm in x_names:
        if nm not in snames:
            raise StateError(f"unknown coordinate {nm!r}; known: {', '.join(snames)}")
    if len(n) != 2 or min(n) < 1 or steps < 1 or check_every < 1 or rows_per_task < 1:
        raise StateError("need n = (na ≥ 1, nb ≥ 1), steps ≥ 1, check_every ≥ 1, rows_per_task ≥ 1")
    av = np.linspace(ranges[0][0], ranges[0][1], int(n[0]))
    bv = np.linspace(ranges[1][0], ranges[1][1], int(n[1]))
    _values(av, x_names[0]), _values(bv, x_names[1])
    lc = find_fixed_point(system, params=params)
    xs = lc.fixed_point
    base = xs if base_state is None else np.asarray(base_state, float)
    if base.shape != xs.shape:
        raise StateError(f"base_state needs {xs.size} values ({', '.join(snames)})")
    if to_state is None:
        slope = float(pvec[k.meta["params"].index("slope")]) if "slope" in k.meta["params"] else None
        to_state = SetCoordinates(snames, x_names, slope)
    cols = ["i", "j", "a", "b", "outcome", "reason", "steps", "distance"]
    store = ResultStore(out, cols, ["i", "j", "a", "b"])

    def key(i: int, j: int) -> tuple[str, ...]:
        return (str(i), str(j), _fmt(float(av[i])), _fmt(float(bv[j])))

    store.check_keys([key(i, j) for i in range(len(av)) for j in range(len(bv))])
    pending = [i for i in range(len(av)) if not all(store.has(key(i, j)) for j in range(len(bv)))]
    budget_rows = len(pending) if max_points is None else max(0, int(max_points)) // len(bv)
    pending = pending[:budget_rows]
    tasks = []
    for grp in _chunks(pending, rows_per_task):
        tasks.append((system, pvec.tolist(), [(i, float(av[i])) for i in grp], bv.tolist(), base.tolist(),
                      xs.tolist(), to_state, steps, check_every, tol, rtol, atol))
    client, close = open_client(scheduler, workers) if tasks else (None, lambda: None)
    try:
        _execute(client, _basin_task, tasks, store, progress, len(pending) * len(bv), "basin")
    finally:
        close()
    outcome = np.full((len(av), len(bv)), -1, dtype=int)
    st = np.zeros((len(av), len(bv)), dtype=int)
    dist = np.full((len(av), len(bv)), math.nan)
    complete = True
    for i in range(len(av)):
        for j in range(len(bv)):
            r = store.rows.get(key(i, j))
            if r is None:
                complete = False
                continue
            outcome[i, j] = BASIN_LABELS.index(r["outcome"])
            st[i, j] = int(r["steps"])
            dist[i, j] = float(r["distance"]) if r["distance"] not in ("", "nan") else math.nan
    if complete:
        store.compact()
    return BasinResult(names=tuple(x_names), a_values=av, b_values=bv, outcome=outcome, steps=st, distance=dist,
                       fixed_point=xs, path=str(out) if out else None, computed=len(pending) * len(bv),
                       state_names=snames)


# ============================================================================ Poincaré iterates
def poincare_iterates(system: HybridSystem, x0: Sequence[float] | None = None, *,
                      params: Mapping[str, float] | None = None, steps: int = 200, rtol: float = 1e-10,
                      atol: float = 1e-10) -> np.ndarray:
    """Successive post-impact states (steps+1 × n; row 0 = x0 or the model's guess); rows after
    a fall are absent (the array is shorter)."""
    k = build(system)
    p = parameter_vector(k, params)
    mode = k.meta["modes"][0]
    mi = k.mode_index(mode)
    n = k.meta["nx"][mi]
    x = np.asarray(x0 if x0 is not None else (system.fixed_point_guess or system.default_start[mode]), float)
    opts = Options(rtol=rtol, atol=atol, max_step_time=getattr(system, "max_step_time", 0.0) or 0.0)
    rows = [x]
    for _ in range(steps):
        st, ctx, _ = run(k, p, mi, x, steps=1, opts=opts)
        if st != _COMPLETED:
            break
        x = ctx[CTX_X:CTX_X + n].copy()
        rows.append(x)
    return np.array(rows)


# ============================================================================ CLI
def sweep_cli(args: Any) -> dict[str, Any]:
    """``amble sweep``: fixed-point branch / map or bifurcation diagram; returns a JSON summary."""
    from ..cli import UsageError, _load, _writable, parse_range, parse_sets

    sets = parse_sets(getattr(args, "set", None))
    ranges = [parse_range(t) for t in args.param]
    if len(ranges) not in (1, 2):
        raise UsageError(f"--param: give one (branch) or two (map) parameters, got {len(ranges)}")
    if args.kind == "bifurcation" and len(ranges) != 1:
        raise UsageError("--kind bifurcation sweeps exactly one --param")
    for nm in ("rtol", "atol"):
        v = getattr(args, nm, 1e-10)
        if not (v > 0 and math.isfinite(v)):
            raise UsageError(f"--{nm} must be a positive number, got {v}")
    if args.workers is not None and args.workers < 1:
        raise UsageError(f"--workers must be at least 1, got {args.workers}")
    out = _writable(args.out, (".csv", ".parquet"), "--out")
    if out is not None and out.exists() and out.stat().st_size == 0:
        out.unlink()  # _writable touched it; an empty file is no journal
    plot = _writable(args.plot, (".png", ".svg", ".pdf"), "--plot")
    if plot is not None and plot.stat().st_size == 0:
        plot.unlink()
    system = _load(args.model)
    names = [r[0] for r in ranges]
    for nm in names:
        if nm in sets:
            raise UsageError(f"parameter {nm!r} is both swept and --set")
    vals = [np.linspace(r[1], r[2], r[3]) for r in ranges]
    common = dict(params=sets, out=out, scheduler=args.scheduler, workers=args.workers,
                  progress=not getattr(args, "json", False), rtol=args.rtol, atol=args.atol)
    t0 = time.perf_counter()
    summary: dict[str, Any] = {"model": args.model, "kind": args.kind, "parameters": names,
                               "ranges": [list(r[1:]) for r in ranges], "set": sets, "file": str(out) if out else None}
    if args.kind == "bifurcation":
        res = bifurcation(system, names[0], vals[0], **common)
        summary["first_period_two"] = first_period_doubling_iterates(res)
    elif len(names) == 1:
        common["rtol"], common["atol"] = min(args.rtol, 1e-12), min(args.atol, 1e-12)
        res = sweep_fixed_points(system, names[0], vals[0], **common)
        summary["period_doubling"] = period_doubling(res)
        st = [r for r in res.rows if r["status"] == "ok" and r["stable"] == "true"]
        summary["stable_range"] = [float(st[0][names[0]]), float(st[-1][names[0]])] if st else None
    else:
        res = sweep_fixed_points_2d(system, (names[0], names[1]), (vals[0], vals[1]), **common)
        summary["stable"] = sum(1 for r in res.rows if r["stable"] == "true")
    summary.update(res.counts())
    summary.update(points=len(res.rows), computed=res.computed, reused=res.reused, complete=res.complete,
                   seconds=round(time.perf_counter() - t0, 3))
    summary["failures"] = [{**{nm: float(r[nm]) for nm in names}, "reason": r["reason"]}
                           for r in res.rows if r["status"] != "ok"][:20]
    if plot is not None:
        from ..viz import sweep_plots as sp

        if args.kind == "bifurcation":
            sp.plot_bifurcation(res, plot)
        elif len(names) == 1:
            sp.plot_branch(res, plot)
        else:
            sp.plot_parameter_map(res, plot)
        summary["plot"] = str(plot)
    if not getattr(args, "json", False):
        print(f"{args.model}: {args.kind} sweep over {' × '.join(names)}: {len(res.rows)} points, "
              f"{summary['ok']} ok, {summary['failed']} failed ({summary['seconds']} s)")
        for key in ("period_doubling", "stable_range", "first_period_two"):
            if key in summary:
                print(f"  {key.replace('_', ' ')}: {summary[key]}")
        if out is not None:
            print(f"  results: {out}")
        if plot is not None:
            print(f"  plot: {plot}")
    return summary


__all__ = ["BASIN_LABELS", "BasinResult", "ResultStore", "SetCoordinates", "SweepResult", "basin", "bifurcation",
           "first_period_doubling_iterates", "open_client", "period_doubling", "poincare_iterates", "sweep_cli",
           "sweep_fixed_points", "sweep_fixed_points_2d", "on_section"]
