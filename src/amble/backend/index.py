"""The warm-start index: from a model's source to its compiled library, without building the model.

The cache key of a library (:func:`amble.backend.cache.structure_key`) is a hash of the
system's symbolic structure, so finding a library by it means building the model first — and
importing SymPy. The index finds it from what the model is *made of* instead. Its entries,
``index-<key>.json`` in the cache directory, are keyed by a hash of

* the model's source files (:func:`amble.models.source_files`: every module of the library for
  a library model, the file itself for ``path.py[:callable]``) and the model's spec;
* amble's version and the sources that the library key covers (the C engine, the backend, the
  derivation and the modelling layer, :func:`amble.backend.cache.source_digest`), and the package
  root that maps the public names to them;
* ``$CC`` and the flags setting (``$AMBLE_CFLAGS`` or the default, with native code the
  processor's identity: :func:`amble.backend.host.flags_setting`; not the compiler found on the
  ``PATH`` nor its ``--version``: finding and running it is the price of a subprocess; a
  compiler upgraded in place, or another found first on the ``PATH``, keeps serving the library
  the previous one built, which computes the same model).

Parameter values (``--set``) do not enter: they are run-time inputs of every library. An entry
holds the library key of the system (:func:`~amble.backend.cache.structure_key`), the SHA-256 of
every other file that was read while the model was built (modules a model file imports, data
it opens; :func:`amble.models.load_traced`), and the system's description
(:func:`amble.backend.compiled.describe`).

A lookup gives a :class:`~amble.backend.compiled.CompiledSystem` only if the entry parses, its
files are unchanged and the library is in the cache with intact bytes
(:func:`~amble.backend.cache.cached`) and loads; otherwise ``None``, and the caller builds the
model as before and records a fresh entry (:func:`record`). An entry that cannot be read is
reported with a :class:`~amble.backend.cache.CacheWarning`. ``AMBLE_WARM_START=0`` turns the
lookup off.
"""

from __future__ import annotations

import json
import os
import warnings
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ..errors import AmbleError
from ..version import __version__
from . import cache, host
from .compiled import FORMAT, CompiledSystem, describe
from .digest import sha256
from .files import write_atomic
from .stamps import stamped_digest

if TYPE_CHECKING:
    from ..modelling.hybrid import HybridSystem

_ROOT_INIT = Path(__file__).resolve().parents[1] / "__init__.py"


def enabled() -> bool:
    """Whether warm-start lookups are on (``$AMBLE_WARM_START`` is not ``0``)."""
    return os.environ.get("AMBLE_WARM_START", "1").strip() != "0"


def index_key(spec: str, sources: Sequence[Path]) -> str:
    """Hash of a model's spec, its source files and amble's generating sources (see the module
    docstring); :class:`OSError` if a source cannot be read."""
    h = sha256(f"amble-index\0{FORMAT}\0{__version__}\0{spec}\0".encode())
    h.update(cache.source_digest().encode())
    h.update(_ROOT_INIT.read_bytes())
    h.update(f"\0{os.environ.get('CC', '')}\0{host.flags_setting()}\0".encode())
    for f in sources:
        h.update(f"{f}\0".encode())
        h.update(Path(f).read_bytes())
    return h.hexdigest()[:32]


def entry_path(spec: str, sources: Sequence[Path], d: Path | None = None) -> Path:
    """Where the index entry of a model lives. The key's hash of the sources is reused from a
    stamp while their file status is unchanged (:mod:`amble.backend.stamps`)."""
    d = d or cache.cache_dir()
    files = [*cache.source_files(), _ROOT_INIT, *map(Path, sources)]
    env = os.environ
    ident = "\0".join(["amble-index", str(FORMAT), __version__, spec, env.get("CC", ""),
                       host.flags_setting(), *map(str, files)])
    return d / f"index-{stamped_digest(d, ident, files, lambda: index_key(spec, sources))}.json"


def lookup(spec: str, sources: Sequence[Path], loader: Callable[[], HybridSystem],
           derivatives: bool = False) -> CompiledSystem | None:
    """The compiled system of a model from the index, or ``None`` (see the module docstring).

    ``loader`` builds the full system when the compiled one is asked for more than its numbers;
    ``derivatives``: the library must hold the derivative kernels."""
    if not enabled():
        return None
    try:
        d = cache.cache_dir()
        path = entry_path(spec, sources, d)
        text = path.read_bytes()  # parsed below: bytes that are not UTF-8 are an unreadable entry
    except OSError:  # no entry (the usual miss), or a source that cannot be read
        return None
    try:
        entry = json.loads(text)
        if entry["format"] != FORMAT or entry["spec"] != spec:
            raise ValueError("another format or model")
        plain, files, info = str(entry["library"]), dict(entry["files"]), dict(entry["system"])
    except (ValueError, KeyError, TypeError) as e:
        warnings.warn(f"amble: warm-start index {path} is unreadable ({type(e).__name__}); building the model",
                      cache.CacheWarning, stacklevel=2)
        return None
    for f, digest in files.items():  # what the model read while it was built must be unchanged
        try:
            if sha256(Path(f).read_bytes()).hexdigest() != digest:
                return None
        except OSError:
            return None
    libraries: dict[bool, tuple[Path, dict]] = {}
    full = cache.cached(d, cache.derivatives_key(plain))
    if full is not None:
        libraries[True] = full
    elif derivatives:
        return None
    else:
        hit = cache.cached(d, plain)
        if hit is None:
            return None
        libraries[False] = hit
    try:
        return CompiledSystem(info, libraries, loader)
    except (AmbleError, KeyError, TypeError, ValueError) as e:  # a library of another layout, a stale entry
        warnings.warn(f"amble: warm-start index {path} does not fit its library ({e}); building the model",
                      cache.CacheWarning, stacklevel=2)
        return None


def record(spec: str, sources: Sequence[Path], system: HybridSystem, files: Sequence[Path] = ()) -> Path | None:
    """Write (or replace) the index entry of a model just built; returns its path, or ``None``
    when the model cannot be indexed (it then simply has no warm start)."""
    if not enabled():
        return None
    try:
        d = cache.cache_dir()
        path = entry_path(spec, sources, d)
        entry: dict[str, Any] = {
            "format": FORMAT, "spec": spec, "library": cache.structure_key(system),
            "files": {str(f): sha256(Path(f).read_bytes()).hexdigest() for f in files},
            "system": describe(system),
        }
        data = json.dumps(entry).encode()
        write_atomic(path, data)
    except (AmbleError, OSError, AttributeError, TypeError, ValueError):
        return None
    return path

