"""Arrays handed to compiled code and back: their addresses, shapes checked before any address
reaches C, fresh output buffers (their types and views per mode and transition worked out once),
mode and transition indices by name or number.

Apart from :class:`~amble.backend.library.Kernels`, which calls the library: these helpers know
nothing of a library, only of the arrays and indices a call passes (a wrong shape raises the
typed error of :mod:`amble.errors`, never a crash in C).
"""

from __future__ import annotations

import ctypes
import operator
import sys
from typing import Any

import numpy as np

from ..errors import ModelError, StateError

__all__ = ["address"]

_ndarray = np.ndarray

_dptr = ctypes.POINTER(ctypes.c_double)
_iptr = ctypes.POINTER(ctypes.c_int)
_i64ptr = ctypes.POINTER(ctypes.c_int64)


def _p(a: np.ndarray) -> Any:
    return a.ctypes.data_as(_dptr)


_F64 = np.dtype(np.float64)
_addressof = ctypes.addressof
_bytes_of = ctypes.c_char.from_buffer  # a writable C-contiguous buffer of ≥ 1 byte, else an error
_frombuffer = np.frombuffer
_NO_PARAMS = np.zeros(1)  # what a system without parameters is given (C reads none of it)
_NO_PARAMS_ADDRESS = _NO_PARAMS.ctypes.data


def _data_field() -> int | None:
    """Where an ndarray's data pointer sits in the array object, else ``None``: NumPy's
    ``PyArrayObject_fields`` is the object header, then ``char *data`` — an offset NumPy's own C
    macro (``PyArray_DATA``) compiles into every extension module, so it cannot move — and CPython's
    ``id`` is the object's address. Checked here on arrays whose data addresses are known."""
    if sys.implementation.name != "cpython":
        return None
    at = object.__basicsize__  # the object header
    probes = (np.zeros(3), np.arange(5.0)[1:], np.ones((2, 2)).T)
    try:
        ok = all(ctypes.c_void_p.from_address(id(a) + at).value == a.ctypes.data for a in probes)
    except (OverflowError, ValueError):
        ok = False
    return at if ok else None


#: A float64 state of shape ``(n,)`` whose strides are :data:`_STEP` (a contiguous one) is handed to
#: C as ``_DATA_AT(id(x) + _DATA)``, a ``c_void_p`` over its data field (ctypes passes its value),
#: several times cheaper than its buffer interface; a read-only array too (C only reads a state).
#: Where the data field is not found, ``_STEP`` is ``None``, which no strides equal: every state
#: then takes the general way.
_DATA = _data_field()
_DATA_AT = ctypes.c_void_p.from_address
_STEP = (8,) if _DATA is not None else None


def address(a: np.ndarray) -> int:
    """The address of a C-contiguous array's data, several times cheaper than
    ``a.ctypes.data`` (which builds a helper object per call) for a writable array."""
    try:
        return _addressof(_bytes_of(a))
    except (TypeError, ValueError, BufferError):  # read-only or empty: the general way
        if not a.flags.c_contiguous:
            raise StateError("an array handed to compiled code must be C-contiguous") from None
        return a.ctypes.data


def _index(i: Any, n: int) -> int | None:
    """An integer index in ``0 … n − 1`` (a NumPy integer too), else ``None``."""
    if isinstance(i, bool):
        return None
    try:
        i = operator.index(i)
    except TypeError:
        return None
    return i if 0 <= i < n else None


def _lookup(kind: str, key: Any, table: dict[str, int], n: int) -> int:
    """The index of a mode or transition named by ``key`` (a name in ``table`` or an index below
    ``n``); the slow path of ``Kernels.mode_index``/``transition_index``, whose plain-int test
    stays inline because it runs on every per-state call."""
    i = table.get(key) if isinstance(key, str) else _index(key, n)
    if i is None:
        raise ModelError(f"unknown {kind} {key!r}; {kind}s: {', '.join(table)} (or their indices 0 … {n - 1})")
    return i


