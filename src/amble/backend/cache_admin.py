"""What the compile cache holds, and removing entries from it without disturbing a build.

The cache directory (:mod:`amble.backend.cache`) holds

* model libraries: ``<key>.json`` (the loader's metadata: the system's ``name``, whether it has
  the ``derivatives`` kernels, the library's file name and SHA-256), the library
  ``<key>-<sha>.so`` and its generated source ``<key>-<sha>.c``; a rebuild that produced other
  bytes leaves the former ``<key>-<sha'>`` files, which belong to the same entry;
* runtime objects (:mod:`amble.backend.runtime`): ``runtime-<key>.json`` and
  ``runtime-<key>-<sha>.o``, one per capacity and toolchain;
* warm-start index entries ``index-<id>.json``, each naming the library key of one model source
  (:mod:`amble.backend.index`), and stamps ``stamp-<id>.json`` (:mod:`amble.backend.stamps`);
* the temporaries of builds: ``build-*`` directories of a compile (marked as amble's) and
  ``.<name>.<pid>.tmp`` files of an atomic write (:func:`amble.backend.files.write_atomic`);
* its tag, ``CACHEDIR.TAG`` (:mod:`amble.backend.cache_home`): a directory without one is not
  listed or cleared. Anything else in it is the user's and never removed.

Builds take no lock: several processes may build into one directory, each writing under temporary
names and renaming into place, and a temporary older than the cache's orphan age is a killed
build's (:func:`amble.backend.cache_home.is_build`, :data:`~amble.backend.cache.ORPHAN_AGE`). The
same marks tell this module that a build is in progress, and removal
(:mod:`amble.backend.cache_clear`) keeps what a build may be using.

A library's *last use* is the later of its access and modification times: loading a library reads
its bytes (their SHA-256 is checked), which the file system records as an access — at most once a
day on ``relatime`` mounts, never on ``noatime`` ones, where it is the time of the last build.
Listing and clearing never read a library or an object, so they are no use.
"""

from __future__ import annotations

import json
import os
import time
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from ..errors import AmbleError, CompileError
from . import cache
from .cache_home import ENTRY_NAMES, TAG, entry_kind, is_amble_name, is_build, is_writing

_MODEL, _RUNTIME = ENTRY_NAMES["model"], ENTRY_NAMES["runtime"]


class CacheRequestError(AmbleError, ValueError):
    """A request about the cache that cannot be carried out: an unusable cache directory, an
    unknown model, a negative age."""


@dataclass(frozen=True)
class Entry:
    """One entry of the cache: the files that are used or removed together.

    ``kind``: ``model`` (a library), ``runtime`` (a runtime object), ``index``, ``stamp`` or
    ``temporary`` (a build's). ``key``: the cache key (``model``, ``runtime``) or the file name.
    ``bytes``: the size of its files; ``last_used``: seconds since the epoch (see the module
    docstring). ``name``: the system's name as its metadata records it (an index entry: the model
    spec it is for); ``derivatives``: whether
    the library holds the derivative kernels; ``specs``: the models (library names or file
    specs) the warm-start index maps to it; ``capacity``: a runtime object's state capacity.
    ``recorded``: whether a ``.json`` records the entry (a library renamed into place whose
    metadata is not written yet is not)."""

    kind: str
    key: str
    files: tuple[Path, ...]
    bytes: int
    last_used: float
    name: str | None = None
    derivatives: bool | None = None
    specs: tuple[str, ...] = ()
    capacity: int | None = None
    recorded: bool = True

    def to_json(self) -> dict[str, Any]:
        out: dict[str, Any] = {"kind": self.kind, "key": self.key}
        if self.kind in ("model", "index"):
            out["name"] = self.name
        if self.kind == "model":
            out.update( derivatives=self.derivatives, specs=list(self.specs), recorded=self.recorded)
        if self.kind == "runtime":
            out["capacity"] = self.capacity
        out.update(bytes=self.bytes, last_used=iso_time(self.last_used), files=[f.name for f in self.files])
        return out


