"""Compiled floor for the compass-gait benchmark: hand-written C, one call.

``floor/compass_floor.c`` is an adaptive DOP853 loop (SciPy's step-size
control and 7th-order dense output) with Brent event location on the dense
output and Drake's impact reset, for Drake's compass-gait model.  This module
writes the DOP853 tables (from ``scipy.integrate._ivp.dop853_coefficients``)
into a header, compiles the C file with ``gcc -O3 -march=native -shared`` into
a temporary directory, and walks N steps in a single ``ctypes`` call.

Run ``python -m benchmarks.peers.floor`` for a small table.
"""

from __future__ import annotations

import argparse
import atexit
import ctypes
import functools
import shutil
import statistics
import subprocess
import tempfile
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from benchmarks.peers.compass_scipy import (
    DEFAULT_PARAMS,
    LIMIT_CYCLE_X0,
    MAX_STEP_DURATION,
    reference,
    state_error,
)

#: The C source of the floor loop.
C_SOURCE: Path = Path(__file__).resolve().parent / "floor" / "compass_floor.c"

#: Compiler command (source, output and include dir are appended).
CFLAGS: tuple[str, ...] = ("-O3", "-march=native", "-shared", "-fPIC", "-std=c11")

_PARAM_ORDER = ("mass_hip", "mass_leg", "length_leg", "center_of_mass_leg", "gravity", "slope")


def dop853_header() -> str:
    """C header with SciPy's DOP853 tables (A, B, C, E3, E5, D) at full precision."""
    from scipy.integrate._ivp import dop853_coefficients as dc

    def arr(v: np.ndarray) -> str:
        return "{" + ", ".join(repr(float(x)) for x in np.ravel(v)) + "}"

    def mat(v: np.ndarray) -> str:
        return "{\n  " + ",\n  ".join(arr(row) for row in v) + "\n}"

    n_ext = dc.N_STAGES_EXTENDED
    return "\n".join(
        [
            "/* DOP853 coefficients, generated from scipy.integrate._ivp.dop853_coefficients. */",
            "#pragma once",
            f"#define DOP853_STAGES {dc.N_STAGES}",
            f"#define DOP853_STAGES_EXT {n_ext}",
            f"#define DOP853_POWER {dc.INTERPOLATOR_POWER}",
            f"static const double DOP853_A[{n_ext}][{n_ext}] = {mat(dc.A)};",
            f"static const double DOP853_B[{dc.N_STAGES}] = {arr(dc.B)};",
            f"static const double DOP853_C[{n_ext}] = {arr(dc.C)};",
            f"static const double DOP853_E3[{dc.N_STAGES + 1}] = {arr(dc.E3)};",
            f"static const double DOP853_E5[{dc.N_STAGES + 1}] = {arr(dc.E5)};",
            f"static const double DOP853_D[{dc.INTERPOLATOR_POWER - 3}][{n_ext}] = {mat(dc.D)};",
            "",
        ]
    )


@functools.lru_cache(maxsize=1)
def build() -> tuple[ctypes.CDLL, str]:
    """Compile the floor into a temporary directory; return ``(library, build_dir)``.

    The library is cached for the life of the process; the directory is removed
    at interpreter exit.
    """
    cc = shutil.which("gcc") or shutil.which("cc")
    if cc is None:
        raise RuntimeError("no C compiler (gcc/cc) on PATH")
    build_dir = tempfile.mkdtemp(prefix="amble_floor_")
    atexit.register(shutil.rmtree, build_dir, True)
    (Path(build_dir) / "dop853_tab.h").write_text(dop853_header())
    lib_path = Path(build_dir) / "libcompass_floor.so"
    cmd = [cc, *CFLAGS, "-I", build_dir, str(C_SOURCE), "-o", str(lib_path), "-lm"]
    subprocess.run(cmd, check=True, capture_output=True, text=True)
    lib = ctypes.CDLL(str(lib_path))
    dp = ctypes.POINTER(ctypes.c_double)
    lib.compass_walk.restype = ctypes.c_int
    lib.compass_walk.argtypes = [
        dp,
        dp,
        ctypes.c_int,
        ctypes.c_double,
        ctypes.c_double,
        ctypes.c_double,
        ctypes.c_double,
        dp,
        dp,
        ctypes.POINTER(ctypes.c_long),
    ]
    return lib, build_dir


