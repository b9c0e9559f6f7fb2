"""Where the compile cache lives, and what in it amble may call its own.

The cache may only ever remove what it wrote, so a directory is a cache only when it says so: amble
writes a ``CACHEDIR.TAG`` (the Cache Directory Tagging Specification's tag, which backup tools
also honour) into a directory it creates or adopts, and refuses one without it. A directory is
adopted (tagged) when it is empty, when it is amble's default location (``$XDG_CACHE_HOME/amble``
or ``~/.cache/amble``: the XDG convention reserves it for amble), or when every name in it is one
amble writes (:func:`is_amble_name`: a cache of an earlier version). Any other directory — a
project folder given as ``AMBLE_CACHE_DIR=.`` — is refused with the reason, never cleaned.

Inside a tagged cache amble's files are known by their names: libraries, runtime objects, index
entries and stamps by the hashes in their names (:data:`ENTRY_NAMES`), half-written files by
``.<entry name>.<pid>.tmp``, and a compile's working directory (:func:`build_directory`) by
``build-<random>`` *and* a marker file written into it first. A directory named ``build-release``
in the cache is the user's and stays.

A configured directory that cannot be used (another user's, writable by others, read-only, not a
directory, not a cache) falls back, with one :class:`CacheWarning` per process, to one stable
private directory per user in the system's temporary directory (``amble-cache-<uid>``, created
0700, used only if it is a directory of this user's, not a link, and no one else may write to
it), so that repeated runs reuse their libraries instead of leaving a new directory each; if that
one cannot be used either, a process's own temporary directory, removed when it exits.
"""

from __future__ import annotations

import json
import os
import re
import warnings
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

#: The tag file of a cache directory, and the first line the specification requires.
TAG = "CACHEDIR.TAG"
TAG_TEXT = ("Signature: 8a477f597d28d172789f06886806bc55\n"
            "# This directory is amble's compile cache: generated libraries, rebuilt on demand.\n"
            "# 'amble cache clear --all' empties it. See https://bford.info/cachedir/\n")

#: The marker a compile writes first into its working directory: what proves the directory amble's.
BUILD_MARKER = ".amble-build"

#: The names of the cache's entries: a model library (``<key>.json``, ``<key>-<sha>.so`` and
#: ``.c``), a runtime object, a warm-start index entry, a stamp.
ENTRY_NAMES: dict[str, re.Pattern[str]] = {
    "model": re.compile(r"([0-9a-f]{24})(?:-[0-9a-f]{16}\.(?:so|c)|\.json)"),
    "runtime": re.compile(r"runtime-([0-9a-f]{24})(?:-[0-9a-f]{16}\.o|\.json)"),
    "index": re.compile(r"index-[0-9a-f]{32}\.json"),
    "stamp": re.compile(r"stamp-[0-9a-f]{32}\.json"),
}
_WRITING = re.compile(r"\.(.+)\.[0-9]+\.tmp")  # files.write_atomic, stamps: .<name>.<pid>.tmp
_BUILD = re.compile(r"build-[a-z0-9_]{8}")      # tempfile's names: prefix + 8 of [a-z0-9_]
#: What an earlier version's build directory holds (adoption only: it has no marker).
_BUILD_FILES = re.compile(r"(model[0-9]*\.(?:c|o|so)|runtime\.o|amble_abi\.h)")


class CacheWarning(UserWarning):
    """The configured cache directory cannot be used; a private fallback one is used instead."""


def entry_kind(name: str) -> str | None:
    """The kind of cache entry a file name is (a key of :data:`ENTRY_NAMES`), or ``None``."""
    return next((k for k, pat in ENTRY_NAMES.items() if pat.fullmatch(name)), None)


def is_writing(name: str) -> bool:
    """Whether ``name`` is a cache entry being written (``.<entry name>.<pid>.tmp``)."""
    m = _WRITING.fullmatch(name)
    return m is not None and entry_kind(m[1]) is not None


def is_build(p: Path) -> bool:
    """Whether ``p`` is a compile's working directory: named ``build-<random>``, holding the marker
    a compile writes first (not a link)."""
    return (_BUILD.fullmatch(p.name) is not None and not p.is_symlink()
            and os.path.isfile(p / BUILD_MARKER))


#: A key each kind of record amble writes holds (adoption: a file named like a record must be one).
_RECORD_KEYS = {"model": "library_sha256", "runtime": "object", "index": "format", "stamp": "digest"}


def is_amble_name(d: Path, name: str) -> bool:
    """Whether ``name`` in ``d`` is one that amble (of this or an earlier version) writes; a
    record (``.json``) must also read as one of amble's."""
    kind = entry_kind(name)
    if kind and name.endswith(".json"):
        try:
            rec = json.loads((d / name).read_bytes())
        except (OSError, ValueError):
            return False
        return isinstance(rec, dict) and _RECORD_KEYS[kind] in rec
    if name == TAG or kind or is_writing(name):
        return True
    p = d / name
    if _BUILD.fullmatch(name) and p.is_dir() and not p.is_symlink():
        try:
            return all(_BUILD_FILES.fullmatch(f) or f == BUILD_MARKER for f in os.listdir(p))
        except OSError:
            return False
    return False


