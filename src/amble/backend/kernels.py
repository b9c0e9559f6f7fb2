"""Compiled kernels: build the generated C once per model structure, cache it, load it.

The cache key is a hash of the system's *structure* (its symbolic positions, masses, energies,
forces, guards and resets) and of the C templates — never of parameter values, which are
run-time inputs. A warm cache therefore skips derivation, code generation and compilation:
the shared library and its metadata are loaded directly. Builds write to a temporary file and
rename it into place, so concurrent processes (Dask workers) can build the same model safely.

The cache lives in ``$AMBLE_CACHE_DIR`` or ``~/.cache/amble``. ``$CC`` picks the C compiler
(default ``cc``); a C99 compiler is the one system requirement of amble.
"""

from __future__ import annotations

import copy
import ctypes
import hashlib
import json
import os
import shutil
import subprocess
import tempfile
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np
import sympy as sp

from ..errors import CompileError, ModelError, StateError
from ..modelling.hybrid import HybridSystem
from ..version import __version__
from . import abi

_C_DIR = Path(str(resources.files("amble.backend") / "_c"))
_LOADED: dict[str, Kernels] = {}

_dptr = ctypes.POINTER(ctypes.c_double)
_iptr = ctypes.POINTER(ctypes.c_int)
_i64ptr = ctypes.POINTER(ctypes.c_int64)


def cache_dir() -> Path:
    d = Path(os.environ.get("AMBLE_CACHE_DIR") or Path.home() / ".cache" / "amble")
    d.mkdir(parents=True, exist_ok=True)
    return d


def structure_key(system: HybridSystem) -> str:
    """Hash of everything that determines the generated code (not parameter values)."""
    h = hashlib.sha256()
    h.update(__version__.encode())
    for f in sorted(_C_DIR.iterdir()):
        if f.suffix in (".c", ".h"):
            h.update(f.read_bytes())
    h.update(Path(__file__).with_name("codegen.py").read_bytes())
    h.update((Path(__file__).parents[1] / "derivation" / "equations.py").read_bytes())
    for name, m in system.modes.items():
        parts: list[Any] = [name, m.dims, m.q, list(m.params), sorted(m.points.items()), sorted(m.masses.items())]
        parts += [m._k_terms, m._v_terms, m._k_override, m._v_override, m._l_override]
        parts += [m._forces, m.gravity_vector]
        h.update(sp.srepr(parts).encode())
    for tr in system.transitions:
        h.update(repr((tr.name, tr.source, tr.target, tr.terminal, tr.step)).encode())
        h.update(sp.srepr([tr.guard.expr, tr.guard.direction, tr.guard.enabled]).encode())
        h.update(sp.srepr(_reset_repr(tr.reset)).encode())
    h.update(repr(list(system.parameters)).encode())
    return h.hexdigest()[:24]


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


def _compiler() -> str:
    cc = os.environ.get("CC") or next((c for c in ("cc", "gcc", "clang") if shutil.which(c)), None)
    if cc is None or shutil.which(cc.split()[0]) is None:
        raise CompileError(
            "no C compiler found: amble compiles each model to native code; install gcc or clang "
            "(e.g. 'apt-get install gcc') or set $CC"
        )
    return cc


def build(system: HybridSystem) -> Kernels:
    """Compiled kernels of a system, from the in-process cache, the disk cache, or a fresh build."""
    key = structure_key(system)
    if key in _LOADED:
        return _with_defaults(_LOADED[key], system)
    d = cache_dir()
    so, meta_f = d / f"{system.name}-{key}.so", d / f"{system.name}-{key}.json"
    if not (so.exists() and meta_f.exists()):
        from .codegen import generate

        src, meta = generate(system)
        _compile(src, so, d)
        tmp = meta_f.with_suffix(f".{os.getpid()}.tmp")
        tmp.write_text(json.dumps(meta))
        os.replace(tmp, meta_f)
    meta = json.loads(meta_f.read_text())
    k = Kernels(so, meta)
    _LOADED[key] = k
    return _with_defaults(k, system)


def _with_defaults(k: Kernels, system: HybridSystem) -> Kernels:
    """Parameter defaults are not part of the structure (they compile to nothing): take them from
    the system at hand, so two systems that differ only in defaults share one library."""
    defaults = [float(system.parameters[p]) for p in k.meta["params"]]
    if defaults == k.meta["param_defaults"]:
        return k
    view = copy.copy(k)
    view.meta = {**k.meta, "param_defaults": defaults}
    return view