def _arg(a: Any, n: int, error: type[Exception], what: str) -> tuple[int, np.ndarray]:
    """The address of ``a`` as ``n`` float64 entries in a row, and the array at that address (it
    must be kept alive until the call returns). A float64 C-contiguous writable ndarray of shape
    ``(n,)`` is passed as it is; anything else of ``n`` entries is converted; another size raises
    ``error`` — before any address reaches C."""
    if type(a) is np.ndarray and a.dtype is _F64 and a.shape == (n,):
        try:
            return _addressof(_bytes_of(a)), a
        except (TypeError, ValueError, BufferError):  # read-only, not contiguous, or empty
            pass
    try:
        a = np.ascontiguousarray(a, dtype=np.float64).ravel()
    except (TypeError, ValueError):
        raise error(f"{what} must be {n} real numbers, got {a!r}") from None
    if a.shape != (n,):
        raise error(f"{what} has {a.size} entries, expected {n}")
    return a.ctypes.data, a


def _matrix(a: Any, n: int, error: type[Exception], what: str) -> np.ndarray:
    """``a`` as a C-contiguous float64 array of rows of ``n`` entries (one row: a vector)."""
    try:
        a = np.ascontiguousarray(a, dtype=np.float64)
    except (TypeError, ValueError):
        raise error(f"{what} must be rows of {n} real numbers") from None
    if a.ndim == 1 and a.shape == (n,):
        a = a[None, :]
    if a.ndim != 2 or a.shape[1] != n:
        raise error(f"{what} must be rows of {n} entries, got shape {a.shape}")
    return a


def _vec(x: Any, n: int) -> np.ndarray:
    x = np.ascontiguousarray(x, dtype=float).ravel()
    if x.shape != (n,):
        raise StateError(f"state has {x.size} entries, expected {n}")
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


#: The per-state calls that :func:`_call_tables` works out a row for, per mode, then per transition.
_MODE_CALLS = ("rhs", "guards", "dynamics", "rhs_jacobian", "surface_gradients")
_TRANSITION_CALLS = ("reset", "reset_jacobian")


def _call_tables(nx: tuple[int, ...], n_guards: tuple[int, ...], n_surfaces: tuple[int, ...],
                 tr_nx: tuple[tuple[int, int], ...], nx_max: int, sc: int, npar: int, guard_len: int, n_switches: int
                 ) -> dict[str, tuple[tuple, ...]]:
    """What each per-state call of ``Kernels`` needs, worked out once: per call (key: the method's
    name), one row per mode (transition) — the state's shape, the C type of the output buffer (a
    fresh zeroed one per call; C writes into it and the results returned are views of it), the
    byte offsets of outputs after the first, the buffer's shape and the indices of the views.
    ``n_guards``: each mode's guards; ``n_surfaces``: those plus its switching surfaces;
    ``tr_nx``: (source, target) state length per transition; ``sc``: the columns of a
    sensitivity row (state, then parameters)."""
    c = ctypes.c_double
    par = slice(nx_max, nx_max + npar)  # the parameter columns of a sensitivity row
    n_rows = guard_len + n_switches  # rows of surface gradients written (the longest any mode has)
    t: dict[str, list[tuple]] = {name: [] for name in _MODE_CALLS + _TRANSITION_CALLS}
    for n, n_g, rows in zip(nx, n_guards, n_surfaces):
        s, nq = (n,), n // 2
        t["rhs"].append((s, c * n))
        t["guards"].append((s, c * guard_len, slice(n_g)))
        # rows of nq entries: M (nq rows), then h, then Γ
        t["dynamics"].append((s, c * ((nq + 2) * nq), 8 * nq * nq, 8 * (nq * nq + nq), (nq + 2, nq),
                              slice(nq), nq, nq + 1))
        # the rows of [∂f/∂x, ∂f/∂p] (sc columns), then f in a row of its own
        t["rhs_jacobian"].append((s, c * ((n + 1) * sc), 8 * n * sc, (n + 1, sc),
                                  (n, slice(n)), (slice(n), slice(n)), (slice(n), par)))
        t["surface_gradients"].append((s, c * (n_rows * sc), (n_rows, sc), (slice(rows), slice(n)),
                                       (slice(rows), par)))

    class Post(ctypes.Structure):  # the post state, then the target's index
        _fields_ = [("x", c * nx_max), ("target", ctypes.c_int)]

    for n, nd in tr_nx:
        t["reset"].append(((n,), Post, Post.target.offset))
        t["reset_jacobian"].append(((n,), c * (nx_max * (sc + 1)), (nx_max, sc + 1),
                                    (slice(nd), slice(n)), (slice(nd), par), (slice(nd), sc)))
    return {name: tuple(rows) for name, rows in t.items()}
