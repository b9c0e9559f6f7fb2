"""The on-disk cache of compiled systems: where it is, what a library's key covers, how it is built.

A library is cached under ``<key>-<sha>.so`` (``<sha>``: its content hash) with its loader
metadata in ``<key>.json``.
The key is a hash of everything that shapes the compiled library:

* the system's *structure* — symbolic positions, masses, energies, forces, guards and resets,
  parameter names — but never parameter values or defaults, which are run-time inputs;
* the sources that generate and compile it: the C engine (``backend/_c``), the backend, the
  derivation, and the modelling layer that feeds them (``modelling/*.py``: trees, DAG tools),
  and the amble version;
* the toolchain: ``$CC`` (or the compiler found), its ``--version`` output, and the flags
  (``$AMBLE_CFLAGS``, or the default: code for this machine's processor, whose identity is then
  part of the key — :mod:`amble.backend.host`).

The package sources are hashed once per process and the compiler identity once per compiler.
A system's structural hash is computed once per revision of its declaration. A cheap
fingerprint (the mode objects and the revisions of the system and its models,
:mod:`amble.modelling.revision`) is checked on every call: adding a transition, replacing a mode
or editing a mode's model in place after a build (a damping force, a control law) makes the next
use hash the declaration again and serve what it now says.

The cache heals and cannot be steered:

* file names come from the key and the library's content hash only (``<key>-<sha>.so``; the model
  name is metadata, never a path component);
* ``<key>.json`` names the library and holds its SHA-256; the library is loaded only if its bytes
  match (a truncated, planted or foreign file is never loaded — it is rebuilt);
* every file is written to a temporary name and renamed into place, so concurrent processes (Dask
  workers) can build the same model; build directories a killed compile left behind are removed,
  and nothing else: only what amble can prove it wrote (:mod:`amble.backend.cache_home`);
* the directory is created private (0700), tagged as a cache (``CACHEDIR.TAG``) and refused if
  another user owns it, others may write to it, or it is not a cache (a folder of the user's
  files); a cache that cannot be used falls back to one private directory per user, with one
  warning.

Every library links the model-independent runtime (the event loop, the implicit integrator,
sensitivities, batches: :mod:`amble.backend.runtime`), compiled once per capacity bucket and
toolchain into ``runtime-<key>-<sha>.o`` beside the libraries, with ``runtime-<key>.json`` holding
its SHA-256; it heals in the same way (a damaged object is rebuilt). A library's key covers the
runtime's: the engine sources and the toolchain are in both, and the capacity follows from the
structure.

The cache lives in ``$AMBLE_CACHE_DIR`` (made absolute), else ``$XDG_CACHE_HOME/amble``, else
``~/.cache/amble``. ``$CC`` picks the C compiler (default ``cc``); a C99 compiler is the one
system requirement of amble.
"""

from __future__ import annotations

import json
import os
import time
import weakref
from functools import lru_cache
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ..errors import CompileError
from ..version import __version__
from . import host
from .cache_home import CacheWarning as CacheWarning  # re-exported: where the cache lives is asked of this module
from .cache_home import build_directory, cache_dir, is_build, is_writing
from .cache_home import configured as configured
from .digest import sha256
from .files import sha256_of, write_atomic
from .units import run_compilers, split_units

# shutil, subprocess, tempfile and the runtime's builder (.runtime) are imported where a library is
# compiled: a warm start needs none of them

if TYPE_CHECKING:  # the lookup of a warm cache imports no SymPy (see backend/index.py)
    from ..modelling.hybrid import HybridSystem
    from . import runtime

_PKG = Path(__file__).resolve().parents[1]
#: The C engine's sources (:data:`amble.backend.runtime.C_DIR`, named here so that a warm start
#: does not import the runtime's builder).
C_DIR = _PKG / "backend" / "_c"

#: Python sources that shape the generated code (relative to the package), besides ``backend/_c``.
_SOURCE_GLOBS = ("backend/*.py", "derivation/**/*.py", "modelling/**/*.py")