@dataclass
class Contents:
    """Everything in a cache directory, by kind (see the module docstring); ``other``: files that
    are none of amble's (never removed)."""

    directory: Path
    models: list[Entry] = field(default_factory=list)
    runtimes: list[Entry] = field(default_factory=list)
    index: list[Entry] = field(default_factory=list)
    stamps: list[Entry] = field(default_factory=list)
    temporaries: list[Entry] = field(default_factory=list)
    other: list[Path] = field(default_factory=list)

    def entries(self) -> list[Entry]:
        """Every entry of every kind (not the ``other`` files)."""
        return [*self.models, *self.runtimes, *self.index, *self.stamps, *self.temporaries]


def iso_time(t: float) -> str:
    """Seconds since the epoch as ISO 8601 UTC, to the second (``2026-01-31T12:00:00Z``)."""
    return time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime(t))


def directory() -> Path:
    """The configured cache directory; :class:`CacheRequestError` if it cannot be used (amble then
    compiles into its fallback with a warning, :mod:`amble.backend.cache_home`, and the configured
    directory is neither listed nor cleared)."""
    d, why = cache.configured()
    if why is not None:
        raise CacheRequestError(f"the cache {d} is not usable ({why}); nothing in it is listed or removed")
    return d


def lstat(p: Path) -> os.stat_result | None:
    """The status of ``p`` itself (a link's, not its target's), ``None`` if it is gone."""
    try:
        return p.lstat()  # a link is the link's own business: never followed out of the cache
    except OSError:  # removed meanwhile (another process cleared or rebuilt)
        return None


def scan(d: Path | None = None) -> Contents:
    """The entries of cache directory ``d`` (default :func:`directory`)."""
    d = directory() if d is None else d
    out = Contents(d)
    groups: dict[tuple[str, str], list[Path]] = {}
    try:
        names = sorted(os.listdir(d))
    except FileNotFoundError:
        return out
    if TAG not in names:  # what is not a cache is never listed as one, let alone cleared
        raise CacheRequestError(f"{d} is not an amble cache (it has no {TAG})")
    for n in names:
        p = d / n
        kind = entry_kind(n)
        if kind and n.endswith(".json") and not is_amble_name(d, n):
            kind = None  # named like a record but not one amble wrote (a rewrite heals a damaged one)
        if is_writing(n) or is_build(p):
            out.temporaries.append(_single("temporary", p))
        elif kind == "runtime" and (m := _RUNTIME.fullmatch(n)):
            groups.setdefault(("runtime", m[1]), []).append(p)
        elif kind == "model" and (m := _MODEL.fullmatch(n)):
            groups.setdefault(("model", m[1]), []).append(p)
        elif kind in ("index", "stamp"):
            (out.index if kind == "index" else out.stamps).append(_single(kind, p))
        elif n != TAG:
            out.other.append(p)
    specs = _specs(out.index)
    out.index = [replace(e, name=hit[0]) if (hit := index_library(e)) else e for e in out.index]
    for (kind, key), files in groups.items():
        meta = read_record(d / (f"runtime-{key}.json" if kind == "runtime" else f"{key}.json"))
        main = d / str(meta.get("object" if kind == "runtime" else "library", "")) if meta else None
        use = lstat(main) if main is not None and main in files else None
        stats = [s for s in map(lstat, files) if s is not None]
        last = max(use.st_atime, use.st_mtime) if use else max((s.st_mtime for s in stats), default=0.0)
        size = sum(s.st_size for s in stats)
        if kind == "runtime":
            cap = meta.get("capacity") if meta else None
            out.runtimes.append(Entry("runtime", key, tuple(files), size, last, capacity=cap if isinstance(cap, int)
                                      else None, recorded=meta is not None))
        else:
            deriv, name = (meta.get("derivatives"), meta.get("name")) if meta else (None, None)
            out.models.append(Entry("model", key, tuple(files), size, last,
                                    name=name if isinstance(name, str) else None,
                                    derivatives=deriv if isinstance(deriv, bool) else None,
                                    specs=tuple(specs.get(key, ())), recorded=meta is not None))
    return out


