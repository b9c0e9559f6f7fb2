"""The one place that talks to the compiled hybrid loop: option and context arrays laid out by
:mod:`amble.backend.abi`, output buffers that grow on demand, and the outcome of a run.

:func:`run` is the lean core: one compiled call integrates, locates events and applies resets;
analysis code (return maps, sweeps) uses it directly, :func:`amble.simulation.simulate.simulate`
wraps it for users.
"""

from __future__ import annotations

import math
import threading
from dataclasses import dataclass
from functools import cached_property, lru_cache
from typing import Any

import numpy as np

from ..backend import abi
from ..backend.abi import CODE, CTX, CTX_X, IOPT, IOPT_FIELDS, OPT, OPT_FIELDS, OUTCOME, sens_layout
from ..backend.c_args import address
from ..backend.library import Kernels
from ..errors import StateError

#: Bytes a run may record (samples and events) before it ends as ``record_limit``: 512 MiB. The
#: buffers are what the trajectory holds (a grown buffer is handed over cut, not copied), so
#: this bounds the growth of the process's peak memory by the recording too.
RECORD_BUDGET = 512 * 2**20

#: Integrators, by name, in the order of their codes (the table of :mod:`amble.backend.abi`).
METHODS = tuple(name for _, name, _, _ in abi.METHODS)
#: Per integrator: do the kernels need their derivatives (an implicit method's Newton matrix)?
NEEDS_JACOBIAN = abi.NEEDS_JACOBIAN
#: The integrators that give sensitivities (their stages carry the variational equations).
SENSITIVITY_METHODS = tuple(m for m in METHODS if abi.HAS_SENSITIVITIES[m])

#: Accepted integrator steps per compiled call: the loop returns this often so that Python can
#: handle signals (Ctrl-C), then resumes exactly where it stopped.
YIELD_STEPS = 20_000

_CX_T, _CX_MODE, _CX_TLAST_STEP, _CX_GRID_T0 = CTX["T"], CTX["MODE"], CTX["TLAST_STEP"], CTX["GRID_T0"]
_CX_TPREV_EVENT, _CX_FRESH = CTX["TPREV_EVENT"], CTX["FRESH"]
_CX_INFO, _CX_STEPS, _CX_EVENTS = CTX["INFO"], CTX["STEPS"], CTX["EVENTS"]
_YIELD, _BUFFER_FULL, _RECORD_LIMIT = CODE["YIELD"], CODE["BUFFER_FULL"], CODE["RECORD_LIMIT"]
#: Codes whose ``ctx`` names the transition (or surface) that ended the run.
_WITH_INFO = (CODE["TERMINAL"], CODE["RESET_FAILED"], CODE["SLIDING"])
_OP_TEND, _OP_SAMPLEDT = OPT["TEND"], OPT["SAMPLEDT"]
_IO_MAXSTEPS, _IO_OUTCAP, _IO_EVCAP = IOPT["MAXSTEPS"], IOPT["OUTCAP"], IOPT["EVCAP"]