#: id(system) → (weak reference, fingerprint, structural hash)
_STRUCT: dict[int, tuple[weakref.ref, tuple, str]] = {}


#: Build directories and half-written files (:func:`~amble.backend.cache_home.is_build`,
#: :func:`~amble.backend.cache_home.is_writing`) older than this (s) belong to a compile that was
#: killed; younger ones may be a build in progress.
ORPHAN_AGE = 3600.0

def source_files() -> list[Path]:
    """The C engine and the Python sources that generate a library."""
    files = sorted(f for f in C_DIR.iterdir() if f.suffix in (".c", ".h"))
    return files + sorted({f for pattern in _SOURCE_GLOBS for f in _PKG.glob(pattern)})


@lru_cache(maxsize=1)
def source_digest() -> str:
    """Hash of the amble version and of every file of :func:`source_files` (once per process)."""
    h = sha256(__version__.encode())
    for f in source_files():
        h.update(f.name.encode())
        h.update(f.read_bytes())
    return h.hexdigest()


def compiler() -> str:
    """The C compiler command: ``$CC``, else the first of cc, gcc, clang on the PATH."""
    return _find_compiler(os.environ.get("CC") or "", os.environ.get("PATH") or "")


@lru_cache(maxsize=16)
def _find_compiler(env_cc: str, path: str) -> str:
    import shutil

    cc = env_cc.strip() or next((c for c in ("cc", "gcc", "clang") if shutil.which(c)), None)
    if cc is None or shutil.which(cc.split()[0]) is None:
        raise CompileError(
            "no C compiler found: amble compiles each model to native code; install gcc or clang "
            "(e.g. 'apt-get install gcc') or set $CC"
        )
    return cc


def cflags() -> list[str]:
    """The flags the compiler is given (:mod:`amble.backend.host`: native code by default)."""
    return host.cflags(compiler())


@lru_cache(maxsize=16)
def compiler_identity(cc: str) -> str:
    """``cc --version`` output (once per compiler command); empty if it cannot be run."""
    import subprocess

    try:
        r = subprocess.run([*cc.split(), "--version"], capture_output=True, text=True, timeout=60)
    except (OSError, subprocess.TimeoutExpired):
        return ""
    return r.stdout + r.stderr


def toolchain() -> str:
    """Compiler command, its identity and the flags (as given and as set: with native code the
    processor's identity), as one string."""
    cc = compiler()
    return "\0".join([cc, compiler_identity(cc), *cflags(), host.flags_setting()])


def runtime_toolchain() -> runtime.Toolchain:
    """The toolchain the shared runtime is compiled with: that of the model libraries."""
    from . import runtime

    return runtime.Toolchain(compiler(), cflags(), toolchain())


def _structure_digest(system: HybridSystem) -> str:
    """Hash of the system's structure (not parameter values or defaults)."""
    from ..modelling.dag import dag_srepr  # SymPy: only when a key is computed from a system

    h = sha256()
    for name, m in system.modes.items():
        parts: list[Any] = [name, m.dims, m.q, list(m.params), sorted(m.points.items()), sorted(m.masses.items())]
        parts += [m._k_terms, m._v_terms, m._k_override, m._v_override, m._l_override]
        parts += [m._forces, m.gravity_vector]
        parts += [[(a.symbol, a.on) for a in m.actuators], [m._laws.get(a.symbol, 0) for a in m.actuators]]
        parts += [[a.limit for a in m.actuators] if m.saturated else []]
        vc = m.virtual
        parts += [[vc.outputs, vc.phase, vc.alpha] if vc is not None else []]
        if m.holonomic_constraints:  # absent from an unconstrained mode: its parts are as they were
            parts += [[(k, v, m.baumgarte.get(k)) for k, v in m.holonomic_constraints.items()]]
        if m.held:  # likewise absent where nothing is held
            parts += [["held", m.held]]
        h.update(dag_srepr(parts).encode())
    for tr in system.transitions:
        h.update(repr((tr.name, tr.source, tr.target, tr.terminal, tr.step)).encode())
        h.update(dag_srepr([tr.guard.expr, tr.guard.direction, tr.guard.enabled]).encode())
        h.update(dag_srepr(_reset_repr(tr.reset)).encode())
    h.update(repr(list(system.parameters)).encode())
    return h.hexdigest()