def simulate(
    x0: Sequence[float] | None = None,
    steps: int = 20,
    rtol: float = 1e-10,
    atol: float = 1e-10,
    event_tol: float = 1e-12,
    params: dict[str, float] | None = None,
) -> dict[str, Any]:
    """Walk ``steps`` steps in one C call (no timing).

    Returns ``post_impact_states`` (``steps x 4``), ``impact_times``,
    ``step_durations``, ``nfev``, ``accepted_steps``, ``rejected_steps`` and
    ``call_wall_s`` (wall time of the ``ctypes`` call).
    """
    lib, _ = build()
    p = dict(DEFAULT_PARAMS)
    if params:
        p.update(params)
    par = np.array([p[k] for k in _PARAM_ORDER], dtype=float)
    x = np.ascontiguousarray(LIMIT_CYCLE_X0 if x0 is None else x0, dtype=float)
    post = np.empty((steps, 4))
    times = np.empty(steps)
    stats = (ctypes.c_long * 3)()
    dp = ctypes.POINTER(ctypes.c_double)
    args = (
        par.ctypes.data_as(dp),
        x.ctypes.data_as(dp),
        steps,
        rtol,
        atol,
        event_tol,
        MAX_STEP_DURATION,
        post.ctypes.data_as(dp),
        times.ctypes.data_as(dp),
        stats,
    )
    t0 = time.perf_counter()
    rc = lib.compass_walk(*args)
    wall = time.perf_counter() - t0
    if rc != 0:
        what = "no foot collision" if rc > 0 else "step size underflow"
        raise RuntimeError(f"floor walk failed in step {abs(rc) - 1}: {what}")
    return {
        "post_impact_states": post,
        "impact_times": times,
        "step_durations": np.diff(times, prepend=0.0),
        "nfev": int(stats[0]),
        "accepted_steps": int(stats[1]),
        "rejected_steps": int(stats[2]),
        "call_wall_s": wall,
    }


def walk(
    x0: Sequence[float] | None = None,
    steps: int = 20,
    rtol: float = 1e-10,
    atol: float = 1e-10,
    repeats: int = 21,
    event_tol: float = 1e-12,
    params: dict[str, float] | None = None,
) -> dict[str, Any]:
    """Time the C floor walking ``steps`` steps (median of ``repeats`` >= 5 calls).

    Returns a dict with ``time_per_step_s`` (median call wall time / ``steps``),
    ``min_time_per_step_s``, ``wall_times_s``, ``post_impact_states``,
    ``impact_times``, ``step_durations``, ``nfev_per_step``,
    ``accepted_steps_per_step``, ``steps``, ``rtol``, ``atol``, ``event_tol``,
    ``repeats``.
    """
    repeats = max(int(repeats), 5)
    walls: list[float] = []
    out: dict[str, Any] = {}
    simulate(x0, steps, rtol, atol, event_tol, params)  # build + warm-up
    for _ in range(repeats):
        out = simulate(x0, steps, rtol, atol, event_tol, params)
        walls.append(out["call_wall_s"])
    return {
        "time_per_step_s": statistics.median(walls) / steps,
        "min_time_per_step_s": min(walls) / steps,
        "wall_times_s": walls,
        "post_impact_states": out["post_impact_states"],
        "impact_times": out["impact_times"],
        "step_durations": out["step_durations"],
        "nfev_per_step": out["nfev"] / steps,
        "accepted_steps_per_step": out["accepted_steps"] / steps,
        "steps": steps,
        "rtol": rtol,
        "atol": atol,
        "event_tol": event_tol,
        "repeats": repeats,
    }


def main(argv: Sequence[str] | None = None) -> None:
    """Print floor timing and accuracy at the benchmark tolerances."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=20, help="walking steps per walk")
    ap.add_argument("--repeats", type=int, default=21, help="timing repeats (>= 5)")
    args = ap.parse_args(argv)

    _, build_dir = build()
    print(f"built {C_SOURCE.name} with gcc {' '.join(CFLAGS)} in {build_dir}")
    ref = reference(LIMIT_CYCLE_X0, args.steps)
    tight = simulate(LIMIT_CYCLE_X0, args.steps, 1e-14, 1e-14, 1e-14)
    cross = state_error(tight["post_impact_states"], ref["post_impact_states"])
    print(
        f"{args.steps} steps; floor at rtol=atol=1e-14 vs SciPy reference: "
        f"max err {cross['max_error']:.1e}"
    )
    print(
        f"{'rtol=atol':>10} {'us/step':>10} {'min us':>9} {'nfev/step':>10} "
        f"{'final err':>10} {'max err':>10}"
    )
    for tol in (1e-8, 1e-10):
        res = walk(LIMIT_CYCLE_X0, args.steps, tol, tol, args.repeats)
        err = state_error(res["post_impact_states"], ref["post_impact_states"])
        print(
            f"{tol:>10.0e} {res['time_per_step_s'] * 1e6:>10.2f} "
            f"{res['min_time_per_step_s'] * 1e6:>9.2f} {res['nfev_per_step']:>10.1f} "
            f"{err['final_error']:>10.2e} {err['max_error']:>10.2e}"
        )


if __name__ == "__main__":
    main()