@dataclass(frozen=True)
class Options:
    """Integration and outcome settings.

    rtol, atol: the integrator's tolerances (relative, absolute). max_step: largest step (s, 0 = none).
    max_step_time: a walker that makes no footfall for this long has ``fell`` (s, 0 = never).
    zeno_dt, zeno_events: this many consecutive events each closer than ``zeno_dt`` (s) to the
    previous one end the run as ``zeno``. max_events: hard cap on events. nsub: uniform guard
    samples per integration step, in addition to the extremum of the cubic through ``g`` and ``ġ``
    at both step ends (which already finds a guard dipping through zero and back inside a step).
    max_integrator_steps: cap on accepted integrator steps of a run (status
    ``max_integrator_steps``); max_steps_between_events: cap on accepted steps between two
    transitions (status ``stalled``: a stiff or chattering run). 0: no cap. method: ``"dop853"``
    (explicit, 8th order: the default), ``"radau"`` (Radau IIA, implicit, 5th order, with the
    model's exact Jacobian in its Newton iterations: for stiff runs — high-gain controllers, stiff
    springs — where an explicit method's step is bounded by stability rather than accuracy) or
    ``"tsit5"`` (Tsitouras 5(4), explicit, with a free 4th-order dense output and SciPy's RK45
    step control: comparable with other 5th-order codes).
    """

    rtol: float = 1e-10
    atol: float = 1e-10
    max_step: float = 0.0
    max_step_time: float = 0.0
    zeno_dt: float = 1e-6
    zeno_events: int = 5
    max_events: int = 1_000_000
    nsub: int = 1
    max_integrator_steps: int = 20_000_000
    max_steps_between_events: int = 1_000_000
    method: str = "dop853"

    def __post_init__(self) -> None:
        if self.method not in METHODS:
            raise StateError(f"method must be one of {', '.join(METHODS)}, got {self.method!r}")
        # a tolerance outside (0, 1) asks for no accuracy or for the impossible (rtol 1e-300 never ends)
        for name in ("rtol", "atol"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and 1e-16 <= v < 1):
                raise StateError(f"{name} must be a number in [1e-16, 1), got {v!r}")
        for name in ("max_step", "max_step_time", "zeno_dt"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v >= 0):
                raise StateError(f"{name} must be a finite number ≥ 0, got {v!r}")

    @cached_property
    def _opt(self) -> np.ndarray:
        """``opt`` laid out by the table, with the per-run fields (end time, sampling) at 0."""
        values = {"TEND": 0.0, "RTOL": self.rtol, "ATOL": self.atol, "MAXSTEP": self.max_step,
                  "MAXSTEPTIME": self.max_step_time, "SAMPLEDT": 0.0, "ZENODT": self.zeno_dt}
        return np.array([values[f] for f in OPT_FIELDS], dtype=float)

    @cached_property
    def _iopt(self) -> np.ndarray:
        """``iopt`` laid out by the table, with the per-run fields (steps, capacities) at 0."""
        values = {"MAXSTEPS": 0, "MAXEVENTS": self.max_events, "OUTCAP": 0, "EVCAP": 0, "ZENON": self.zeno_events,
                  "NSUB": self.nsub, "MAXISTEPS": self.max_integrator_steps,
                  "MAXISTEPS_EV": self.max_steps_between_events, "YIELDN": YIELD_STEPS,
                  "METHOD": abi.METHOD[self.method]}
        return np.array([values[f] for f in IOPT_FIELDS], dtype=np.int64)


@dataclass(slots=True)
class Sensitivity:
    """Derivatives of where a run ended with respect to its initial state ``x0`` and the
    parameters ``p`` (in the kernels' parameter order), from the variational equations and the
    saltation matrices of its events.

    A run that ended at an event (its steps done, a terminal transition, the event cap) ended at
    a time that moves with the data: ``dx_dx0``/``dx_dp`` are then the derivatives of the state at
    that event (just after the reset for a step, just before a terminal one), and
    ``dt_dx0``/``dt_dp`` those of the event time. A run that ended at a fixed time has ``dt = 0``.
    """

    dx_dx0: np.ndarray
    dx_dp: np.ndarray
    dt_dx0: np.ndarray
    dt_dp: np.ndarray


@dataclass(slots=True)
class Run:
    """Where a run ended: ``code`` (an :data:`amble.backend.abi.STATUS` code), ``status`` (its
    outcome name; a terminal transition's own status, e.g. ``fell``), time ``t`` (s), ``mode``
    index, state ``x`` (that mode's length), ``steps`` and ``events`` counted, ``info`` (index of
    the transition that ended it, or −1), the raw ``ctx`` and the ``recorded`` buffers (empty when
    the run recorded nothing)."""

    code: int
    status: str
    t: float
    mode: int
    x: np.ndarray
    steps: int
    events: int
    info: int
    ctx: np.ndarray
    recorded: dict[str, Any]
    sensitivity: Sensitivity | None = None

    @property
    def completed(self) -> bool:
        """All requested steps were taken."""
        return self.code == CODE["STEPS_DONE"]


def outcome(k: Kernels, code: int, info: int) -> str:
    """Readable outcome of a status code: a terminal transition's own status, else its name."""
    if code == CODE["TERMINAL"]:
        return str(k.meta["transitions"][info]["terminal"])
    return OUTCOME.get(code) or "integrator_failure"