def _reset_repr(reset: Any) -> list:
    if reset is None:
        return []
    out: list[Any] = [type(reset).__name__]
    for k, v in sorted(vars(reset).items()):
        out.append(k)
        if isinstance(v, dict):
            out.append(sorted((str(a), b) for a, b in v.items()))
        else:
            out.append(v)
    return out


def _structure(system: HybridSystem) -> str:
    """The structural hash, computed once per system object (see the module docstring)."""
    sid = id(system)
    fp = fingerprint(system)
    hit = _STRUCT.get(sid)
    if hit is not None and hit[0]() is system and hit[1] == fp:
        return hit[2]
    digest = _structure_digest(system)
    _STRUCT[sid] = (weakref.ref(system, _forget(sid)), fp, digest)
    return digest


def _forget(sid: int) -> Any:
    def drop(ref: weakref.ref) -> None:
        hit = _STRUCT.get(sid)
        if hit is not None and hit[0] is ref:
            del _STRUCT[sid]
    return drop


def structure_key(system: HybridSystem) -> str:
    """Cache key of a system's library: its structure, the generating sources, the toolchain."""
    cc, flags, path = settings()
    return _key(_structure(system), cc or "", host.setting_of(flags), path or "")


def settings() -> tuple[str | None, str | None, str | None]:
    """The environment a library's key reads besides the system: ``$CC``, ``$AMBLE_CFLAGS`` and
    ``$PATH`` (where the compiler is found). Equal settings and an unchanged system
    (:func:`fingerprint`) give the same key."""
    env = os.environ
    return env.get("CC"), env.get("AMBLE_CFLAGS"), env.get("PATH")


def fingerprint(system: HybridSystem) -> tuple:
    """What a system's structural hash is checked against on every use: the identities of the mode
    objects and the revisions of the system and its modes (:mod:`amble.modelling.revision`: any
    edit of a declaration advances one), so an edited declaration is hashed again, never served
    the kernels of what it said before."""
    modes = [(id(m), getattr(m, "revision", 0)) for m in system.modes.values()]
    return (len(system.transitions), getattr(system, "revision", 0), *modes)


@lru_cache(maxsize=256)
def _key(structure: str, env_cc: str, env_flags: str, env_path: str) -> str:
    h = sha256(structure.encode())
    h.update(source_digest().encode())
    h.update(toolchain().encode())
    return h.hexdigest()[:24]


@lru_cache(maxsize=256)  # a pure function of its argument, asked on every build(): hashed once
def derivatives_key(key: str) -> str:
    """Cache key of the library that also holds the derivative kernels (a superset of ``key``'s)."""
    return sha256(f"{key}:derivatives".encode()).hexdigest()[:24]


def library(system: HybridSystem, key: str, derivatives: bool = False) -> tuple[Path, dict]:
    """Path of the system's compiled library and its loader metadata: the cached ones if they are
    intact (:func:`cached`), else built now. ``key`` is the library's own key (for ``derivatives``,
    :func:`derivatives_key`)."""
    d = cache_dir()
    hit = cached(d, key)
    if hit is not None:
        return hit
    return rebuild(system, key, d, derivatives)


def cached(d: Path, key: str) -> tuple[Path, dict] | None:
    """The cached library of ``key`` if its metadata parses and the library's bytes have the
    recorded SHA-256, else ``None``."""
    try:
        meta = json.loads((d / f"{key}.json").read_text())
        so = d / meta["library"]
        ok = so.parent == d and sha256_of(so) == meta["library_sha256"]
    except (OSError, ValueError, KeyError, TypeError):
        return None
    return (so, meta) if ok else None