def _single(kind: str, p: Path) -> Entry:
    """An entry of one file, or of a build directory (its size: that of the files in it)."""
    st = lstat(p)
    size = st.st_size if st else 0
    if p.is_dir() and not p.is_symlink():
        try:
            size = sum(f.stat(follow_symlinks=False).st_size for f in os.scandir(p) if f.is_file())
        except OSError:
            pass
    return Entry(kind, p.name, (p,), size, st.st_mtime if st else 0.0)


def read_record(p: Path) -> dict | None:
    """A metadata file's object, or ``None`` if it is missing or unreadable (a damaged entry:
    listed and removable like any other)."""
    try:
        meta = json.loads(p.read_text())
    except (OSError, ValueError):
        return None
    return meta if isinstance(meta, dict) else None


def recorded_files(entry: Entry) -> set[Path]:
    """The files a model library's ``.json`` names: itself, the library and the library's source
    (empty if the entry has no readable record)."""
    d = entry.files[0].parent
    meta = read_record(d / f"{entry.key}.json")
    lib = meta.get("library") if meta else None
    if not isinstance(lib, str):
        return set()
    return {d / f"{entry.key}.json", d / lib, (d / lib).with_suffix(".c")}


def index_library(entry: Entry) -> tuple[str, str] | None:
    """The model spec of an index entry and the library key it names, or ``None`` if unreadable."""
    rec = read_record(entry.files[0])
    if rec is None or not isinstance(rec.get("spec"), str) or not isinstance(rec.get("library"), str):
        return None
    return rec["spec"], rec["library"]


def index_keys(plain: str) -> tuple[str, str]:
    """The library keys an index entry naming ``plain`` may be served by: the library with the
    derivative kernels and the plain one (:func:`amble.backend.index.lookup`)."""
    return cache.derivatives_key(plain), plain


def _specs(index: list[Entry]) -> dict[str, list[str]]:
    out: dict[str, list[str]] = {}
    for e in index:
        hit = index_library(e)
        if hit is not None:
            for key in index_keys(hit[1]):
                if hit[0] not in out.setdefault(key, []):
                    out[key].append(hit[0])
    return out


def building(contents: Contents, now: float | None = None) -> list[Entry]:
    """The temporaries of builds in progress: those younger than the cache's orphan age."""
    now = time.time() if now is None else now
    return [e for e in contents.temporaries if now - e.last_used <= cache.ORPHAN_AGE]


def info(d: Path | None = None) -> dict[str, Any]:
    """The cache directory, whether amble can use it, its entries counted by kind, its total size
    (bytes, amble's files and any others), the builds in progress, and the toolchain a build
    would use now: compiler command, the first line of its ``--version``, the flags it would pass
    (:func:`amble.backend.cache.cflags`)."""
    d, why = cache.configured() if d is None else (d, None)
    out: dict[str, Any] = {"directory": str(d), "usable": why is None}
    if why is not None:
        out["reason"] = why
    c = scan(d) if why is None else Contents(d)
    other = sum(s.st_size for s in map(lstat, [*c.other, d / TAG]) if s is not None)
    out.update(models=len(c.models), runtimes=len(c.runtimes), index_entries=len(c.index), stamps=len(c.stamps),
               builds_in_progress=len(building(c)), other_files=len(c.other),
               bytes=sum(e.bytes for e in c.entries()) + other)
    try:
        cc = cache.compiler()
        ident = cache.compiler_identity(cc).strip().splitlines()
        out["compiler"] = {"command": cc, "version": ident[0] if ident else None}
    except CompileError as e:  # no compiler: the cache can still be seen and cleared
        out["compiler"] = {"command": None, "version": None, "error": str(e)}
    out["cflags"] = cache.cflags()
    return out