def run(
    k: Kernels,
    p: np.ndarray,
    mode: int,
    x0: np.ndarray,
    *,
    t0: float = 0.0,
    t_end: float = math.inf,
    steps: int = 0,
    opts: Options = Options(),
    sample_dt: float = 0.0,
    record: bool = False,
    events_only: bool = False,
    budget: int = RECORD_BUDGET,
    sensitivities: bool | str = False,
) -> Run:
    """Run from ``x0`` in mode ``mode`` at ``t0`` until ``t_end`` (s), ``steps`` step transitions
    (0: no limit) or another end; record samples (every ``sample_dt`` s, 0: every integration step)
    and events when ``record`` (only events with ``events_only``). Recorded buffers never grow
    past ``budget`` bytes: the run then ends as ``record_limit`` with what it recorded. With
    ``sensitivities`` the run also carries ``∂x/∂(x0, p)`` (:class:`Sensitivity`); ``"state"``
    carries ``∂x/∂x0`` only (cheaper: parameters touch most of the model's expressions)."""
    # Called once per return-map evaluation (tens of µs of compiled work): the arrays are laid
    # out from templates and index constants, not rebuilt field by field.
    nxm = k.nx_max
    ctx = np.zeros(CTX_X + nxm)
    ctx[_CX_T], ctx[_CX_MODE], ctx[_CX_TLAST_STEP], ctx[_CX_GRID_T0] = t0, mode, t0, t0
    ctx[_CX_TPREV_EVENT], ctx[_CX_FRESH] = -math.inf, 1.0
    ctx[CTX_X : CTX_X + x0.size] = x0
    opt = opts._opt.copy()
    opt[_OP_TEND], opt[_OP_SAMPLEDT] = t_end, sample_dt if record else 0.0
    iopt = opts._iopt.copy()
    iopt[_IO_MAXSTEPS] = steps
    buf = _Buffers.take(0 if events_only else _first_rows(nxm, budget), nxm) if record else _NO_RECORDING
    if sensitivities not in (False, True, "state"):
        raise StateError(f"sensitivities must be True, False or 'state', got {sensitivities!r}")
    if (sensitivities or NEEDS_JACOBIAN[opts.method]) and not k.meta.get("derivatives"):
        raise StateError(f"system {k.meta['name']!r}: sensitivities and the implicit integrator need the kernels "
                         "built with their derivatives: amble.compiled(system, derivatives=True)")
    if sensitivities and not abi.HAS_SENSITIVITIES[opts.method]:
        # the variational equations ride on an explicit method's stages
        raise StateError(f"sensitivities need method={' or '.join(map(repr, SENSITIVITY_METHODS))}, "
                         f"not {opts.method!r}")
    sens = _sensitivity_buffer(k, x0.size, sensitivities is True) if sensitivities else None
    sens_addr = sens.ctypes.data if sens is not None else None
    code = _YIELD
    try:
        while True:
            iopt[_IO_OUTCAP], iopt[_IO_EVCAP] = buf.cap, buf.ecap
            code = buf.call(k, p, ctx, opt, iopt, sens_addr)
            if code == _BUFFER_FULL:
                if buf.nbytes_grown() > budget:  # the run is resumable here: stop with what it has
                    code = _RECORD_LIMIT
                    break
                buf.grow()
            elif code != _YIELD:
                break
    except KeyboardInterrupt as exc:
        # Ctrl-C between two compiled calls: the run so far stays reachable as ``exc.run``
        exc.run = _result(k, _YIELD, ctx, buf)  # type: ignore[attr-defined]
        raise
    r = _result(k, code, ctx, buf)
    if sens is not None:
        r.sensitivity = _sensitivity(k, r, sens, x0.size, p)
    return r


#: Runs that end at an event, whose end time therefore moves with the initial data.
_AT_EVENT = (CODE["STEPS_DONE"], CODE["TERMINAL"], CODE["MAX_EVENTS"])


def _sensitivity_buffer(k: Kernels, nx0: int, params: bool) -> np.ndarray:
    """``S = [I 0]`` (the initial state's own columns), ``dτ = 0`` and the numbers of state and
    parameter columns carried, laid out by :func:`amble.backend.abi.sens_layout`: a copy of a
    template kept per shape (laying it out costs more than a small model's run)."""
    return _sensitivity_template(k.nx_max, k.sc, nx0, len(k.meta["params"]) if params else 0).copy()


@lru_cache(maxsize=64)
def _sensitivity_template(nx_max: int, sc: int, nx0: int, npar: int) -> np.ndarray:
    lay = sens_layout(nx_max, sc)
    sens = np.zeros(lay["SIZE"])
    S = sens[lay["S"] : lay["S"] + nx_max * sc].reshape(nx_max, sc)
    S[np.arange(nx0), np.arange(nx0)] = 1.0
    sens[lay["NCS"]], sens[lay["NCP"]] = nx0, npar
    sens.flags.writeable = False  # copied by every run
    return sens