def _compile(src: str, so: Path, d: Path) -> None:
    cc = _compiler()
    flags = os.environ.get("AMBLE_CFLAGS", "-O2").split()
    with tempfile.TemporaryDirectory(dir=d) as tmpd:
        c_file = Path(tmpd) / "model.c"
        c_file.write_text(src)
        out = Path(tmpd) / "model.so"
        cmd = [*cc.split(), *flags, "-std=c99", "-Werror=implicit-function-declaration", "-fPIC", "-shared",
               "-I", str(_C_DIR), str(c_file), "-o", str(out), "-lm"]
        try:
            r = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
        except (OSError, subprocess.TimeoutExpired) as e:
            raise CompileError(f"C compiler failed to run: {e}") from None
        if r.returncode != 0:
            first = next((ln for ln in r.stderr.splitlines() if "error" in ln), r.stderr.strip()[:300])
            raise CompileError(f"C compilation of the generated model failed: {first}")
        shutil.copy(c_file, so.with_suffix(".c"))
        os.replace(out, so)


class Kernels:
    """ctypes view of one compiled system. Arrays passed in must be C-contiguous float64."""

    def __init__(self, so: Path, meta: dict) -> None:
        self.path = so
        self.meta = meta
        try:
            lib = ctypes.CDLL(str(so))
        except OSError as e:
            raise CompileError(f"cannot load compiled model {so}: {e}") from None
        self._lib = lib
        info = np.zeros(8, dtype=np.int64)
        lib.amble_info.argtypes = [_i64ptr]
        lib.amble_info(info.ctypes.data_as(_i64ptr))
        self.n_modes, self.nx_max, self.n_tr, self.n_points = (int(v) for v in info[:4])
        self.layout = int(info[6])
        if self.layout != abi.LAYOUT:
            raise CompileError(
                f"compiled model {so} has interface layout {self.layout}, this amble expects {abi.LAYOUT}: "
                f"it is stale; clear the cache ({so.parent})"
            )
        lib.amble_simulate.restype = ctypes.c_int
        # Raw addresses (arr.ctypes.data): the hot entry point is called once per return-map
        # evaluation, and building typed ctypes pointers costs more than a walking step.
        lib.amble_simulate.argtypes = [ctypes.c_void_p] * 13
        lib.amble_rhs.restype = ctypes.c_int
        lib.amble_rhs.argtypes = [ctypes.c_int, ctypes.c_double, _dptr, _dptr, _dptr]
        lib.amble_guards.argtypes = [ctypes.c_int, ctypes.c_double, _dptr, _dptr, _dptr]
        lib.amble_reset.restype = ctypes.c_int
        lib.amble_reset.argtypes = [ctypes.c_int, ctypes.c_double, _dptr, _dptr, _dptr, _iptr]
        lib.amble_dynamics.argtypes = [ctypes.c_int, ctypes.c_double, _dptr, _dptr, _dptr, _dptr, _dptr]
        lib.amble_rows_energy.argtypes = [ctypes.c_int64, _dptr, _iptr, _dptr, _dptr, _dptr]
        lib.amble_rows_kinematics.argtypes = [ctypes.c_int64, _dptr, _iptr, _dptr, _dptr, _dptr, _dptr]
        self.simulate_raw = lib.amble_simulate

    # -- conveniences over single states (analysis, tests); the hot path is amble_simulate
    def mode_index(self, mode: str | int) -> int:
        if isinstance(mode, int):
            return mode
        try:
            return self.meta["modes"].index(mode)
        except ValueError:
            raise ModelError(f"unknown mode {mode!r}; modes: {', '.join(self.meta['modes'])}") from None

    def rhs(self, mode: str | int, t: float, x: np.ndarray, p: np.ndarray) -> np.ndarray:
        mi = self.mode_index(mode)
        x = _vec(x, self.meta["nx"][mi])
        dx = np.zeros_like(x)
        err = self._lib.amble_rhs(mi, float(t), _p(x), _p(p), _p(dx))
        if err:
            raise ModelError(f"mass matrix is singular or ill-conditioned at state {x.tolist()}")
        return dx

    def dynamics(self, mode: str | int, t: float, x: np.ndarray, p: np.ndarray
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Mass matrix ``M``, bias ``h`` and generalized force ``Γ`` at a state (``M q̈ + h = Γ``)."""
        mi = self.mode_index(mode)
        nx = self.meta["nx"][mi]
        x = _vec(x, nx)
        n = nx // 2
        M, h, G = np.zeros((n, n)), np.zeros(n), np.zeros(n)
        self._lib.amble_dynamics(mi, float(t), _p(x), _p(p), _p(M), _p(h), _p(G))
        return M, h, G

    def guards(self, mode: str | int, t: float, x: np.ndarray, p: np.ndarray) -> np.ndarray:
        mi = self.mode_index(mode)
        x = _vec(x, self.meta["nx"][mi])
        g = np.zeros(max(self.n_tr, 1))
        self._lib.amble_guards(mi, float(t), _p(x), _p(p), _p(g))
        n = sum(1 for tr in self.meta["transitions"] if tr["source"] == self.meta["modes"][mi])
        return g[:n]

    def reset(self, transition: str | int, t: float, x: np.ndarray, p: np.ndarray) -> tuple[str, np.ndarray]:
        """Apply a transition's reset to a pre-event state; returns (target mode, post state)."""
        trs = self.meta["transitions"]
        k = transition if isinstance(transition, int) else [tr["name"] for tr in trs].index(transition)
        src = self.meta["modes"].index(trs[k]["source"])
        x = _vec(x, self.meta["nx"][src])
        out = np.zeros(self.nx_max)
        target = ctypes.c_int(-1)
        err = self._lib.amble_reset(k, float(t), _p(x), _p(p), _p(out), ctypes.byref(target))
        if err:
            raise ModelError(f"reset of {trs[k]['name']!r} failed (singular impulse system)")
        mode = self.meta["modes"][target.value]
        return mode, out[: self.meta["nx"][target.value]].copy()

    def energy_rows(self, t: np.ndarray, modes: np.ndarray, x: np.ndarray, p: np.ndarray) -> np.ndarray:
        t, modes, x = _rows(t, modes, x, self.nx_max, self.n_modes)
        out = np.zeros((len(t), 2))
        self._lib.amble_rows_energy(len(t), _p(t), modes.ctypes.data_as(_iptr), _p(x), _p(p), _p(out))
        return out

    def kinematics_rows(self, t: np.ndarray, modes: np.ndarray, x: np.ndarray, p: np.ndarray
                        ) -> tuple[np.ndarray, np.ndarray]:
        t, modes, x = _rows(t, modes, x, self.nx_max, self.n_modes)
        pos = np.zeros((len(t), self.n_points, 3))
        vel = np.zeros((len(t), self.n_points, 3))
        self._lib.amble_rows_kinematics(len(t), _p(t), modes.ctypes.data_as(_iptr), _p(x), _p(p), _p(pos), _p(vel))
        return pos, vel


def _p(a: np.ndarray) -> Any:
    return a.ctypes.data_as(_dptr)


def _vec(x: Any, n: int) -> np.ndarray:
    x = np.ascontiguousarray(x, dtype=float).ravel()
    if x.shape != (n,):
        raise ModelError(f"state has {x.size} entries, expected {n}")
    return x


def _rows(t: Any, modes: Any, x: Any, nx_max: int, n_modes: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Rows of (time, mode, state) for the row-wise kernels: equal lengths, modes in range, states
    padded to ``nx_max``."""
    t = np.ascontiguousarray(t, dtype=float).ravel()
    modes = np.ascontiguousarray(modes, dtype=np.int32).ravel()
    x = np.asarray(x, dtype=float)
    if x.ndim == 1:
        x = x[None, :]
    if x.ndim != 2 or x.shape[1] > nx_max:
        raise StateError(f"states must be rows of at most {nx_max} entries, got shape {x.shape}")
    if not (len(t) == len(modes) == x.shape[0]):
        raise StateError(f"row counts differ: {len(t)} times, {len(modes)} modes, {x.shape[0]} states")
    if len(modes) and (modes.min() < 0 or modes.max() >= n_modes):
        bad = int(modes[(modes < 0) | (modes >= n_modes)][0])
        raise StateError(f"mode index {bad} out of range (the system has {n_modes} modes)")
    if x.shape[1] < nx_max:
        x = np.hstack([x, np.full((x.shape[0], nx_max - x.shape[1]), np.nan)])
    return t, modes, np.ascontiguousarray(x)
