"""Compiled kernels: the ctypes view of a system's compiled library, and :func:`compiled`, which
loads it from the in-process cache, the disk cache (:mod:`amble.backend.cache`, which also
decides the cache key and compiles), or a fresh build.

A warm cache skips derivation, code generation and compilation: the shared library and its
metadata are loaded directly. A library whose Python↔C layout (:data:`amble.backend.abi.LAYOUT`)
differs from this loader's is refused.
"""

from __future__ import annotations

import copy
import ctypes
import operator
import threading
import weakref
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol, runtime_checkable

import numpy as np

from ..errors import CompileError, ModelError, ParameterError, StateError
from . import abi, cache
from .cache import cache_dir, structure_key

if TYPE_CHECKING:  # loading a cached library imports no SymPy
    from ..modelling.hybrid import HybridSystem

__all__ = ["Kernels", "address", "build", "cache_dir", "compiled", "structure_key"]

_LOADED: dict[str, Kernels] = {}

_dptr = ctypes.POINTER(ctypes.c_double)
_iptr = ctypes.POINTER(ctypes.c_int)
_i64ptr = ctypes.POINTER(ctypes.c_int64)


@runtime_checkable
class CarriesKernels(Protocol):
    """A system that carries its compiled kernels (:class:`~amble.backend.compiled.CompiledSystem`):
    those it holds, else its declared system to build them from."""

    def compiled_kernels(self, derivatives: bool = False) -> Kernels | None: ...

    def symbolic(self) -> HybridSystem: ...


def compiled(system: HybridSystem, derivatives: bool = False) -> Kernels:
    """The compiled kernels of a system, from the in-process cache, the disk cache, or a fresh build.

    ``derivatives``: also the derivative kernels (flow and reset Jacobians, guard gradients) that
    sensitivity runs, exact return-map Jacobians and the implicit integrator need. They are
    several times longer than the rest, so a library is built with them only when asked; one that
    has them serves plain runs too, and is preferred when it is at hand.

    A system that carries its compiled kernels (:class:`~amble.backend.compiled.CompiledSystem`,
    found by the warm-start index) is served those; without the ones asked for, its full system
    is built."""
    if _carries_kernels(system):
        k = system.compiled_kernels(derivatives)
        if k is not None:
            return k
        system = system.symbolic()
    served = (id(system), derivatives, cache.fingerprint(system), *cache.settings())
    hit = _SERVED.get(served)
    if hit is not None and hit[0]() is system:
        return hit[1]
    k = _load(system, derivatives)
    if len(_SERVED) >= 256:  # systems made per call (a sweep over models) would fill it
        _SERVED.clear()
    entry = (weakref.ref(system), k)  # an id reused by a later system finds a dead reference
    _SERVED[served] = entry
    if k.meta.get("derivatives"):  # from now on it serves plain runs too, as _load prefers it
        _SERVED[(served[0], not derivatives, *served[2:])] = entry
    return k


#: Whether instances of a class carry their kernels (:class:`CarriesKernels`), by class: the check
#: of a runtime-checkable protocol looks the class over afresh on every call (tens of µs).
_CARRIES: dict[type, bool] = {}


def _carries_kernels(system: Any) -> bool:
    kind = type(system)
    known = _CARRIES.get(kind)
    if known is None:
        known = _CARRIES[kind] = isinstance(system, CarriesKernels)
    return known


#: What :func:`compiled` served, by (id of the system, derivatives asked, its
#: :func:`~amble.backend.cache.fingerprint`, the :func:`~amble.backend.cache.settings` its key
#: reads) → (weak reference to the system, kernels): working out the key and the defaults again
#: took longer than the rest of a short :func:`~amble.simulation.simulate.simulate` call's
#: checks together. Weak: a served system is not kept alive by this table.
_SERVED: dict[tuple, tuple[weakref.ref, Kernels]] = {}


#: the name of :func:`compiled` inside the package
build = compiled


def _load(system: HybridSystem, derivatives: bool) -> Kernels:
    """The kernels of ``system``, without the table of served ones (see :func:`compiled`)."""
    plain = cache.structure_key(system)
    full = cache.derivatives_key(plain)
    k = _LOADED.get(full) or (None if derivatives else _LOADED.get(plain))
    if k is None and not derivatives and cache.cached(cache.cache_dir(), full) is not None:
        derivatives = True  # already compiled with them: no second build
    if k is None:
        key = full if derivatives else plain
        so, meta = cache.library(system, key, derivatives)
        try:
            k = Kernels(so, meta)
        except CompileError:  # intact bytes that do not load (another layout, a foreign build): rebuild once
            so, meta = cache.rebuild(system, key, derivatives=derivatives)
            k = Kernels(so, meta)
        _LOADED[key] = k
    return _with_defaults(k, system)