@contextmanager
def build_directory(d: Path) -> Iterator[Path]:
    """A compile's working directory in cache ``d``, marked as amble's before anything is written
    into it, removed with its contents afterwards."""
    import tempfile

    with tempfile.TemporaryDirectory(prefix="build-", dir=d) as tmpd:
        (Path(tmpd) / BUILD_MARKER).write_bytes(b"")
        yield Path(tmpd)


def default_dir() -> Path:
    """amble's default cache location: ``$XDG_CACHE_HOME/amble``, else ``~/.cache/amble``
    (:class:`RuntimeError` without a home)."""
    xdg = os.environ.get("XDG_CACHE_HOME")
    return Path(xdg) / "amble" if xdg else Path.home() / ".cache" / "amble"


def configured_dir() -> Path:
    """``$AMBLE_CACHE_DIR`` as an absolute path (a relative one is taken from the current
    directory once, so a library's path stays valid wherever it is loaded from), else
    :func:`default_dir`."""
    env = os.environ.get("AMBLE_CACHE_DIR")
    if env:
        return Path(os.path.abspath(os.path.expanduser(env)))
    return default_dir()


def unusable(d: Path, adopt_any: bool = False) -> str | None:
    """Why ``d`` cannot serve as the cache (after creating it private if missing and tagging it if
    it may be adopted, see the module docstring), or ``None``. ``adopt_any``: ``d`` is amble's own
    location, adopted whatever it holds."""
    try:
        d.mkdir(mode=0o700, parents=True, exist_ok=True)
    except OSError as e:
        return f"cannot create it ({e.strerror or e})"
    if not d.is_dir():
        return "it is not a directory"
    st = d.stat()
    if hasattr(os, "getuid") and st.st_uid != os.getuid():
        return "another user owns it"
    if st.st_mode & 0o022:
        return "other users may write to it"
    if not os.access(d, os.W_OK | os.X_OK):
        return "it is not writable"
    if (d / TAG).is_file():
        return None
    return _adopt(d, adopt_any)


def _adopt(d: Path, adopt_any: bool) -> str | None:
    try:
        foreign = [] if adopt_any else [n for n in sorted(os.listdir(d)) if not is_amble_name(d, n)]
    except OSError as e:
        return f"cannot list it ({e.strerror or e})"
    if foreign:
        return (f"it is not an amble cache: it has no {TAG} and holds files amble did not write "
                f"({foreign[0]!r}); give an empty or new directory")
    try:
        tmp = d / f".{TAG}.{os.getpid()}.tmp"
        tmp.write_text(TAG_TEXT)
        os.replace(tmp, d / TAG)
    except OSError as e:  # e.g. a kernel file system that looks writable to root
        return f"cannot write to it ({e.strerror or e})"
    return None


def configured() -> tuple[Path, str | None]:
    """The configured cache directory and why it cannot be used (``None`` if it can)."""
    try:
        d = configured_dir()
        own = "AMBLE_CACHE_DIR" not in os.environ or d == default_dir()
    except RuntimeError as e:  # Path.home() without a home
        return Path("~"), f"no home directory ({e})"
    return d, unusable(d, adopt_any=own)


_FALLBACK: dict[str, Path] = {}


def cache_dir() -> Path:
    """The cache directory: the configured one if it is usable, else the fallback (see the module
    docstring; one :class:`CacheWarning` per process and configured directory)."""
    d, why = configured()
    if why is None:
        return d
    key = str(d)
    if key not in _FALLBACK:
        _FALLBACK[key] = _fallback()
        warnings.warn(f"amble: cache {d} is not usable ({why}); compiling into {_FALLBACK[key]}",
                      CacheWarning, stacklevel=3)
    return _FALLBACK[key]


def _fallback() -> Path:
    import tempfile

    uid = os.getuid() if hasattr(os, "getuid") else os.getlogin()
    mine = Path(tempfile.gettempdir()) / f"amble-cache-{uid}"
    try:
        mine.mkdir(mode=0o700, exist_ok=True)
        st = os.lstat(mine)
        private = (not os.path.islink(mine) and mine.is_dir() and st.st_mode & 0o077 == 0
                   and (not hasattr(os, "getuid") or st.st_uid == os.getuid()))
    except OSError:
        private = False
    if private and unusable(mine, adopt_any=True) is None:
        return mine
    import atexit
    import shutil

    own = Path(tempfile.mkdtemp(prefix="amble-cache-"))  # someone else's: one of this process's own
    atexit.register(shutil.rmtree, own, ignore_errors=True)
    unusable(own, adopt_any=True)  # tagged: a cache like any other while the process lives
    return own


__all__ = ["BUILD_MARKER", "ENTRY_NAMES", "TAG", "CacheWarning", "build_directory", "cache_dir", "configured",
           "configured_dir", "default_dir", "entry_kind", "is_amble_name", "is_build", "is_writing", "unusable"]
