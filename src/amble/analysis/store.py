"""Result store of parameter sweeps: an append-only, resumable CSV journal, and the result table.

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

All values are stored as text exactly as written (:func:`fmt_value`); :class:`SweepResult`
converts columns back to numbers on demand.
"""

from __future__ import annotations

import csv
import errno
import io
import math
import os
import warnings
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from operator import itemgetter
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import OutputError
from .cells import COLUMN_TYPES, TextRows, fmt_value, parse_value


class ResultFileWarning(UserWarning):
    """Rows of a result file that cannot be read back as their column types were ignored (they are
    computed again)."""


class ResultStore:
    """Append-only CSV journal of sweep rows keyed by ``key`` columns (see module docstring).

    ``path``: ``FILE.csv``, ``FILE.parquet`` or ``None`` (rows kept in memory only); existing
    rows are loaded on construction. ``columns``: every column, in file order, or a mapping of
    each column to its type (:data:`COLUMN_TYPES`): a row read from the file whose cell is not
    of its column's type (``step_time`` = ``abc``: a damaged or edited file) is then ignored with
    a :class:`ResultFileWarning`, so the point is computed again instead of counted as ``ok``.
    ``key``: the columns that identify a point (first row of a key wins).

    Writability is checked on construction, before any work: a file must be creatable in the
    directory (every rewrite goes through a temporary file there) and an existing journal must
    be writable. Should a write still fail (a full disk, ``ENOSPC``), it is an
    :class:`OutputError` that leaves the journal as it was before the write: rows already
    appended are kept, and running the same sweep again resumes from them. A file that cannot be
    read (not UTF-8 text, not Parquet) is an :class:`OutputError` too; it is never overwritten.

    A store with a file holds an exclusive advisory lock on ``.FILE.lock`` from construction to
    :meth:`close` (it is a context manager; the lock file is removed then): a second sweep on the
    same file is refused with an :class:`OutputError` instead of both writing it (the compaction
    of one would drop the rows of the other).
    """

    def __init__(self, path: str | os.PathLike | None, columns: Sequence[str] | Mapping[str, str],
                 key: Sequence[str]) -> None:
        self.columns = list(columns)
        self.types: dict[str, str] = dict(columns) if isinstance(columns, Mapping) else {}
        self.key = list(key)
        at = [self.columns.index(c) for c in self.key]
        # the key of a row given as its cells in column order (a tuple, also for one key column)
        self._key_of = itemgetter(*at) if len(at) > 1 else (lambda t, i=at[0]: (t[i],))
        self.ignored = 0  # rows of the file that were not of their columns' types
        self._first_ignored = ""
        self.final: Path | None = Path(path) if path is not None else None
        if self.final is not None and self.final.suffix.lower() not in (".csv", ".parquet"):
            raise OutputError(f"result file {str(self.final)!r} must end with .csv or .parquet")
        self.parquet = self.final is not None and self.final.suffix.lower() == ".parquet"
        self.journal = (self.final.with_name(self.final.name + ".journal.csv") if self.parquet else self.final)
        self.rows: dict[tuple[str, ...], dict[str, str]] = {}
        self._lock = _lock(self.final) if self.final is not None else None
        try:
            self._check_writable()
            self._load()
        except BaseException:
            self.close()
            raise

    def close(self) -> None:
        """Release the file's lock (rows already appended are durable)."""
        if self._lock is not None:
            _unlock(self._lock)
            self._lock = None

    def __enter__(self) -> ResultStore:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def _check_writable(self) -> None:
        """:class:`OutputError` now, before any work, if the file could not be written later."""
        if self.final is None:
            return
        where = self.final.parent if str(self.final.parent) else Path(".")
        try:  # a real file, not permission bits: also right for root and read-only file systems
            import tempfile  # here, not at import: a warm run that writes no file never needs it

            fd, probe = tempfile.mkstemp(prefix=f".{self.final.name}.", suffix=".probe", dir=where)
            os.close(fd)
            os.unlink(probe)
            if self.journal is not None and self.journal.exists():
                open(self.journal, "ab").close()  # opening to append changes nothing
        except OSError as e:
            raise OutputError(f"cannot write result file {str(self.final)!r} ({e.strerror or e}); "
                              "choose another file") from None

    def _load(self) -> None:
        if self.final is None:
            return
        if self.parquet and self.final.exists() and self.final.stat().st_size > 0:
            for r in self._read_parquet():
                self._add_read({c: "" if r[c] is None else str(r[c]) for c in self.columns}, "a row")
        if self.journal is None or not self.journal.exists() or self.journal.stat().st_size == 0:
            self._warn_ignored()
            return
        data = self.journal.read_bytes()
        good = data[: data.rfind(b"\n") + 1]  # a torn last line (killed mid-write) is dropped
        try:
            text = good.decode()
        except UnicodeDecodeError as e:  # not written by a sweep (which writes UTF-8): never guess
            line = good.count(b"\n", 0, e.start) + 1
            raise OutputError(f"{str(self.journal)!r} is not a sweep result file (line {line} is not UTF-8 "
                              "text); use another file") from None
        lines = text.split("\n")[:-1]
        reader = csv.reader(lines)
        header = next(reader, None)
        if header != self.columns:
            raise OutputError(f"{str(self.journal)!r} holds a different kind of sweep (columns differ); "
                             "use another file")
        if len(good) < len(data):  # only now, the file known to be this sweep's: cut the torn line
            with open(self.journal, "r+b") as f:  # off, so the next append starts on a fresh line
                f.truncate(len(good))
                os.fsync(f.fileno())
        for n, fields in enumerate(reader, start=2):
            if len(fields) == len(self.columns):
                self._add_read(dict(zip(self.columns, fields)), f"line {n}")
        self._warn_ignored()

    def _read_parquet(self) -> list[dict[str, Any]]:
        """The rows of the Parquet file; :class:`OutputError` if it is not one of this sweep."""
        import pyarrow as pa
        import pyarrow.parquet as pq

        assert self.final is not None
        try:
            tab = pq.read_table(self.final)
        except (pa.ArrowException, OSError) as e:  # ArrowInvalid: a damaged file or not Parquet
            first = str(e).splitlines()[0] if str(e) else type(e).__name__
            raise OutputError(f"{str(self.final)!r} is not a readable Parquet file ({first}); "
                              "use another file") from None
        if tab.column_names != self.columns:
            raise OutputError(f"{str(self.final)!r} holds a different kind of sweep (columns differ)")
        return tab.to_pylist()

    def _add_read(self, row: Mapping[str, str], where: str) -> None:
        """Add a row read from the file unless a cell is not of its column's type."""
        bad = next(((c, row[c]) for c, kind in self.types.items() if not _is_type(row[c], kind)), None)
        if bad is None:
            self._add(row)
            return
        self.ignored += 1
        if self.ignored == 1:
            self._first_ignored = f"{where}: {bad[0]} = {bad[1]!r} is not {self.types[bad[0]]}"

    def _warn_ignored(self) -> None:
        if self.ignored:
            warnings.warn(f"{str(self.final)!r}: {self.ignored} damaged row(s) ignored and computed again "
                          f"({self._first_ignored})", ResultFileWarning, stacklevel=4)

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
            raise OutputError(f"{str(self.final)!r} holds {len(extra)} point(s) of another sweep (e.g. {shown}); "
                             "use another file or the same grid")

    def has(self, key: tuple[str, ...]) -> bool:
        """Whether the point with this key is already stored."""
        return key in self.rows

    def append(self, rows: Iterable[Mapping[str, Any]] | TextRows) -> None:
        """Add rows (values formatted exactly, :func:`~amble.analysis.cells.fmt_value`); durable
        on return when the store has a file. :class:`~amble.analysis.cells.TextRows` (cells
        already as text, in column order) are appended as they are."""
        if isinstance(rows, TextRows):
            self.append_text(rows)
            return
        self.append_text([tuple(fmt_value(r.get(c, "")) for c in self.columns) for r in rows])

    def append_text(self, rows: Iterable[Sequence[str]]) -> None:
        """Add rows whose cells are already text (:func:`~amble.analysis.cells.fmt_value`), in
        column order; a row whose key is stored already is skipped (the first of a key wins).
        Durable on return (one ``write`` and ``fsync`` for all of them)."""
        fresh = []
        ncol, cols = len(self.columns), self.columns
        for t in rows:
            if len(t) != ncol:
                raise ValueError(f"a row of {len(t)} cells for the {ncol} columns {', '.join(cols)}")
            k = self._key_of(t)
            if k not in self.rows:
                self.rows[k] = dict(zip(cols, t))
                fresh.append(t)
        if self.journal is None or not fresh:
            return
        new = not self.journal.exists() or self.journal.stat().st_size == 0
        buf = io.StringIO()
        w = csv.writer(buf, lineterminator="\n")
        if new:
            w.writerow(self.columns)
        w.writerows(fresh)
        size = self.journal.stat().st_size if not new else 0
        try:
            with open(self.journal, "a", newline="", encoding="utf-8") as f:
                f.write(buf.getvalue())
                f.flush()
                os.fsync(f.fileno())
        except OSError as e:
            for t in fresh:  # not durable: the points are still pending
                self.rows.pop(self._key_of(t), None)
            try:  # the journal as it was: no torn rows of this write
                os.truncate(self.journal, size)
            except OSError:
                pass
            raise OutputError(f"cannot append to result file {str(self.journal)!r}: {_reason(e)}; the rows "
                              "written before are kept, run the same sweep again to resume") from None

    def sorted_rows(self) -> list[dict[str, str]]:
        """All stored rows, sorted by key."""
        field = _SortField()  # a grid's keys repeat few field texts: each is converted once
        return [self.rows[k] for k in sorted(self.rows, key=lambda k: tuple(map(field.__getitem__, k)))]

    def compact(self, rows: list[dict[str, str]] | None = None) -> None:
        """Rewrite the file sorted by key, atomically (deterministic content for equal results).
        ``rows``: :meth:`sorted_rows`, when the caller has them already."""
        if self.final is None:
            return
        rows = self.sorted_rows() if rows is None else rows
        tmp = self.final.with_name(f".{self.final.name}.{os.getpid()}.tmp")
        try:
            self._write_compacted(rows, tmp)
            os.replace(tmp, self.final)
        except OSError as e:  # the journal still holds every row: nothing computed is lost
            try:
                tmp.unlink()
            except OSError:
                pass
            raise OutputError(f"cannot write result file {str(self.final)!r}: {_reason(e)}; the {len(rows)} "
                              f"rows are kept in {str(self.journal)!r}, run the same sweep again to finish "
                              "it") from None
        if self.parquet and self.journal is not None and self.journal.exists():
            self.journal.unlink()

    def _write_compacted(self, rows: list[dict[str, str]], tmp: Path) -> None:
        """Write the sorted ``rows`` to ``tmp`` in the file's format, durably."""
        if self.parquet:
            import pyarrow as pa
            import pyarrow.parquet as pq

            pq.write_table(pa.table({c: [r[c] for r in rows] for c in self.columns}), tmp)
            return
        with open(tmp, "w", newline="", encoding="utf-8") as f:
            w = csv.writer(f, lineterminator="\n")
            w.writerow(self.columns)
            for r in rows:
                w.writerow([r[c] for c in self.columns])
            f.flush()
            os.fsync(f.fileno())