def _with_defaults(k: Kernels, system: HybridSystem) -> Kernels:
    """Parameter defaults are not part of the structure (they compile to nothing): take them from
    the system at hand, so two systems that differ only in defaults share one library."""
    given = {getattr(s, "name", None) or str(s): v for m in system.modes.values() for s, v in m.params.items()}
    defaults = [float(given[p]) for p in k.meta["params"]]
    if defaults == k.meta["param_defaults"]:
        return k
    view = copy.copy(k)
    view.meta = {**k.meta, "param_defaults": defaults}
    return view


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
        # The per-state entry points take raw addresses (void *): typed ctypes pointers built per call
        # (ndarray.ctypes.data_as) cost several times the call itself.
        ptrs = lambda n: [ctypes.c_void_p] * n  # noqa: E731
        for name, res, args in (("amble_rhs", ctypes.c_int, ptrs(3)), ("amble_guards", None, ptrs(3)),
                                ("amble_reset", ctypes.c_int, ptrs(4)), ("amble_dynamics", None, ptrs(5)),
                                ("amble_rhs_jac", ctypes.c_int, ptrs(4)), ("amble_rhs_jacp", ctypes.c_int, ptrs(3)),
                                ("amble_rhs_jac_all", ctypes.c_int, ptrs(4)),
                                ("amble_surfaces_grad", None, ptrs(3)), ("amble_reset_jac", ctypes.c_int, ptrs(3))):
            f = getattr(lib, name)
            f.restype, f.argtypes = res, [ctypes.c_int, ctypes.c_double, *args]
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
        self._p_seen: tuple[Any, int] = (None, 0)
        self._derivatives = bool(meta.get("derivatives"))
        self._guard_len = max(self.n_tr, 1)
        self._surface_len = (self._guard_len + len(meta["switches"])) * self.sc
        self._c_rhs, self._c_guards, self._c_reset = lib.amble_rhs, lib.amble_guards, lib.amble_reset
        self._c_dynamics, self._c_rhs_jac_all = lib.amble_dynamics, lib.amble_rhs_jac_all
        self._c_surfaces_grad, self._c_reset_jac = lib.amble_surfaces_grad, lib.amble_reset_jac

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

    def _xp(self, nx: int, x: Any, p: Any) -> tuple[int, np.ndarray, int, np.ndarray]:
        """Addresses of a state of ``nx`` entries and of the parameters (see :func:`_arg`), with
        the arrays at them (to keep alive until the call returns). The caller's last parameter
        array is remembered with its address: it is passed call after call, and holding it keeps
        its memory where it is (NumPy refuses to resize an array that is referenced)."""
        ax, x = _arg(x, nx, StateError, "state")
        seen = self._p_seen
        if p is seen[0] and p.dtype is _F64:
            return ax, x, seen[1], p
        if self._npar == 0:  # no parameters: any placeholder of ≤ 1 entry (C reads none of it)
            if np.size(p) > 1:
                raise ParameterError(f"system {self.meta['name']!r} has no parameters, got {np.size(p)} values")
            q, ap = _NO_PARAMS, _NO_PARAMS_ADDRESS
        else:
            ap, q = _arg(p, self._npar, ParameterError, "parameter vector")
        if type(p) is np.ndarray and (q is p or self._npar == 0):  # only the caller's own array is remembered
            self._p_seen = (p, ap)
        return ax, x, ap, q

    def rhs(self, mode: str | int, t: float, x: np.ndarray, p: np.ndarray) -> np.ndarray:
        """The right-hand side ``dx/dt`` of a mode at a state (units of the state per time unit)."""
        mi = mode if type(mode) is int and 0 <= mode < self.n_modes else self.mode_index(mode)
        nx = self._nx[mi]
        ax, x, ap, p = self._xp(nx, x, p)
        buf = _out(nx)
        if self._c_rhs(mi, float(t), ax, ap, buf):
            raise ModelError(f"mass matrix is singular or ill-conditioned at state {x.tolist()}")
        return _frombuffer(buf)

    def dynamics(self, mode: str | int, t: float, x: np.ndarray, p: np.ndarray
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Mass matrix ``M``, bias ``h`` and generalized force ``Γ`` at a state (``M q̈ + h = Γ``)."""
        mi = mode if type(mode) is int and 0 <= mode < self.n_modes else self.mode_index(mode)
        nx = self._nx[mi]
        n = nx // 2
        ax, x, ap, p = self._xp(nx, x, p)
        buf = _out(n * n + 2 * n)
        a0 = _addressof(buf)
        self._c_dynamics(mi, float(t), ax, ap, a0, a0 + 8 * n * n, a0 + 8 * (n * n + n))
        out = _frombuffer(buf)
        return out[: n * n].reshape(n, n), out[n * n : n * n + n], out[n * n + n :]

    def guards(self, mode: str | int, t: float, x: np.ndarray, p: np.ndarray) -> np.ndarray:
        """The guard values of the transitions from a mode, in order."""
        mi = mode if type(mode) is int and 0 <= mode < self.n_modes else self.mode_index(mode)
        ax, x, ap, p = self._xp(self._nx[mi], x, p)
        buf = _out(self._guard_len)
        self._c_guards(mi, float(t), ax, ap, buf)
        return _frombuffer(buf)[: self._n_guards[mi]]

    def reset(self, transition: str | int, t: float, x: np.ndarray, p: np.ndarray) -> tuple[str, np.ndarray]:
        """Apply a transition's reset to a pre-event state; returns (target mode, post state)."""
        k = transition if type(transition) is int and 0 <= transition < self.n_tr else self.transition_index(transition)
        ax, x, ap, p = self._xp(self._tr_nx[k][0], x, p)
        buf = _out(self.nx_max + 1)  # the post state, then the target's index (an int in the last slot)
        a0 = _addressof(buf)
        if self._c_reset(k, float(t), ax, ap, a0, a0 + 8 * self.nx_max):
            raise ModelError(f"reset of {self.meta['transitions'][k]['name']!r} failed (singular impulse system)")
        target = ctypes.c_int.from_buffer(buf, 8 * self.nx_max).value
        return self.meta["modes"][target], _frombuffer(buf)[: self._nx[target]]

    # -- exact derivatives (generated from the symbolic model; see backend/variational_codegen.py)
    def _need_derivatives(self) -> None:
        if not self._derivatives:
            raise ModelError(f"system {self.meta['name']!r}: these kernels were built without their derivatives; "
                             "use amble.compiled(system, derivatives=True)")

    def rhs_jacobian(self, mode: str | int, t: float, x: np.ndarray, p: np.ndarray
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(f, ∂f/∂x, ∂f/∂p)`` of a mode's right-hand side at a state."""
        self._need_derivatives()
        mi = mode if type(mode) is int and 0 <= mode < self.n_modes else self.mode_index(mode)
        nx = self._nx[mi]
        ax, x, ap, p = self._xp(nx, x, p)
        buf = _out(nx + nx * self.sc)  # f, then the rows of [∂f/∂x, ∂f/∂p] of sc columns
        a0 = _addressof(buf)
        if self._c_rhs_jac_all(mi, float(t), ax, ap, a0, a0 + 8 * nx):
            raise ModelError(f"mass matrix is singular or ill-conditioned at state {x.tolist()}")
        out = _frombuffer(buf)
        J = out[nx:].reshape(nx, self.sc)
        return out[:nx], J[:, :nx], J[:, self.nx_max : self.nx_max + self._npar]

    def surface_gradients(self, mode: str | int, t: float, x: np.ndarray, p: np.ndarray
                          ) -> tuple[np.ndarray, np.ndarray]:
        """``(∂g/∂x, ∂g/∂p)`` of a mode's guards (one row per transition from it, in order), then
        its switching surfaces."""
        self._need_derivatives()
        mi = mode if type(mode) is int and 0 <= mode < self.n_modes else self.mode_index(mode)
        nx = self._nx[mi]
        ax, x, ap, p = self._xp(nx, x, p)
        buf = _out(self._surface_len)
        self._c_surfaces_grad(mi, float(t), ax, ap, buf)
        rows = self._n_surfaces[mi]
        G = _frombuffer(buf)[: rows * self.sc].reshape(rows, self.sc)
        return G[:, :nx], G[:, self.nx_max : self.nx_max + self._npar]

    def reset_jacobian(self, transition: str | int, t: float, x: np.ndarray, p: np.ndarray
                       ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(∂Δ/∂x, ∂Δ/∂p, ∂Δ/∂t)`` of a transition's reset at a pre-event state."""
        self._need_derivatives()
        k = transition if type(transition) is int and 0 <= transition < self.n_tr else self.transition_index(transition)
        nx, nd = self._tr_nx[k]
        ax, x, ap, p = self._xp(nx, x, p)
        buf = _out(self.nx_max * (self.sc + 1))
        if self._c_reset_jac(k, float(t), ax, ap, buf):
            raise ModelError(f"reset of {self.meta['transitions'][k]['name']!r} failed (singular impulse system)")
        D = _frombuffer(buf).reshape(self.nx_max, self.sc + 1)
        return D[:nd, :nx], D[:nd, self.nx_max : self.nx_max + self._npar], D[:nd, self.sc]

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


def _p(a: np.ndarray) -> Any:
    return a.ctypes.data_as(_dptr)


_F64 = np.dtype(np.float64)
_addressof = ctypes.addressof
_bytes_of = ctypes.c_char.from_buffer  # a writable C-contiguous buffer of ≥ 1 byte, else an error
_frombuffer = np.frombuffer
_OUT: dict[int, type] = {}
_NO_PARAMS = np.zeros(1)  # what a system without parameters is given (C reads none of it)
_NO_PARAMS_ADDRESS = _NO_PARAMS.ctypes.data


def _out(n: int) -> ctypes.Array:
    """A fresh zeroed C array of ``n`` doubles: the output of one call, handed to C as it is and
    returned as an ndarray over the same memory (cheaper than an ndarray's address)."""
    t = _OUT.get(n)
    if t is None:
        t = _OUT[n] = ctypes.c_double * max(n, 1)
    return t()


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
