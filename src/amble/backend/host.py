"""The C flags amble compiles with, and the machine the code is compiled for.

A model's library and the shared runtime are compiled on the machine that runs them, the first
time they are needed, so by default they are compiled for its processor (``-march=native``): the
integrator's state loops then use the widest vector instructions it has (the compass gait's
walking step: 11 % fewer instructions with AVX2 than with the baseline x86-64 set). Floating-point
contraction is off (``-ffp-contract=off``): no multiply–add is fused, so every result is bitwise
that of a build for the baseline instruction set — only faster.

Native code is not portable, so the cache keys of native builds (:mod:`amble.backend.cache`,
:mod:`amble.backend.index`) include the processor's identity (model and feature flags): a cache
shared by machines of different processors (a home directory on a cluster) holds one library per
kind of processor instead of handing one machine's instructions to another.

``$AMBLE_CFLAGS`` replaces the flags (e.g. ``-O2`` for code any x86-64 runs, or to profile under
valgrind, which does not decode every AVX-512 instruction). A compiler that refuses
``-march=native`` compiles without it. Flags that let the compiler assume no NaN or infinity
occurs (``-ffast-math``, ``-Ofast``, ``-ffinite-math-only``, clang's ``-fno-honor-nans`` and
``-fno-honor-infinities``) would compile away the checks that end a run whose state is no longer
finite (status ``integrator_failure``) and make it run on with NaNs; and ``-ffast-math``,
``-Ofast`` and ``-funsafe-math-optimizations`` on the link line make GCC (before 13) link
``crtfastmath.o`` into the library, which sets flush-to-zero for the *whole process* when the
library loads (every subnormal number in NumPy, SciPy and Python becomes 0). They are replaced by
their harmless parts (:data:`_REPLACED`: reassociation, reciprocals, no signed zeros, no
``errno``), with one :class:`FlagsWarning` per process.
"""

from __future__ import annotations

import os
import warnings
from functools import lru_cache

#: The flags of a build when ``$AMBLE_CFLAGS`` is not set.
DEFAULT_CFLAGS = "-O2 -march=native -ffp-contract=off"

#: Lines of ``/proc/cpuinfo`` that identify what instructions a processor has.
_CPU_FIELDS = ("vendor_id", "cpu family", "model", "model name", "flags", "features", "cpu implementer",
               "cpu architecture", "cpu variant", "cpu part")


#: The parts of the unsafe math flags that keep NaN and infinity and set no processor mode.
_HARMLESS = ("-fno-math-errno", "-fno-signed-zeros", "-fno-trapping-math", "-fassociative-math", "-freciprocal-math")
#: Flags amble does not compile with → what it compiles with instead (see the module docstring).
_REPLACED: dict[str, tuple[str, ...]] = {
    "-ffast-math": _HARMLESS, "-Ofast": ("-O3", *_HARMLESS), "-funsafe-math-optimizations": _HARMLESS[1:],
    "-ffinite-math-only": (), "-fno-honor-nans": (), "-fno-honor-infinities": (),
}


class FlagsWarning(UserWarning):
    """``$AMBLE_CFLAGS`` asked for something amble cannot run with, and was changed."""


def ieee(flags: list[str]) -> tuple[list[str], list[str]]:
    """``flags`` with every flag that assumes finite values or sets flush-to-zero replaced by its
    harmless parts (see the module docstring), and the flags replaced (empty: unchanged)."""
    asked = [f for f in flags if f in _REPLACED]
    if not asked:
        return flags, []
    out = [g for f in flags for g in (_REPLACED.get(f, (f,)))]
    return list(dict.fromkeys(out)), asked


def flags_setting() -> str:
    """The flags as set (``$AMBLE_CFLAGS`` or the default), and with native code the processor's
    identity: what the cache keys hash. Cheap: no compiler is run."""
    return setting_of(os.environ.get("AMBLE_CFLAGS"))


def setting_of(flags: str | None) -> str:
    """:func:`flags_setting` for ``$AMBLE_CFLAGS`` read as ``flags`` (``None``: not set)."""
    return _setting(DEFAULT_CFLAGS if flags is None else flags)


@lru_cache(maxsize=8)
def _setting(flags: str) -> str:
    # one string object per setting: the keys' caches hash it once, not a kilobyte per build()
    used, asked = ieee(flags.split())  # the flags compiled with, not the ones asked for
    if asked:  # said once per setting, whether the library is compiled now or was before
        warnings.warn(f"amble: AMBLE_CFLAGS {' '.join(asked)} would compile away the checks of a state that is no "
                      f"longer finite (or flush subnormal numbers to zero in the whole process); compiling with "
                      f"{' '.join(used)}", FlagsWarning, stacklevel=5)
    flags = " ".join(used)
    return f"{flags}\0{cpu_identity()}" if "native" in flags else flags


def cflags(cc: str) -> list[str]:
    """The flags to compile with, for compiler command ``cc``: the setting with IEEE semantics
    restored (see the module docstring), without its ``native`` options if ``cc`` does not
    accept them."""
    flags = ieee(os.environ.get("AMBLE_CFLAGS", DEFAULT_CFLAGS).split())[0]
    native = [f for f in flags if f.endswith("=native")]
    if native and not _accepts(cc, tuple(native)):
        flags = [f for f in flags if f not in native]
    return flags


@lru_cache(maxsize=1)
def cpu_identity() -> str:
    """The processor's model and feature flags (first processor of ``/proc/cpuinfo``), else the
    platform's machine and processor names."""
    try:
        with open("/proc/cpuinfo", encoding="utf-8", errors="replace") as f:
            lines = []
            for line in f:
                if not line.strip():
                    break  # the first processor's block is enough: they are all alike
                key = line.split(":", 1)[0].strip().lower()
                if key in _CPU_FIELDS:
                    lines.append(line.strip())
        if lines:
            return "\n".join(lines)
    except OSError:
        pass
    import platform  # not on the warm-start path of Linux

    return f"{platform.machine()}\n{platform.processor()}"


@lru_cache(maxsize=8)
def _accepts(cc: str, flags: tuple[str, ...]) -> bool:
    """Whether ``cc`` compiles an empty unit with ``flags`` (once per process and compiler)."""
    import subprocess

    try:
        r = subprocess.run([*cc.split(), *flags, "-x", "c", "-c", "-", "-o", os.devnull], input="int amble_probe;\n",
                           capture_output=True, text=True, timeout=60)
    except (OSError, subprocess.TimeoutExpired):
        return False
    return r.returncode == 0