def rebuild(system: HybridSystem, key: str, d: Path | None = None, derivatives: bool = False) -> tuple[Path, dict]:
    """Generate, compile and record the library of ``system`` under ``key`` (replacing any entry)."""
    from .codegen import generate

    d = d or cache_dir()
    _remove_orphans(d)
    src, meta = generate(system, derivatives=derivatives)
    so, digest = _compile(src, key, d)
    meta = {**meta, "library": so.name, "library_sha256": digest}
    write_atomic(d / f"{key}.json", json.dumps(meta).encode())
    write_atomic(so.with_suffix(".c"), src.encode())  # the generated source, for inspection
    return so, meta


def _remove_orphans(d: Path) -> None:
    """Remove what a killed compile of amble's left behind in ``d``: its build directories
    (:func:`~amble.backend.cache_home.is_build`) and half-written entries, once older than
    :data:`ORPHAN_AGE`. Nothing else is touched, whatever its name."""
    import shutil

    now = time.time()
    try:
        names = os.listdir(d)
    except OSError:
        return
    for p in [d / n for n in names if is_writing(n) or is_build(d / n)]:
        try:
            if now - p.lstat().st_mtime > ORPHAN_AGE:
                shutil.rmtree(p) if p.is_dir() and not p.is_symlink() else p.unlink()
        except OSError:
            pass


def _compile(src: str, key: str, d: Path) -> tuple[Path, str]:
    """Compile ``src`` into ``d/<key>-<sha>.so``; returns the path and the library's SHA-256.

    A generated model unit (it names the capacity of its runtime, :func:`runtime.capacity_of`) is
    linked with the shared runtime object (:mod:`amble.backend.runtime`, compiled once per
    capacity and toolchain); any other source is compiled on its own. A source with a function of
    its own unit (:func:`split_units`) is compiled as two units at once and linked: the largest
    kernel of a big tree model takes as long as everything else together, so on two cores the
    wall time nearly halves. A runtime object not yet cached (a machine's first build) is compiled
    beside the model's units, not before them, and linked when both are done."""
    from concurrent.futures import ThreadPoolExecutor

    from . import runtime

    cc = compiler()
    cap = runtime.capacity_of(src)
    tc = None if cap is None else runtime_toolchain()
    ready = None if cap is None else runtime.cached_object(d, cap, tc)
    pool = ThreadPoolExecutor(1) if cap is not None and ready is None else None
    pending = None if pool is None else pool.submit(runtime.runtime_object, d, cap, tc)
    try:
        with build_directory(d) as tmpd:
            out = tmpd / "model.so"
            base = [*cc.split(), *cflags(), "-std=c99", "-Werror=implicit-function-declaration", "-fPIC"]
            main, own = split_units(src)
            units = [main] if own is None else [main, own]
            files = []
            for i, text in enumerate(units):
                files.append(tmpd / f"model{i or ''}.c")
                files[-1].write_text(text)
            if own is None and pending is None:
                linked = [] if ready is None else [str(ready)]
                run_compilers([[*base, "-shared", "-I", str(C_DIR), str(files[0]), *linked, "-o", str(out), "-lm"]],
                              cc)
            else:
                objs = [f.with_suffix(".o") for f in files]
                run_compilers([[*base, "-c", "-I", str(C_DIR), str(f), "-o", str(o)] for f, o in zip(files, objs)],
                              cc)
                linked = [str(pending.result())] if pending is not None else [] if ready is None else [str(ready)]
                run_compilers([[*base, "-shared", *map(str, objs), *linked, "-o", str(out), "-lm"]], cc)
            if not out.is_file() or out.stat().st_size == 0:
                raise CompileError(f"C compiler {cc!r} reported success but wrote no library")
            digest = sha256_of(out)
            so = d / f"{key}-{digest[:16]}.so"
            os.replace(out, so)
    finally:
        if pool is not None:
            pool.shutdown(wait=True)  # a failed model compile still leaves the runtime finished and cached
    return so, digest
