"""Removing entries from the compile cache without disturbing a build in progress.

A model library is removed as a whole (its ``.json`` first, so that no reader trusts a
half-removed entry, then its ``.so`` and ``.c``), together with the warm-start index entries that
named it; runtime objects only when everything or everything older than an age is cleared. The
leftovers of killed builds (temporaries older than the cache's orphan age) go with every clear, as
they go with every build.

Builds take no lock (:mod:`amble.backend.cache_admin`), so what a build may be using is kept:

* a temporary younger than the orphan age (a compile's ``build-*`` directory, a write's
  ``.<name>.<pid>.tmp``): the mark of a build in progress;
* a library file its ``.json`` does not name, younger than the orphan age: a build renames the
  library into place before it writes the metadata;
* while a build is in progress, every file modified since it began (what it writes or is about to
  load: a build of the same key may be replacing the entry) and the runtime objects (it may be
  linking one); the marks are looked for again before the runtime objects are removed;
* a file modified after the clear began (a build that started meanwhile).

A library a running process has loaded stays usable after its file is removed (the mapping
outlives the name); a process that looks it up afterwards builds it again.
"""

from __future__ import annotations

import math
import os
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from . import cache
from . import cache_admin as admin
from .cache_admin import CacheRequestError, Entry

#: s: file times on the coarsest file-system clocks in use are this far behind the wall clock
_SLACK = 2.0
_DAY = 86400.0


@dataclass
class Removal:
    """What :func:`clear` removed (or, with ``dry_run``, would remove): the entries with the files
    actually removed, and the files kept with the reason (a build in progress)."""

    directory: Path
    dry_run: bool
    removed: list[Entry] = field(default_factory=list)
    kept: list[tuple[Path, str]] = field(default_factory=list)

    @property
    def files_removed(self) -> int:
        return sum(len(e.files) for e in self.removed)

    @property
    def bytes_freed(self) -> int:
        return sum(e.bytes for e in self.removed)

    def to_json(self) -> dict[str, Any]:
        return {"directory": str(self.directory), "dry_run": self.dry_run,
                "removed": [e.to_json() for e in self.removed],
                "kept": [{"file": p.name, "reason": why} for p, why in self.kept],
                "files_removed": self.files_removed, "bytes_freed": self.bytes_freed}


def clear(d: Path | None = None, *, everything: bool = False, older_than: float | None = None,
          model: str | None = None, dry_run: bool = False) -> Removal:
    """Remove cache entries of cache directory ``d`` (default
    :func:`~amble.backend.cache_admin.directory`); give exactly one of

    * ``everything``: every entry — libraries, runtime objects, index entries, stamps;
    * ``older_than``: the libraries and runtime objects last used more than this many days ago
      (≥ 0; :class:`~amble.backend.cache_admin.Entry`), and index entries older than that whose
      library is gone;
    * ``model``: the libraries of this model — the system's name in their metadata, or a model
      spec (library name or ``path.py[:callable]``) the index maps to them; none is a
      :class:`~amble.backend.cache_admin.CacheRequestError`.

    Index entries that named a removed library are removed with it; files of a build in progress
    are kept (see the module docstring). ``dry_run``: remove nothing, report what would go."""
    if sum([bool(everything), older_than is not None, model is not None]) != 1:
        raise CacheRequestError("clear: give exactly one of everything, older_than (days) or model")
    if older_than is not None and not (isinstance(older_than, (int, float)) and math.isfinite(older_than)
                                       and older_than >= 0):
        raise CacheRequestError(f"clear: older_than must be a number of days, at least 0, got {older_than!r}")
    d = admin.directory() if d is None else d
    start = time.time()
    c = admin.scan(d)
    marks = admin.building(c, start)
    cutoff = start - older_than * _DAY if older_than is not None else math.inf
    models, runtimes = _chosen(c, everything, cutoff, model)
    run = _Clearing(Removal(d, dry_run), start, min((_began(e) for e in marks), default=math.inf) - _SLACK)
    for e in models:
        named = admin.recorded_files(e)
        run.take(e, lambda p, st, named=named: run.in_use(p, st) or (
            "a build in progress renamed it into place and has not recorded it yet"
            if p not in named and start - st.st_mtime <= cache.ORPHAN_AGE else None))
    # a model build that began meanwhile would link one
    linking = bool(marks) or bool(runtimes and admin.building(admin.scan(d)))
    for e in runtimes:
        run.take(e, lambda p, st: "a build in progress may be linking it" if linking else run.in_use(p, st))
    remaining = {e.key for e in _still(c.models, run.out)}
    gone_keys = {e.key for e in run.out.removed if e.kind == "model" and any(p.suffix == ".json" for p in e.files)}
    for e in c.index:
        hit = admin.index_library(e)
        keys = set(admin.index_keys(hit[1])) if hit else set()
        stale = not keys & remaining and (bool(keys & gone_keys) or e.last_used < cutoff)
        if everything or stale:
            run.take(e, run.in_use)
    for e in c.stamps if everything else []:
        run.take(e, run.in_use)
    for e in c.temporaries:
        fresh = e in marks
        if fresh and everything:
            run.out.kept.append((e.files[0], "a build in progress"))
        elif not fresh:  # a killed build's, unless written again since the scan
            run.take(e, lambda p, st: "a build in progress" if start - st.st_mtime <= cache.ORPHAN_AGE else None)
    return run.out


