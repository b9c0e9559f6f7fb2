"""The model-independent runtime, compiled once and shared by every model's library.

The hybrid simulation loop — event location, the implicit integrator, sensitivities, recording,
batches (``_c/runtime.c`` and the headers it includes) — is the same code for every model: it
reads the model's sizes and tables as hidden constants and calls its kernels as hidden functions
of the model's unit (``_c/model.h``, ``_c/model_tail.h``), resolved when the model's library is
linked. It is compiled once per *capacity* into an object in the cache directory; a model's build
compiles only its generated kernels (and the DOP853 step, with its right-hand side inlined) and
links them with that object.

The capacity is the state length the integrator's arrays hold (``Step`` in ``_c/stepper.h``): the
model's longest state rounded up to a power of two, at least 8 (:func:`capacity`), so a handful of
runtime objects serve every model. Everything else the runtime sizes by the model is a C99
variable-length array of the model's own length.

An object is cached under ``runtime-<key>-<sha>.o`` with ``runtime-<key>.json`` recording its
SHA-256; the key is a hash of every engine source (``backend/_c``), the interface header
(:func:`amble.backend.abi.c_header`) and the table of integrators
(:func:`~amble.backend.abi.c_steppers`), the compiler, its version and the flags, and the
capacity. An object whose bytes do not match is rebuilt; every file is written under a temporary
name and renamed, so processes building at once each end with a valid object. A model library's
own key (:func:`amble.backend.cache.structure_key`) covers all of these inputs, since the capacity
is a function of the model's structure.
"""

from __future__ import annotations

import json
import os
import re
from functools import lru_cache
from pathlib import Path
from typing import NamedTuple

from ..errors import CompileError
from . import abi
from .cache_home import build_directory
from .digest import sha256
from .files import sha256_of, write_atomic
from .units import run_compilers

C_DIR = Path(__file__).resolve().parent / "_c"  # a package on disk (importlib.resources costs ~10 ms)

#: the macro a generated unit defines to the capacity of the runtime it is linked with
CAPACITY_MACRO = "AMBLE_NXCAP"
#: the header a generated unit ends with (the model as the runtime sees it, and the DOP853 step)
TAIL = "model_tail.h"
#: smallest capacity: the library's walkers (4 to 8 states) share one object
MIN_CAPACITY = 8

#: runtime objects compiled by this process (how often the one-time compile was paid)
COMPILES = 0

_CAP_RE = re.compile(rf"^#define {CAPACITY_MACRO} (\d+)$", re.M)


def capacity(nx_max: int) -> int:
    """The runtime capacity for a model whose longest state has ``nx_max`` entries: the smallest
    power of two ≥ max(nx_max, :data:`MIN_CAPACITY`)."""
    cap = MIN_CAPACITY
    while cap < nx_max:
        cap *= 2
    return cap


def capacity_of(src: str) -> int | None:
    """The capacity a generated unit is written for, or ``None`` for a source that is no model
    unit (it is compiled on its own, without the runtime)."""
    m = _CAP_RE.search(src)
    return int(m[1]) if m else None


class Toolchain(NamedTuple):
    """How the runtime is compiled: the compiler command, its flags, and the identity string that
    keys them (:func:`amble.backend.cache.toolchain`: command, ``--version`` output, flags)."""

    cc: str
    flags: list[str]
    identity: str


def runtime_key(cap: int, tc: Toolchain) -> str:
    """Cache key of the runtime object of capacity ``cap`` built with ``tc``."""
    h = sha256(_sources_digest().encode())
    h.update(tc.identity.encode())
    h.update(f"\0{CAPACITY_MACRO}={cap}".encode())
    return h.hexdigest()[:24]


@lru_cache(maxsize=1)
def _sources_digest() -> str:
    """Hash of the engine's C sources and the Python↔C header, once per process (as the model
    libraries' own :func:`amble.backend.cache.source_digest`)."""
    h = sha256(b"amble-runtime\0")
    for f in sorted(C_DIR.iterdir()):
        if f.suffix in (".c", ".h"):
            h.update(f.name.encode() + b"\0" + f.read_bytes())
    h.update(abi.c_header().encode())
    h.update(abi.c_steppers().encode())
    return h.hexdigest()


def cached_object(d: Path, cap: int, tc: Toolchain) -> Path | None:
    """The cached runtime object of capacity ``cap`` in ``d`` if its bytes are intact, else ``None``."""
    key = runtime_key(cap, tc)
    try:
        meta = json.loads((d / f"runtime-{key}.json").read_text())
        obj = d / meta["object"]
        ok = obj.parent == d and meta["capacity"] == cap and sha256_of(obj) == meta["sha256"]
    except (OSError, ValueError, KeyError, TypeError):
        return None
    return obj if ok else None


def runtime_object(d: Path, cap: int, tc: Toolchain) -> Path:
    """The runtime object of capacity ``cap`` in cache directory ``d``: the cached one if intact,
    else compiled now (a compiler failure is a :class:`~amble.errors.CompileError`)."""
    return cached_object(d, cap, tc) or build(d, cap, tc)


def build(d: Path, cap: int, tc: Toolchain) -> Path:
    """Compile the runtime of capacity ``cap`` into ``d`` and record it (replacing any entry)."""
    global COMPILES
    key, cc = runtime_key(cap, tc), tc.cc
    with build_directory(d) as work:
        tmpd = str(work)
        (work / "amble_abi.h").write_text(abi.c_header())
        (work / "amble_steppers.h").write_text(abi.c_steppers())
        out = work / "runtime.o"
        cmd = [*cc.split(), *tc.flags, "-std=c99", "-Werror=implicit-function-declaration", "-fPIC",
               f"-D{CAPACITY_MACRO}={cap}", "-I", tmpd, "-I", str(C_DIR), "-c", str(C_DIR / "runtime.c"),
               "-o", str(out)]
        run_compilers([cmd], cc, what="the amble runtime")
        COMPILES += 1
        if not out.is_file() or out.stat().st_size == 0:
            raise CompileError(f"C compiler {cc!r} reported success but wrote no library (the amble runtime object)")
        digest = sha256_of(out)
        obj = d / f"runtime-{key}-{digest[:16]}.o"
        os.replace(out, obj)
    write_atomic(d / f"runtime-{key}.json", json.dumps({"object": obj.name, "sha256": digest,
                                                          "capacity": cap}).encode())
    return obj
