"""The ctypes view of one compiled system's library (:class:`Kernels`): its entry points typed
once at load, calls at a single state (right-hand side, dynamics, guards, resets and their exact
derivatives), at many states per compiled call, and batches of walks and section projections.

Apart from :mod:`amble.backend.kernels`, which decides which library a system is served (the
in-process tables, the disk cache, a fresh build): this module only opens one library it is
given and calls into it. A library whose Python↔C layout (:data:`amble.backend.abi.LAYOUT`)
differs from this loader's is refused.
"""

from __future__ import annotations

import ctypes
import threading
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import CompileError, ModelError, ParameterError, StateError
from . import abi
from .c_args import (
    _DATA,
    _DATA_AT,
    _F64,
    _NO_PARAMS,
    _NO_PARAMS_ADDRESS,
    _STEP,
    _arg,
    _call_tables,
    _dptr,
    _frombuffer,
    _i64ptr,
    _iptr,
    _lookup,
    _matrix,
    _ndarray,
    _p,
    _rows,
    _vec,
)

__all__ = ["Kernels"]

#: The per-state entry points: name, result type, number of address arguments (after the mode or
#: transition index and the time).
_PER_STATE = (("amble_rhs", ctypes.c_int, 3), ("amble_guards", None, 3), ("amble_reset", ctypes.c_int, 4),
              ("amble_dynamics", None, 5), ("amble_rhs_jac", ctypes.c_int, 4), ("amble_rhs_jacp", ctypes.c_int, 3),
              ("amble_rhs_jac_all", ctypes.c_int, 4), ("amble_surfaces_grad", None, 3),
              ("amble_reset_jac", ctypes.c_int, 3))
_void, _double, _byref = ctypes.c_void_p, ctypes.c_double, ctypes.byref