def _chosen(c: admin.Contents, everything: bool, cutoff: float, model: str | None) -> tuple[list[Entry], list[Entry]]:
    """The libraries and runtime objects a clear is asked to remove."""
    if everything:
        return c.models, c.runtimes
    if model is None:  # older than the cutoff
        return [e for e in c.models if e.last_used < cutoff], [e for e in c.runtimes if e.last_used < cutoff]
    models = [e for e in c.models if model in (e.name, *e.specs)]
    if not models:
        raise CacheRequestError(f"no compiled model {model!r} in the cache {c.directory} "
                                "('amble cache list' shows them)")
    return models, []


@dataclass
class _Clearing:
    """One clear in progress: what it removed and kept so far, when it began (``start``) and when
    the oldest build in progress began (``began``)."""

    out: Removal
    start: float
    began: float

    def in_use(self, p: Path, st: os.stat_result) -> str | None:
        if st.st_mtime >= self.began or st.st_mtime > self.start:
            return "a build in progress may be writing or loading it"
        return None

    def take(self, e: Entry, why_kept: Callable[[Path, os.stat_result], str | None]) -> None:
        """Remove the files of ``e`` that ``why_kept`` has no reason to keep (the record first)."""
        gone = []
        for p in sorted(e.files, key=lambda p: p.suffix != ".json"):  # the record first
            st = admin.lstat(p)
            if st is None:
                continue  # removed meanwhile
            size = e.bytes if p.is_dir() else st.st_size  # a build directory: the files in it
            why = why_kept(p, st)
            if why is None and not self.out.dry_run:
                why = _remove(p)
            if why is None:
                gone.append((p, size))
            elif why:  # "": removed by another process meanwhile, neither ours nor kept
                self.out.kept.append((p, why))
        if gone:
            self.out.removed.append(Entry(e.kind, e.key, tuple(p for p, _ in gone), sum(n for _, n in gone),
                                          e.last_used, e.name, e.derivatives, e.specs, e.capacity, e.recorded))


def _still(models: list[Entry], out: Removal) -> list[Entry]:
    """The library entries whose record (``.json``) is still in the cache after the removal."""
    records = {p for e in out.removed for p in e.files if p.suffix == ".json"}
    return [e for e in models if any(p.suffix == ".json" and p not in records for p in e.files)]


def _began(e: Entry) -> float:
    """When the build a temporary belongs to began: the oldest time of the temporary and, for a
    build directory, of the files in it."""
    p = e.files[0]
    times = [e.last_used]
    try:
        times += [f.stat(follow_symlinks=False).st_mtime for f in os.scandir(p)] if p.is_dir() else []
    except OSError:
        pass
    return min(times)


def _remove(p: Path) -> str | None:
    """Remove one file (or a killed build's directory); ``None`` when done, ``""`` if it is gone
    already (another process removed it), else why it cannot be removed."""
    try:
        if p.is_dir() and not p.is_symlink():
            import shutil  # only a killed build's directory needs it

            shutil.rmtree(p)
        else:
            p.unlink()
    except FileNotFoundError:
        return ""
    except OSError as e:
        return f"cannot remove it ({e.strerror or e})"
    return None


__all__ = ["Removal", "clear"]