def _sensitivity(k: Kernels, r: Run, sens: np.ndarray, nx0: int, p: np.ndarray) -> Sensitivity:
    nxm, sc = k.nx_max, k.sc
    lay = sens_layout(nxm, sc)
    npar = int(sens[lay["NCP"]])
    S = sens[lay["S"] : lay["S"] + nxm * sc].reshape(nxm, sc)[: r.x.size]
    tau = sens[lay["TAU"] : lay["TAU"] + sc]
    dx_dx0, dt_dx0 = S[:, :nx0].copy(), tau[:nx0].copy()
    dx_dp, dt_dp = S[:, nxm : nxm + npar].copy(), tau[nxm : nxm + npar].copy()
    if r.code in _AT_EVENT:
        # the buffer holds S at a fixed time just after the event: the state at the (moving)
        # event itself adds its flow times dτ
        f = k.rhs(r.mode, r.t, r.x, p)
        dx_dx0 += np.outer(f, dt_dx0)
        if npar:
            dx_dp += np.outer(f, dt_dp)
    else:
        dt_dx0[:], dt_dp[:] = 0.0, 0.0
    return Sensitivity(dx_dx0=dx_dx0, dx_dp=dx_dp, dt_dx0=dt_dx0, dt_dp=dt_dp)


def walk_many(k: Kernels, p: np.ndarray, mode: int, x0: np.ndarray, xref: np.ndarray, *, steps: int,
              check_every: int, tol: float, opts: Options = Options(), threads: int = 1) -> dict[str, Any]:
    """Walk every row of ``x0`` from t = 0 for up to ``steps`` footfalls in one compiled call (no
    recording, the GIL released): in runs of ``check_every`` footfalls, each started like
    :func:`run` from the previous one's final state, until ``max |x − xref| < tol``; ``p`` is one
    parameter vector for all walks or one row per walk. Returns per
    walk ``code``, ``status`` (as :attr:`Run.status`), ``steps``, ``distance`` (NaN if no run
    completed) and the final ``x`` — what a loop over :func:`run` gives, without its Python cost
    per walk (which kept two threads of basin cells at about 1.2× one). ``threads``: walk the rows
    on this many threads of this process, which share them row by row (results do not depend
    on it)."""
    opt = opts._opt.copy()
    opt[_OP_TEND] = math.inf
    out = k.walk_batch(mode, x0, p, opt, opts._iopt, xref, steps, check_every, tol, threads=threads)
    ok = CODE["STEPS_DONE"]
    done = outcome(k, ok, -1)
    out["status"] = [done if c == ok else outcome(k, c, i) for c, i in zip(out["code"].tolist(), out["info"].tolist())]
    return out


def _result(k: Kernels, code: int, ctx: np.ndarray, buf: _Buffers) -> Run:
    c = ctx[:CTX_X].tolist()  # one conversion instead of a NumPy scalar per field
    mi = int(c[_CX_MODE])
    info = int(c[_CX_INFO]) if code in _WITH_INFO else -1
    status = "interrupted" if code == _YIELD else outcome(k, code, info)
    return Run(code=code, status=status, t=c[_CX_T], mode=mi, x=ctx[CTX_X : CTX_X + k.meta["nx"][mi]].copy(),
               steps=int(c[_CX_STEPS]), events=int(c[_CX_EVENTS]), info=info, ctx=ctx,
               recorded=buf.result_and_release())


#: Sample rows and event rows the buffers of a recording run start with: a walk of a few hundred
#: steps on a 0.01 s grid never regrows (each regrowth copies every row). Sample buffers start at
#: no more than :data:`_FIRST_BYTES` (a long state vector starts with fewer rows), which bounds
#: what a thread keeps for its next run.
_FIRST_ROWS = 1 << 15
_FIRST_BYTES = 4 * 2**20
_FIRST_EVENTS = 256

#: Buffers of finished runs, per thread, ready for the next run of the same shape: a fresh
#: megabyte-sized array is mapped, faulted in page by page and unmapped again by the operating
#: system on every run, which cost more than a 20-step walk itself. Only buffers that never grew
#: are kept, one per shape and thread.
_FREE = threading.local()


