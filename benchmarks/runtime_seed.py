"""Cold caches that already hold the model-independent runtime.

Every model library links the same runtime object (:mod:`amble.backend.runtime`: the event loop,
the implicit integrator, sensitivities, batches), compiled once per capacity bucket, compiler and
flags — once per machine, not once per model. A "cold" build in these benchmarks therefore means
*no model compiled*: each run gets a fresh ``AMBLE_CACHE_DIR`` seeded with copies of the runtime
objects, and the runtime's own one-time compile is measured separately (:func:`compile_times`) and
reported in a row of its own.
"""

from __future__ import annotations

import shutil
import tempfile
import time
from pathlib import Path

from benchmarks.common import fresh_cache_dir

#: capacities compiled into the seed: every model of the benchmarks (up to 128 states: the n = 40 chain has 80) fits one
CAPACITIES: tuple[int, ...] = (8, 16, 32, 64, 128)

_SEED: dict[str, object] = {}


def _seed() -> tuple[Path, dict[int, float]]:
    """The directory holding one runtime object per capacity, and the wall time (s) of each compile."""
    if not _SEED:
        from amble.backend import cache, runtime

        d = Path(tempfile.mkdtemp(prefix="amble_bench_runtime_"))
        times = {}
        for cap in CAPACITIES:
            t0 = time.perf_counter()
            runtime.build(d, cap, cache.runtime_toolchain())
            times[cap] = time.perf_counter() - t0
        _SEED.update(dir=d, times=times)
    return _SEED["dir"], _SEED["times"]  # type: ignore[return-value]


def seeded_cache_dir() -> str:
    """A new cache directory with no model in it and the runtime objects copied in; the caller
    removes it."""
    src, _ = _seed()
    d = fresh_cache_dir()
    for f in src.glob("runtime-*"):
        shutil.copy2(f, d)
    return d


def compile_times() -> dict[int, float]:
    """Wall time (s) of the runtime's one-time compile, per capacity (compiled on first use)."""
    return dict(_seed()[1])


def row_text(caps: tuple[int, ...]) -> str:
    """The one-time runtime compile of the capacities ``caps``, for a table cell or a sentence."""
    t = compile_times()
    return ", ".join(f"{t[c]:.2f} s (capacity {c})" for c in caps)


SECTION_NOTE = ("Cold = no model compiled; the model-independent runtime is compiled once per machine "
                "(measured separately, its own row) and every cold cache is seeded with it — honest "
                "because every model's library links that same object "
                "(`tests/backend/test_runtime_shared.py`).")