def _reason(e: OSError) -> str:
    """An OS error in words (a full disk named as such)."""
    if e.errno == errno.ENOSPC:
        return "no space left on device"
    return e.strerror or (os.strerror(e.errno) if e.errno else "") or str(e) or type(e).__name__


def _is_type(text: str, kind: str) -> bool:
    """Whether a stored cell reads back as a value of column type ``kind`` (empty: always)."""
    if text == "" or kind == "str":
        return True
    if kind == "bool":
        return text in ("true", "false")
    try:
        parse_value(text, kind)
    except (ValueError, TypeError):  # json.JSONDecodeError is a ValueError
        return False
    return True


def _lock(final: Path) -> Any:
    """An open lock file beside ``final``, exclusively locked; :class:`OutputError` if another
    process holds it. Where ``fcntl`` is missing (Windows) sweeps are not locked.

    The holder removes the lock file when it closes (:func:`_unlock`), so no request — a refused
    one included — leaves a file behind. A lock taken on a file that was removed meanwhile is no
    lock (a third process may create the name anew): the path must still name the locked file,
    else the lock is taken again."""
    try:
        import fcntl
    except ImportError:
        return None
    path = final.with_name(f".{final.name}.lock")
    while True:
        try:
            f = open(path, "a+")
        except OSError as e:
            raise OutputError(f"cannot lock result file {str(final)!r} ({e.strerror or e})") from None
        try:
            fcntl.flock(f.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            f.seek(0)
            holder = f.read().strip()
            f.close()
            raise OutputError(f"result file {str(final)!r} is in use by another sweep"
                              f"{f' (process {holder})' if holder else ''}; wait for it or use another file") from None
        try:
            same = os.stat(path).st_ino == os.fstat(f.fileno()).st_ino
        except OSError:  # removed by its holder between our open and our lock
            same = False
        if same:
            break
        f.close()
    f.seek(0)
    f.truncate()
    f.write(str(os.getpid()))
    f.flush()
    return f


def _unlock(f: Any) -> None:
    """Remove the lock file (still holding the lock, so no one else can be using it) and release it."""
    try:
        os.unlink(f.name)
    except OSError:
        pass
    f.close()


class _SortField(dict):
    """Key field text → what it sorts as: integer fields (grid indices) numerically, so row 10
    follows row 9; others as text. Filled on first use of each text."""

    def __missing__(self, x: str) -> int | str:
        v = self[x] = int(x) if x.lstrip("-").isdigit() else x
        return v


def state_columns(names: Sequence[str]) -> list[str]:
    """Column names ``x_<state>`` of a stored post-impact state."""
    return [f"x_{n}" for n in names]


def state_from_row(row: Mapping[str, str], names: Sequence[str]) -> np.ndarray | None:
    """The stored state of a row, or ``None`` if it is missing or not finite (a failed point)."""
    try:
        x = np.array([float(row[c]) for c in state_columns(names)])
    except (KeyError, ValueError):
        return None
    return x if np.all(np.isfinite(x)) else None


@dataclass
class SweepResult:
    """Rows of a finished (or partial) sweep, sorted by key; values as written in the file (str).

    ``types``: column name → type (:data:`COLUMN_TYPES`); :meth:`records` and :meth:`table`
    give the values as numbers."""

    kind: str
    params: list[str]
    rows: list[dict[str, str]]
    path: str | None
    complete: bool
    computed: int
    reused: int
    state_names: list[str] = field(default_factory=list)
    types: dict[str, str] = field(default_factory=dict)

    def records(self) -> list[dict[str, Any]]:
        """The rows with each value converted by its column type (untyped columns stay text)."""
        return [{c: parse_value(v, self.types.get(c, "str")) for c, v in r.items()} for r in self.rows]

    def table(self) -> dict[str, Any]:
        """Column name → values: a NumPy array for ``int``/``float``/``bool`` columns without
        empty cells (``float`` ones: NaN where empty), else a list."""
        recs = self.records()
        out: dict[str, Any] = {}
        for c in (self.rows[0] if self.rows else self.types):
            vals = [r[c] for r in recs]
            kind = self.types.get(c, "str")
            numeric = kind == "float" or (kind in ("int", "bool") and all(v is not None for v in vals))
            out[c] = np.array(vals, dtype={"int": int, "float": float, "bool": bool}[kind]) if numeric else vals
        return out

    def column(self, name: str) -> np.ndarray:
        """A numeric column (NaN where empty)."""
        return np.array([float(r[name]) if r[name] not in ("", "nan") else math.nan for r in self.rows])

    def ok(self) -> np.ndarray:
        """Boolean mask of the rows whose point succeeded."""
        return np.array([r["status"] == "ok" for r in self.rows])

    def counts(self) -> dict[str, int]:
        """Number of ``ok`` and ``failed`` rows."""
        ok = int(self.ok().sum())
        return {"ok": ok, "failed": len(self.rows) - ok}


__all__ = ["COLUMN_TYPES", "ResultFileWarning", "ResultStore",
           "SweepResult", "fmt_value", "parse_value", "state_columns", "state_from_row"]