@lru_cache(maxsize=64)  # asked on every recording run, with the same few shapes
def _first_rows(nxm: int, budget: int) -> int:
    """Sample rows to start with: :data:`_FIRST_ROWS`, or fewer if a small budget asks for it."""
    row = 8 + 4 + 8 * nxm
    return max(16, min(_FIRST_ROWS, _FIRST_BYTES // row, budget // (4 * row)))


class _Buffers:
    def __init__(self, cap: int, ecap: int, nxm: int) -> None:
        self.cap, self.ecap, self.nxm = cap, ecap, nxm
        self.t = np.zeros(max(cap, 1))
        self.mode = np.zeros(max(cap, 1), dtype=np.int32)
        self.x = np.zeros((max(cap, 1), nxm))
        self.et = np.zeros(max(ecap, 1))
        self.etr = np.zeros(max(ecap, 1), dtype=np.int32)
        self.epre = np.zeros((max(ecap, 1), nxm))
        self.epost = np.zeros((max(ecap, 1), nxm))
        self.n = np.zeros(1, dtype=np.int64)
        self.ne = np.zeros(1, dtype=np.int64)
        # the row and event counters as Python ints: a memoryview reads and writes them without
        # making a NumPy scalar (several of which a short run's fixed cost was made of)
        self._counts = (memoryview(self.n), memoryview(self.ne))
        self._addresses = self.addresses()
        self._shape = (cap, ecap, nxm)

    @classmethod
    def take(cls, cap: int, nxm: int) -> _Buffers:
        """Empty buffers of ``cap`` rows (and :data:`_FIRST_EVENTS` events): this thread's free
        ones of that shape, or new ones."""
        free = getattr(_FREE, "buffers", None)
        buf = free.pop((cap, _FIRST_EVENTS, nxm), None) if free else None
        if buf is None:
            return cls(cap, _FIRST_EVENTS, nxm)
        n, ne = buf._counts
        n[0] = ne[0] = 0
        return buf

    def addresses(self) -> tuple[int, ...]:
        # __array_interface__ is several times cheaper than building an ndarray.ctypes object
        return tuple(a.__array_interface__["data"][0] for a in (self.t, self.mode, self.x, self.n, self.et, self.etr,
                                                                self.epre, self.epost, self.ne))

    def call(self, k: Kernels, p, ctx, opt, iopt, sens: int | None = None) -> int:
        return int(k.simulate_raw(address(p), address(ctx), address(opt), address(iopt), *self._addresses, sens))

    def nbytes_grown(self) -> int:
        """Bytes the buffers would hold after :meth:`grow`."""
        rows = 2 * self.cap * (8 + 4 + 8 * self.nxm)
        events = (2 if int(self.ne[0]) >= self.ecap - 1 else 1) * self.ecap * (8 + 4 + 16 * self.nxm)
        return rows + events

    def grow(self) -> None:
        if self.cap == 0 and self.ecap == 0:
            raise RuntimeError("buffer full without recording")  # cannot happen: C only reports it when recording
        n, ne = int(self.n[0]), int(self.ne[0])
        self.cap *= 2
        self.ecap *= 2 if ne >= self.ecap - 1 else 1
        for name, size in (("t", self.cap), ("mode", self.cap), ("x", self.cap)):
            old = getattr(self, name)
            new = np.zeros((size,) + old.shape[1:], dtype=old.dtype)
            new[:n] = old[:n]
            setattr(self, name, new)
        for name in ("et", "etr", "epre", "epost"):
            old = getattr(self, name)
            new = np.zeros((self.ecap,) + old.shape[1:], dtype=old.dtype)
            new[:ne] = old[:ne]
            setattr(self, name, new)
        self._addresses = self.addresses()

    def result_and_release(self) -> dict[str, Any]:
        """The recorded rows: copies if the buffers never grew (they go back to this thread's free
        ones), else the buffers themselves cut to the rows in place.

        A grown buffer is held by nothing else, and a copy of it would double what the run holds
        at its largest (the buffers and the copies, both up to ``budget`` bytes, alive at once):
        the budget then bounds the process's memory, not only the buffers'."""
        if self is _NO_RECORDING:
            return _EMPTY
        n, ne = self._counts[0][0], self._counts[1][0]
        names = ("t", "mode", "x", "et", "etr", "epre", "epost")
        if (self.cap, self.ecap, self.nxm) != self._shape:
            out = {name: _cut(getattr(self, name), n if name in ("t", "mode", "x") else ne) for name in names}
            self.cap = self.ecap = 0  # the arrays now belong to the caller
            return out
        out = {"t": self.t[:n].copy(), "mode": self.mode[:n].copy(), "x": self.x[:n].copy(),
               "et": self.et[:ne].copy(), "etr": self.etr[:ne].copy(), "epre": self.epre[:ne].copy(),
               "epost": self.epost[:ne].copy()}
        if not hasattr(_FREE, "buffers"):
            _FREE.buffers = {}
        _FREE.buffers[self._shape] = self
        return out


def _cut(a: np.ndarray, rows: int) -> np.ndarray:
    """``a`` cut to its first ``rows`` rows in place (``realloc``: shrinking moves no data)."""
    a.resize((rows,) + a.shape[1:], refcheck=False)
    return a


#: Buffers of every run that records nothing, shared: with both capacities 0 the compiled loop
#: writes no row, no event and no counter into them, so runs in several threads may share them.
_NO_RECORDING = _Buffers(0, 0, 1)
_EMPTY: dict[str, Any] = {}