def _held(lib: ctypes.CDLL, name: str, res: Any) -> Any:
    """Entry point ``name`` as the per-state calls call it: without releasing the GIL
    (``ctypes.PYFUNCTYPE``; a per-state kernel takes less than releasing and taking back the GIL
    costs — the loops over many states, ``amble_rows`` and the batches, release it) and without
    argument types, so that ctypes passes every argument as it is instead of calling a converter
    per argument: the caller hands the index as a Python ``int`` (a C ``int``), the time as a
    ``c_double`` and every address as a ``c_void_p``, a C array or a ``byref`` — never a plain
    ``int`` for an address (it would be cut to a C ``int``). (Argument types for the first two
    only would make ctypes call it as a variadic function, which differs on some platforms.)"""
    return ctypes.PYFUNCTYPE(res)((name, lib))


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
        info = np.zeros(9, dtype=np.int64)
        lib.amble_info.argtypes = [_i64ptr]
        lib.amble_info(info.ctypes.data_as(_i64ptr))
        self.n_modes, self.nx_max, self.n_tr, self.n_points = (int(v) for v in info[:4])
        self.layout = int(info[6])
        self.sc = int(info[7])  # columns of a sensitivity row (state, then parameters)
        self.nx_capacity = int(info[8])  # the state capacity of the shared runtime it links (backend/runtime.py)
        if self.layout != abi.LAYOUT:
            raise CompileError(
                f"compiled model {so} has interface layout {self.layout}, this amble expects {abi.LAYOUT}: "
                f"it is stale; clear the cache ({so.parent})"
            )
        lib.amble_simulate.restype = ctypes.c_int
        # Raw addresses (arr.ctypes.data): the hot entry point is called once per return-map
        # evaluation, and building typed ctypes pointers costs more than a walking step.
        lib.amble_simulate.argtypes = [ctypes.c_void_p] * 14
        # The per-state entry points, typed here for a caller of the library's own; the per-state
        # methods call them through prototypes of their own (see _held).
        ptrs = lambda n: [ctypes.c_void_p] * n  # noqa: E731
        for name, res, args in _PER_STATE:
            f = getattr(lib, name)
            f.restype, f.argtypes = res, [ctypes.c_int, ctypes.c_double, *ptrs(args)]
        lib.amble_rows_energy.argtypes = [ctypes.c_int64, _dptr, _iptr, _dptr, _dptr, _dptr]
        lib.amble_rows_kinematics.argtypes = [ctypes.c_int64, _dptr, _iptr, _dptr, _dptr, _dptr, _dptr]
        lib.amble_rows.restype = ctypes.c_int64
        lib.amble_rows.argtypes = [ctypes.c_int64, ctypes.c_int, ctypes.c_int, ctypes.c_void_p, ctypes.c_int64,
                                   ctypes.c_void_p, ctypes.c_int64, ctypes.c_void_p, ctypes.c_int64,
                                   ctypes.c_void_p, ctypes.c_int64]
        self._fast_tables()
        self.simulate_raw = lib.amble_simulate
        lib.amble_walk_batch.restype = None
        lib.amble_walk_batch.argtypes = [ctypes.c_int64, ctypes.c_void_p, ctypes.c_int] + [ctypes.c_void_p] * 2 + \
            [ctypes.c_int64] + [ctypes.c_void_p] * 3 + [ctypes.c_int64, ctypes.c_int64, ctypes.c_double] + \
            [ctypes.c_void_p] * 5
        self._walk_batch = lib.amble_walk_batch
        lib.amble_project_batch.restype = None
        lib.amble_project_batch.argtypes = [ctypes.c_int64, ctypes.c_void_p, ctypes.c_int, ctypes.c_int, ctypes.c_int,
                                            ctypes.c_double, ctypes.c_void_p, ctypes.c_void_p, ctypes.c_int,
                                            ctypes.c_void_p, ctypes.c_void_p, ctypes.c_double, ctypes.c_int,
                                            ctypes.c_void_p, ctypes.c_void_p]
        self._project_batch = lib.amble_project_batch

    # -- single states (analysis, tests, a user's own loop); the hot path is amble_simulate.
    # Inputs: any array-like; a float64 C-contiguous writable ndarray of the right shape is handed
    # to C as it is (its address), anything else is converted first. Shapes are checked before any
    # address reaches C. Every call returns fresh arrays (nothing is reused between calls); the
    # arrays one call returns may be views of one buffer of its own (not C-contiguous, e.g. ∂f/∂x).
    def _fast_tables(self) -> None:
        """What the per-state calls look up, worked out once: mode and transition indices by
        name, state lengths, rows of guards and surfaces per mode, the entry points."""
        meta, lib = self.meta, self._lib
        modes, trs = meta["modes"], meta["transitions"]
        self._mode_ix = {m: i for i, m in enumerate(modes)}
        self._tr_ix = {tr["name"]: i for i, tr in enumerate(trs)}
        self._nx = tuple(meta["nx"])
        self._npar = len(meta["params"])
        self._n_guards = tuple(sum(tr["source"] == m for tr in trs) for m in modes)
        self._n_surfaces = tuple(g + sum(sw["mode"] == m for sw in meta["switches"])
                                 for m, g in zip(modes, self._n_guards))
        self._tr_nx = tuple((self._nx[modes.index(tr["source"])],
                             self._nx[modes.index(tr["target"])] if tr["target"] else
                             self._nx[modes.index(tr["source"])]) for tr in trs)
        self._p_seen: tuple[Any, Any] = (None, None)
        self._derivatives = bool(meta.get("derivatives"))
        self._guard_len = max(self.n_tr, 1)
        c = {name: _held(lib, name, res) for name, res, _ in _PER_STATE}
        self._c_rhs, self._c_guards, self._c_reset = c["amble_rhs"], c["amble_guards"], c["amble_reset"]
        self._c_dynamics, self._c_rhs_jac_all = c["amble_dynamics"], c["amble_rhs_jac_all"]
        self._c_surfaces_grad, self._c_reset_jac = c["amble_surfaces_grad"], c["amble_reset_jac"]
        self._modes = tuple(modes)
        calls = _call_tables(self._nx, self._n_guards, self._n_surfaces, self._tr_nx, self.nx_max, self.sc,
                             self._npar, self._guard_len, len(meta["switches"]))
        self._rhs_calls, self._guards_calls, self._dynamics_calls = calls["rhs"], calls["guards"], calls["dynamics"]
        self._rhs_jacobian_calls, self._surface_calls = calls["rhs_jacobian"], calls["surface_gradients"]
        self._reset_calls, self._reset_jacobian_calls = calls["reset"], calls["reset_jacobian"]

    def mode_index(self, mode: str | int) -> int:
        """The index of a mode given by name or index (:class:`~amble.errors.ModelError` if none)."""
        if type(mode) is int and 0 <= mode < self.n_modes:
            return mode
        return _lookup("mode", mode, self._mode_ix, self.n_modes)

    def transition_index(self, transition: str | int) -> int:
        """The index of a transition given by name or index (:class:`~amble.errors.ModelError` if none)."""
        if type(transition) is int and 0 <= transition < self.n_tr:
            return transition
        return _lookup("transition", transition, self._tr_ix, self.n_tr)

    def _xp_any(self, nx: int, x: Any, p: Any) -> tuple[Any, np.ndarray, Any, np.ndarray]:
        """Addresses (``c_void_p``) of a state of ``nx`` entries and of the parameters (see
        :func:`_arg`), with the arrays at them (to keep alive until the call returns). The
        caller's last parameter array is remembered with its address: it is passed call after
        call, and holding it keeps its memory where it is (NumPy refuses to resize an array that
        is referenced). Each per-state call first tests for the common case: a contiguous
        float64 ndarray of the right shape for the state, and that same parameter array
        (:meth:`_addresses`)."""
        ax, x = _arg(x, nx, StateError, "state")
        seen = self._p_seen
        if p is seen[0] and p.dtype is _F64:
            return _void(ax), x, seen[1], p
        if self._npar == 0:  # no parameters: any placeholder of ≤ 1 entry (C reads none of it)
            if np.size(p) > 1:
                raise ParameterError(f"system {self.meta['name']!r} has no parameters, got {np.size(p)} values")
            q, ap = _NO_PARAMS, _void(_NO_PARAMS_ADDRESS)
        else:
            a, q = _arg(p, self._npar, ParameterError, "parameter vector")
            ap = _void(a)
        if type(p) is np.ndarray and (q is p or self._npar == 0):  # only the caller's own array is remembered
            self._p_seen = (p, ap)
        return _void(ax), x, ap, q

    def _addresses(self, shape: tuple[int], x: Any, p: Any) -> tuple[Any, Any, Any, Any]:
        """A per-state call's state and parameter addresses with the arrays at them (to keep
        alive until the call returns): the common case first — a contiguous float64 state of
        ``shape`` and the parameter array of the previous call — else :meth:`_xp_any`."""
        seen = self._p_seen
        if (type(x) is _ndarray and x.dtype is _F64 and x.shape == shape and x.strides == _STEP
                and p is seen[0] and p.dtype is _F64):
            return _DATA_AT(id(x) + _DATA), x, seen[1], p
        return self._xp_any(shape[0], x, p)

    # Each call below: the mode's (transition's) row of its table (c_args._call_tables), the state
    # and parameter addresses, then one C call (see _held) into a fresh zeroed buffer, whose views
    # are returned. A state's address: a c_void_p over the data field of the array (c_args._DATA).
    def rhs(self, mode: str | int, t: float, x: np.ndarray, p: np.ndarray) -> np.ndarray:
        """The right-hand side ``dx/dt`` of a mode at a state (units of the state per time unit)."""
        mi = mode if type(mode) is int and 0 <= mode < self.n_modes else self.mode_index(mode)
        shape, out_t = self._rhs_calls[mi]
        ax, x, ap, p = self._addresses(shape, x, p)
        buf = out_t()
        if self._c_rhs(mi, _double(float(t)), ax, ap, buf):
            raise ModelError(f"mass matrix is singular or ill-conditioned at state {x.tolist()}")
        return _frombuffer(buf)

    def dynamics(self, mode: str | int, t: float, x: np.ndarray, p: np.ndarray
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Mass matrix ``M``, bias ``h`` and generalized force ``Γ`` at a state (``M q̈ + h = Γ``)."""
        mi = mode if type(mode) is int and 0 <= mode < self.n_modes else self.mode_index(mode)
        shape, out_t, h_at, g_at, rows, mass, h, g = self._dynamics_calls[mi]
        ax, x, ap, p = self._addresses(shape, x, p)
        buf = out_t()
        self._c_dynamics(mi, _double(float(t)), ax, ap, buf, _byref(buf, h_at), _byref(buf, g_at))
        out = _ndarray(rows, _F64, buf)
        return out[mass], out[h], out[g]

    def guards(self, mode: str | int, t: float, x: np.ndarray, p: np.ndarray) -> np.ndarray:
        """The guard values of the transitions from a mode, in order."""
        mi = mode if type(mode) is int and 0 <= mode < self.n_modes else self.mode_index(mode)
        shape, out_t, own = self._guards_calls[mi]
        ax, x, ap, p = self._addresses(shape, x, p)
        buf = out_t()
        self._c_guards(mi, _double(float(t)), ax, ap, buf)
        return _frombuffer(buf)[own]

    def reset(self, transition: str | int, t: float, x: np.ndarray, p: np.ndarray) -> tuple[str, np.ndarray]:
        """Apply a transition's reset to a pre-event state; returns (target mode, post state)."""
        k = transition if type(transition) is int and 0 <= transition < self.n_tr else self.transition_index(transition)
        shape, out_t, target_at = self._reset_calls[k]
        ax, x, ap, p = self._addresses(shape, x, p)
        buf = out_t()
        if self._c_reset(k, _double(float(t)), ax, ap, _byref(buf), _byref(buf, target_at)):
            raise ModelError(f"reset of {self.meta['transitions'][k]['name']!r} failed (singular impulse system)")
        target = buf.target
        return self._modes[target], _frombuffer(buf)[: self._nx[target]]

    # -- exact derivatives (generated from the symbolic model; see backend/variational_codegen.py)
    def _need_derivatives(self) -> None:
        if not self._derivatives:
            raise ModelError(f"system {self.meta['name']!r}: these kernels were built without their derivatives; "
                             "use amble.compiled(system, derivatives=True)")

    def rhs_jacobian(self, mode: str | int, t: float, x: np.ndarray, p: np.ndarray
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(f, ∂f/∂x, ∂f/∂p)`` of a mode's right-hand side at a state."""
        if not self._derivatives:
            self._need_derivatives()
        mi = mode if type(mode) is int and 0 <= mode < self.n_modes else self.mode_index(mode)
        shape, out_t, f_at, rows, f, jx, jp = self._rhs_jacobian_calls[mi]
        ax, x, ap, p = self._addresses(shape, x, p)
        buf = out_t()
        if self._c_rhs_jac_all(mi, _double(float(t)), ax, ap, _byref(buf, f_at), buf):
            raise ModelError(f"mass matrix is singular or ill-conditioned at state {x.tolist()}")
        out = _ndarray(rows, _F64, buf)
        return out[f], out[jx], out[jp]

    def surface_gradients(self, mode: str | int, t: float, x: np.ndarray, p: np.ndarray
                          ) -> tuple[np.ndarray, np.ndarray]:
        """``(∂g/∂x, ∂g/∂p)`` of a mode's guards (one row per transition from it, in order), then
        its switching surfaces."""
        if not self._derivatives:
            self._need_derivatives()
        mi = mode if type(mode) is int and 0 <= mode < self.n_modes else self.mode_index(mode)
        shape, out_t, rows, gx, gp = self._surface_calls[mi]
        ax, x, ap, p = self._addresses(shape, x, p)
        buf = out_t()
        self._c_surfaces_grad(mi, _double(float(t)), ax, ap, buf)
        G = _ndarray(rows, _F64, buf)
        return G[gx], G[gp]

    def reset_jacobian(self, transition: str | int, t: float, x: np.ndarray, p: np.ndarray
                       ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(∂Δ/∂x, ∂Δ/∂p, ∂Δ/∂t)`` of a transition's reset at a pre-event state."""
        if not self._derivatives:
            self._need_derivatives()
        k = transition if type(transition) is int and 0 <= transition < self.n_tr else self.transition_index(transition)
        shape, out_t, rows, dx, dp, dt = self._reset_jacobian_calls[k]
        ax, x, ap, p = self._addresses(shape, x, p)
        buf = out_t()
        if self._c_reset_jac(k, _double(float(t)), ax, ap, buf):
            raise ModelError(f"reset of {self.meta['transitions'][k]['name']!r} failed (singular impulse system)")
        D = _ndarray(rows, _F64, buf)
        return D[dx], D[dp], D[dt]

    # -- many states per call: one compiled loop over the rows (amble_rows; the GIL is released)
    def _many(self, op: str, mode: str | int, t: Any, X: Any, p: Any, width: int) -> np.ndarray:
        """Operation ``op`` (:data:`amble.backend.abi.ROW_OPS`) of ``mode`` at every row of ``X``;
        ``width`` output entries per row. ``t``: one time or one per row; ``p``: one parameter
        vector or one row per state."""
        mi = self.mode_index(mode)
        nx = self._nx[mi]
        X = _matrix(X, nx, StateError, "states")
        n = X.shape[0]
        try:
            t = np.asarray(t, dtype=np.float64)
            P = np.ascontiguousarray(p if self._npar or np.size(p) > 1 else _NO_PARAMS, dtype=np.float64)
        except (TypeError, ValueError):
            raise StateError("times and parameters must be real numbers") from None
        if t.ndim > 1 or (t.ndim == 1 and t.shape != (n,)):
            raise StateError(f"times must be one number or one per state ({n}), got shape {t.shape}")
        t, ts = np.ascontiguousarray(t), t.ndim  # a 0-d time becomes one entry read by every row
        npar = self._npar or 1
        if P.shape != (npar,) and P.shape != (n, npar):
            raise ParameterError(f"parameters must be one vector of {self._npar} or one row of {self._npar} "
                                 f"per state, got shape {P.shape}")
        out = np.zeros((n, width))
        bad = self._lib.amble_rows(n, abi.ROW_OP[op], mi, t.ctypes.data, ts, X.ctypes.data, nx, P.ctypes.data,
                                   npar if P.ndim == 2 else 0, out.ctypes.data, width)
        if bad >= 0:
            raise ModelError(f"mass matrix is singular or ill-conditioned at state {X[bad].tolist()} (row {bad})")
        return out

    def rhs_many(self, mode: str | int, t: float | np.ndarray, X: np.ndarray, p: np.ndarray) -> np.ndarray:
        """:meth:`rhs` at every row of ``X`` (``n × nx``) in one compiled call: ``n × nx``.
        ``t``: one time or one per row; ``p``: one parameter vector or one row per state. Each
        row equals :meth:`rhs` of that row, bit for bit."""
        return self._many("RHS", mode, t, X, p, self._nx[self.mode_index(mode)])

    def dynamics_many(self, mode: str | int, t: float | np.ndarray, X: np.ndarray, p: np.ndarray
                      ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """:meth:`dynamics` at every row of ``X`` in one compiled call: ``M`` (``n × nq × nq``),
        ``h`` and ``Γ`` (``n × nq``), ``nq = nx / 2``. ``t``, ``p`` as for :meth:`rhs_many`."""
        nq = self._nx[self.mode_index(mode)] // 2
        out = self._many("DYNAMICS", mode, t, X, p, nq * nq + 2 * nq)
        return out[:, : nq * nq].reshape(-1, nq, nq), out[:, nq * nq : nq * nq + nq], out[:, nq * nq + nq :]

    def constraint_names(self, mode: str | int) -> list[str]:
        """The names of a mode's holonomic constraint equations, in the order of λ (empty: none)."""
        return list(self.meta.get("constraints", {}).get(self.meta["modes"][self.mode_index(mode)], []))

    def constraint_forces(self, mode: str | int, t: float, x: np.ndarray, p: np.ndarray) -> np.ndarray:
        """The forces ``λ`` of a mode's holonomic constraints at a state (``M q̈ + h = Γ + Jᵀλ``,
        ``J = ∂φ/∂q``; :meth:`amble.Model.holonomic`), one per equation (empty for a mode without)."""
        return self.constraint_forces_many(mode, t, np.asarray(x, dtype=np.float64)[None, :], p)[0]

    def constraint_forces_many(self, mode: str | int, t: float | np.ndarray, X: np.ndarray, p: np.ndarray
                               ) -> np.ndarray:
        """:meth:`constraint_forces` at every row of ``X`` in one compiled call: ``n × m``. ``t``,
        ``p`` as for :meth:`rhs_many`."""
        return self._many("CONSTRAINT_FORCES", mode, t, X, p, len(self.constraint_names(mode)))

    def rhs_jacobian_many(self, mode: str | int, t: float | np.ndarray, X: np.ndarray, p: np.ndarray
                          ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """:meth:`rhs_jacobian` at every row of ``X`` in one compiled call: ``f`` (``n × nx``),
        ``∂f/∂x`` (``n × nx × nx``), ``∂f/∂p`` (``n × nx × len(params)``). ``t``, ``p`` as for
        :meth:`rhs_many`."""
        self._need_derivatives()
        nx = self._nx[self.mode_index(mode)]
        out = self._many("RHS_JAC", mode, t, X, p, nx + nx * self.sc)
        J = out[:, nx:].reshape(-1, nx, self.sc)
        return out[:, :nx], J[:, :, :nx].copy(), J[:, :, self.nx_max : self.nx_max + self._npar].copy()

    def walk_batch(self, mode: str | int, x0: np.ndarray, p: np.ndarray, opt: np.ndarray, iopt: np.ndarray,
                   xref: np.ndarray, steps: int, check_every: int, tol: float, threads: int = 1
                   ) -> dict[str, np.ndarray]:
        """Walk every row of ``x0`` (initial states of ``mode`` at t = 0) for up to ``steps``
        footfalls in one compiled call (which releases the GIL), in runs of ``check_every``
        footfalls each started afresh from the last one's final state, stopping a walk when
        ``max |x − xref| < tol`` after a run. ``p``: the parameters of every walk, or one row per
        walk (``n × len(params)``). ``opt``/``iopt``: the run option layouts of
        :mod:`amble.backend.abi` (capacities ignored: nothing is recorded). ``threads`` > 1:
        that many threads call it at once on the same rows, taking the next unwalked row each
        (one atomic counter), so unequal walks keep every thread busy to the end; each walk is
        the same whichever thread takes it. Returns per walk: ``code`` (status of its last run),
        ``info`` (the transition that ended it, or −1), ``steps`` (footfalls taken),
        ``distance`` (after the last completed run; NaN if none) and ``x`` (final states,
        NaN-padded to ``nx_max``)."""
        mi = self.mode_index(mode)
        nx = self.meta["nx"][mi]
        x0 = np.asarray(x0, dtype=float)
        if x0.ndim != 2 or x0.shape[1] != nx:
            raise StateError(f"initial states must be rows of {nx} entries, got shape {x0.shape}")
        if isinstance(threads, bool) or not isinstance(threads, int) or threads < 1:
            raise StateError(f"threads must be an integer ≥ 1, got {threads!r}")
        xref = _vec(xref, nx)
        n = x0.shape[0]
        xs = np.full((n, self.nx_max), np.nan)
        xs[:, :nx] = x0
        opt = np.ascontiguousarray(opt, dtype=float)
        iopt = np.ascontiguousarray(iopt, dtype=np.int64)
        p = np.ascontiguousarray(p, dtype=float)
        npar = len(self.meta["params"])
        if p.ndim == 2 and p.shape != (n, npar) or p.ndim not in (1, 2):
            raise StateError(f"parameters must be one vector or one row of {npar} per walk, got shape {p.shape}")
        stride = npar if p.ndim == 2 else 0
        out = {"code": np.zeros(n, dtype=np.int32), "info": np.zeros(n, dtype=np.int32),
               "steps": np.zeros(n, dtype=np.int64), "distance": np.zeros(n), "x": np.zeros((n, self.nx_max))}
        addr = lambda a: a.ctypes.data  # noqa: E731
        threads = min(threads, n)
        counter = np.zeros(1, dtype=np.int64)
        args = (n, addr(counter) if threads > 1 else None, mi, addr(xs), addr(p), stride, addr(opt), addr(iopt),
                addr(xref), int(steps), int(check_every), float(tol),
                *(addr(out[k]) for k in ("code", "info", "steps", "distance", "x")))
        if threads <= 1:
            self._walk_batch(*args)
        else:
            workers = [threading.Thread(target=self._walk_batch, args=args) for _ in range(threads - 1)]
            for w in workers:
                w.start()
            self._walk_batch(*args)  # this thread takes rows too
            for w in workers:
                w.join()
        return out

    def project_batch(self, mode: int, transition: int, row: int, t: float, pre: np.ndarray, S: np.ndarray,
                      x: np.ndarray, p: np.ndarray, tol: float, max_iter: int, threads: int = 1
                      ) -> tuple[np.ndarray, np.ndarray]:
        """Put every row of ``x`` (states of the transition's target mode) on its post-impact
        section in one compiled call, by the Newton iteration of
        :meth:`amble.analysis.section.Section.project` from the pre-impact state ``pre`` (guard
        ``row`` of ``mode``, time ``t``, section coordinates ``S``). Returns the post-impact states
        (NaN-padded to ``nx_max``) and per row whether the iteration decided it (``False``: a
        reset that failed, a rank-deficient step, no convergence — left to the full iteration).
        ``threads`` as for :meth:`walk_batch`. Needs the derivative kernels."""
        self._need_derivatives()
        x = np.asarray(x, dtype=float)
        n = x.shape[0]
        xs = np.full((n, self.nx_max), np.nan)
        xs[:, : x.shape[1]] = x
        pre = np.ascontiguousarray(pre, dtype=float)
        S = np.ascontiguousarray(S, dtype=np.int64)
        p = np.ascontiguousarray(p, dtype=float)
        y, ok = np.zeros((n, self.nx_max)), np.zeros(n, dtype=np.int32)
        threads = max(1, min(int(threads), n))
        counter = np.zeros(1, dtype=np.int64)
        args = (n, counter.ctypes.data if threads > 1 else None, int(mode), int(transition), int(row), float(t),
                pre.ctypes.data, S.ctypes.data, len(S), xs.ctypes.data, p.ctypes.data, float(tol), int(max_iter),
                y.ctypes.data, ok.ctypes.data)
        workers = [threading.Thread(target=self._project_batch, args=args) for _ in range(threads - 1)]
        for w in workers:
            w.start()
        self._project_batch(*args)
        for w in workers:
            w.join()
        return y, ok.astype(bool)

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
