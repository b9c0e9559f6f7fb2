"""Simulate a hybrid system for users: defaults, checked inputs, and a :class:`Trajectory`.

The compiled run itself is :func:`amble.simulation.engine.run`, the lean core that analysis code
(return maps, sweeps) calls directly when it needs only the final state and outcome.
"""

from __future__ import annotations

import dataclasses
import math
import numbers
import operator
import string
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from ..backend.abi import CODE, CTX, NEEDS_JACOBIAN
from ..backend.kernels import compiled
from ..backend.library import Kernels
from ..errors import ParameterError, StateError
from .engine import RECORD_BUDGET, Options, Run, run
from .memo import Memo
from .trajectory import Event, Events, Trajectory

if TYPE_CHECKING:
    from ..modelling.hybrid import HybridSystem


def parameter_vector(k: Kernels, params: Mapping[str, float] | None, system: HybridSystem | None = None
                     ) -> np.ndarray:
    """Defaults overridden by ``params``; unknown names, non-finite values and (given the
    ``system``) values outside a parameter's declared domain are :class:`ParameterError`.
    A new array on every call (callers keep it: a trajectory's ``params``)."""
    key = _parameter_key(k, params)
    hit = _PARAMETERS.get(key, k) if key is not None else None
    if hit is not None:
        if system is not None and hit[1]:
            system.check_parameters(hit[1])  # domains are the system's: checked on every call
        return hit[0].copy()
    names = k.meta["params"]
    p = np.array(k.meta["param_defaults"], dtype=float)
    if params is not None and not isinstance(params, Mapping):  # a list of pairs or of names reads ambiguously
        raise ParameterError(f"params must be a mapping of parameter names to values (e.g. {{'slope': 0.05}}), "
                             f"got a {type(params).__name__}")
    given: dict[str, float] = {}
    if params:
        for key_, val in params.items():
            if key_ not in names:
                raise ParameterError(f"unknown parameter {key_!r}; known: {', '.join(names)}")
            try:
                v = float(val)
            except (TypeError, ValueError):
                raise ParameterError(f"parameter {key_!r} must be a number, got {val!r}") from None
            if not math.isfinite(v):
                raise ParameterError(f"parameter {key_!r} must be finite, got {val!r}")
            p[names.index(key_)] = v
        given = {key_: float(p[names.index(key_)]) for key_ in params}
        if system is not None:
            system.check_parameters(given)
    if p.size == 0:
        p = np.zeros(1)
    if key is not None:
        _PARAMETERS.put(key, (p, given), k)
        return p.copy()
    return p


#: Parameter vectors by (id of the kernels, the overrides as given) → (vector, the overrides as
#: checked against the domains): names, numbers and finiteness are checked once; a sweep passes a
#: new value on every call, hence the bound.
_PARAMETERS = Memo(256)


def _parameter_key(k: Kernels, params: Any) -> tuple | None:
    """The memo key of these overrides, or ``None`` (not memoised) unless every value is a plain
    ``float`` or ``int``: two values that compare equal then convert to the same number."""
    if not params:
        return (id(k),) if params is None or type(params) is dict else None
    if type(params) is not dict:
        return None
    items = tuple(params.items())
    for _, v in items:
        if type(v) is not float and type(v) is not int:
            return None
    return (id(k), *items)


def initial_state(system: HybridSystem, k: Kernels, x0: Sequence[float] | None, mode: str | None
                  ) -> tuple[int, np.ndarray]:
    if mode is not None and not isinstance(mode, str):
        raise StateError(f"mode must be a mode name ({', '.join(k.meta['modes'])}), got {mode!r}")
    mode = mode or k.meta["modes"][0]
    mi = k.mode_index(mode)
    names = k.meta["state_names"][mode]
    if x0 is None:
        if mode not in system.default_start:
            raise StateError(f"system {system.name!r} has no default start for mode {mode!r}; give x0")
        x0 = system.default_start[mode]
    if isinstance(x0, (str, bytes)):  # NumPy would read "1.5" as one number and fail on "abcd"
        raise StateError(f"initial state must be a sequence of numbers ({', '.join(names)}), got {x0!r}")
    try:
        x = np.asarray(x0, dtype=float).ravel()
    except (TypeError, ValueError):
        raise StateError(f"initial state must be a sequence of numbers ({', '.join(names)}), got {x0!r}") from None
    if x.size != len(names):
        raise StateError(
            f"initial state has {x.size} values, mode {mode!r} needs {len(names)}: {', '.join(names)}"
        )
    values = x.tolist()
    if not all(map(math.isfinite, values)):  # a tenth of np.isfinite(x).all() on a short state
        raise StateError(f"initial state is not finite: {values}")
    return mi, x


def simulate(
    system: HybridSystem,
    x0: Sequence[float] | None = None,
    *,
    mode: str | None = None,
    params: Mapping[str, float] | None = None,
    steps: int | None = None,
    t_end: float | None = None,
    rtol: float | None = None,
    atol: float | None = None,
    sample_dt: float = 0.01,
    max_step_time: float | None = None,
    options: Options | None = None,
    samples: bool = True,
    budget: int = RECORD_BUDGET,
    method: str | None = None,
) -> Trajectory:
    """Simulate a hybrid system and return its :class:`Trajectory`.

    Parameters
    ----------
    x0:
        Full initial state in ``system.state_names(mode)`` order; default: the system's start.
    params:
        Parameter overrides by name (others keep their defaults).
    steps, t_end:
        Stop after this many footfalls and/or at this time (s). With neither, ``t_end = 10``.
    rtol, atol:
        Integrator tolerances; default those of ``options`` (whose own default is 1e-10).
    sample_dt:
        Output grid spacing (s); ``0`` records every integration step instead.
    max_step_time:
        A walker with no footfall for this long has fallen (s); default from the system.
    samples:
        ``False``: record events only (the trajectory's rows are then the initial and the final
        state) — constant memory however long the run.
    budget:
        Bytes the recording may take (default 512 MiB): the sample and event buffers, which
        the trajectory then holds without a copy (so the process's peak memory grows by about
        this much at most); a run that would record more ends as ``record_limit`` with what it has.
    method:
        ``"dop853"`` (explicit, the default), ``"radau"`` (implicit Radau IIA with the model's
        exact Jacobian, for stiff systems) or ``"tsit5"`` (explicit Tsitouras 5(4)); default that
        of ``options``.
    """
    base = options or _DEFAULT_OPTIONS
    if not isinstance(base, Options):
        raise StateError(f"options must be an amble Options, got {type(base).__name__}")
    # the type of every argument is checked before any work: a string or a list compared with a
    # number would otherwise surface as a TypeError deep inside
    steps = _count(steps, "steps", base.max_events)
    t_end = None if t_end is None else _real(t_end, "t_end (end time, s)")
    sample_dt = _real(sample_dt, "sample_dt (s)")
    # tolerances taken from ``base`` were checked when it was made (Options.__post_init__)
    rtol = base.rtol if rtol is None else _tolerance(rtol, "rtol")
    atol = base.atol if atol is None else _tolerance(atol, "atol")
    max_step_time = None if max_step_time is None else _real(max_step_time, "max_step_time (s)")
    budget = _count(budget, "budget (bytes)", 0) or RECORD_BUDGET
    if t_end is not None and not (t_end > 0 and math.isfinite(t_end)):
        raise StateError(f"end time must be positive and finite, got {t_end}")
    if not (sample_dt >= 0 and math.isfinite(sample_dt)):
        raise StateError(f"sample_dt must be a finite number ≥ 0 s, got {sample_dt}")
    # an implicit integrator's Newton matrix is the exact Jacobian (an unknown name is refused below)
    jacobian = NEEDS_JACOBIAN.get(method or (options.method if options else "dop853"), False)
    k = compiled(system, derivatives=jacobian)
    p = parameter_vector(k, params, system)
    mi, x = initial_state(system, k, x0, mode)
    if steps is None and t_end is None:
        t_end = 10.0
    mst = max_step_time if max_step_time is not None else system.max_step_time
    opts = _options(base, rtol, atol, mst, base.method if method is None else method)
    try:
        r = run(k, p, mi, x, t_end=t_end if t_end is not None else math.inf, steps=steps or 0, opts=opts,
                sample_dt=sample_dt, record=True, events_only=not samples, budget=budget)
    except KeyboardInterrupt as exc:
        partial = getattr(exc, "run", None)
        if partial is not None:  # the run so far, as ``exc.trajectory``
            exc.trajectory = _trajectory(k, p, partial, opts)  # type: ignore[attr-defined]
            exc.trajectory.system = system  # type: ignore[attr-defined]
        raise
    traj = _trajectory(k, p, r, opts)
    if not samples:  # rows: where the run started and where it ended
        rows = np.empty((2, k.nx_max))
        rows.fill(np.nan)
        rows[0, : x.size], rows[1, : r.x.size] = x, r.x
        traj.t, traj.mode, traj.x = np.array([0.0, r.t]), np.array([mi, r.mode], dtype=np.int32), rows
    traj.system = system
    return traj


def _real(value: Any, what: str) -> float:
    """``value`` as a float if it is a real number (not a bool, not text), else :class:`StateError`."""
    if type(value) is float:  # the usual case, without the abstract-class check
        return value
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise StateError(f"{what} must be a number, got {value!r}")
    return float(value)


def _tolerance(value: Any, name: str) -> float:
    """A given tolerance as a positive, finite float, else :class:`StateError`."""
    v = _real(value, name)
    if not (v > 0 and math.isfinite(v)):
        raise StateError(f"{name} must be a positive number, got {v}")
    return v


def _count(value: Any, what: str, most: int) -> int | None:
    """``value`` as an int ≥ 1 (and ≤ ``most`` unless ``most`` is 0) if it is an integer (not a
    bool, not a float or text), else :class:`StateError`; ``None`` stays ``None``."""
    if value is None:
        return None
    if type(value) is int and 1 <= value <= (most or 2**62):  # the usual case
        return value
    try:
        n = operator.index(value) if not isinstance(value, bool) else None
    except TypeError:
        n = None
    if n is None:
        raise StateError(f"{what} must be an integer, got {value!r}")
    if n < 1 or n > (most or 2**62):  # the compiled loop counts in 64 bits
        bound = f" and at most {most} (Options.max_events)" if most else f" and at most {2**62}"
        raise StateError(f"{what} must be at least 1{bound}, got {n}")
    return n


#: The options of a call that gives none.
_DEFAULT_OPTIONS = Options()

#: Options by (id(base), rtol, atol, max_step_time, method).
_OPTIONS = Memo(64)


def _options(base: Options, rtol: float, atol: float, max_step_time: float, method: str) -> Options:
    """``base`` with these tolerances, step-time limit and integrator; one object per distinct
    setting, so its laid-out option arrays (cached on it) are built once, not on every call.
    Keyed by the identity of ``base`` (hashing a frozen dataclass of eleven fields took longer
    than the rest of the lookup); a new ``Options`` per call still gets equal results."""
    key = (id(base), rtol, atol, max_step_time, method)
    opts = _OPTIONS.get(key, base)
    if opts is None:
        opts = dataclasses.replace(base, rtol=rtol, atol=atol, max_step_time=max_step_time, method=method)
        _OPTIONS.put(key, opts, base)
    return opts


def _trajectory(k: Kernels, p: np.ndarray, r: Run, opts: Options) -> Trajectory:
    meta = k.meta
    trs = meta["transitions"]
    rec = r.recorded
    # the Event objects are made when first read (about half a microsecond per footfall, often
    # never needed)
    events: Sequence[Event] = (Events(rec["et"], rec["etr"], rec["epre"], rec["epost"], _kinds(meta), k.nx_max)
                               if len(rec.get("et", ())) else [])
    # positional: the dataclass's keyword parsing was a fifth of this function's cost
    return Trajectory(rec["t"], rec["mode"], rec["x"], events, r.status,
                      _message(r, opts, trs, meta.get("switches", ())), r.steps, p, k, r.x, meta["modes"][r.mode])


#: Per transition list (by its id): its names and the state lengths on either side, as
#: :class:`Events` reads them.
_KINDS = Memo(64)


def _kinds(meta: dict) -> list[tuple[str, str, str, int, int]]:
    trs = meta["transitions"]
    kinds = _KINDS.get((id(trs),), trs)
    if kinds is None:
        modes, nx = meta["modes"], meta["nx"]
        kinds = [(tr["name"], tr["source"], tr["target"], nx[modes.index(tr["source"])],
                  nx[modes.index(tr["target"])]) for tr in trs]
        _KINDS.put((id(trs),), kinds, trs)
    return kinds


#: How each way of ending reads, by status name (:data:`amble.backend.abi.STATUS`).
_MESSAGES = {
    "TERMINAL": "{transition} at t = {t:.6g} s",
    "STEPS_DONE": "{steps} steps in {t:.6g} s",
    "END_TIME": "reached t = {t:.6g} s after {steps} steps",
    "STEP_TIMEOUT": "no footfall within {max_step_time:g} s (t = {t:.6g} s)",
    "ZENO": "{zeno_events} events less than {zeno_dt:g} s apart near t = {t:.9g} s",
    "STEP_TOO_SMALL": "step size underflow at t = {t:.9g} s",
    "NONFINITE": "state became non-finite near t = {t:.9g} s",
    "SINGULAR_MASS": "mass matrix singular or ill-conditioned at t = {t:.9g} s, state {x}",
    "RESET_FAILED": "reset of {transition!r} failed at t = {t:.9g} s",
    "MAX_EVENTS": "{events} events, the most allowed, at t = {t:.6g} s",
    "RECORD_LIMIT": "recording budget spent at t = {t:.6g} s ({steps} steps): record less often (sample_dt) "
                    "or nothing (samples=False)",
    "STALLED": "{max_steps_between_events} integrator steps without a transition, the most allowed, at t = {t:.9g} s"
               "{stiff}",
    "MAX_ISTEPS": "{max_integrator_steps} integrator steps, the most allowed, at t = {t:.9g} s{stiff}",
    "YIELD": "interrupted at t = {t:.9g} s",
    "SLIDING": "sliding on switching surface {surface} ({surface_expr}) at t = {t:.9g} s",
}


#: How each message field is worked out from (run, options, transitions, switching surfaces).
_FIELD_VALUES = {
    "t": lambda r, o, trs, sw: r.t, "steps": lambda r, o, trs, sw: r.steps, "events": lambda r, o, trs, sw: r.events,
    "x": lambda r, o, trs, sw: r.x.tolist(), "max_step_time": lambda r, o, trs, sw: o.max_step_time,
    "zeno_events": lambda r, o, trs, sw: o.zeno_events, "zeno_dt": lambda r, o, trs, sw: o.zeno_dt,
    "max_steps_between_events": lambda r, o, trs, sw: o.max_steps_between_events,
    "max_integrator_steps": lambda r, o, trs, sw: o.max_integrator_steps, "surface": lambda r, o, trs, sw: r.info,
    "surface_expr": lambda r, o, trs, sw: _surface(r, sw),
    "transition": lambda r, o, trs, sw: trs[r.info]["name"] if r.info >= 0 and r.code != CODE["SLIDING"] else "",
    "stiff": lambda r, o, trs, sw: _stiff_hint(r, o),
}


#: By status code: its message template and the fields the template reads (parsed once).
_TEMPLATES = {code: (text, tuple(dict.fromkeys(f for _, f, _, _ in string.Formatter().parse(text) if f)))
              for code, text in ((CODE[name], text) for name, text in _MESSAGES.items() if name in CODE)}
_OTHER = ("stopped at t = {t:.6g} s", ("t",))
#: The most common ending, formatted without the per-field look-ups (its template, written out).
_STEPS_DONE = CODE["STEPS_DONE"]
assert _MESSAGES["STEPS_DONE"] == "{steps} steps in {t:.6g} s", "keep _message's written-out template in step"


def _message(r: Run, opts: Options, trs: Sequence, switches: Sequence) -> str:
    if r.code == _STEPS_DONE:
        return f"{r.steps} steps in {r.t:.6g} s"
    template, fields = _TEMPLATES.get(r.code, _OTHER)
    # only the fields this template reads are worked out (the state as a list, the stiffness
    # hint: microseconds on every call of simulate() otherwise)
    return template.format_map({f: _FIELD_VALUES[f](r, opts, trs, switches) for f in fields})


def _stiff_hint(r: Run, opts: Options) -> str:
    """Why a run exhausted its step budget: still crossing a switching surface in its last steps,
    it chatters about the switch; otherwise an explicit run with tiny steps is most likely stiff
    (its steps bounded by stability, not accuracy; ``ctx`` holds the next step size)."""
    h = float(r.ctx[CTX["H"]])
    mean = r.t / max(float(r.ctx[CTX["ISTEPS"]]), 1.0)
    last = float(r.ctx[CTX["TPREV_EVENT"]])  # the last transition or switching-surface crossing
    if 0 <= r.t - last < 1e3 * max(h, mean):
        # crossings of a switching surface do not end the step budget: a run that still crossed
        # one in its last steps chatters about it (a state-dependent switch that pushes the flow
        # away on both sides oscillates with an amplitude of its own), which no integrator cures
        return (f" (the state still crosses a switching surface, last at t = {last:.9g} s: it chatters "
                f"about the switch, which a smaller step or another integrator does not cure)")
    if NEEDS_JACOBIAN[opts.method]:  # already implicit
        return ""
    if h > 0 and mean > 0 and h < 1e-4 * max(r.t, 1.0):
        return (f" (steps of ~{mean:.2g} s: the system looks stiff; try the implicit integrator, "
                f"method='radau' / --method radau)")
    return ""


def _surface(r: Run, switches: list) -> str:
    """The switching surface a ``sliding`` run ended on, as derived from the model."""
    return str(switches[r.info]["expr"]) if r.code == CODE["SLIDING"] and 0 <= r.info < len(switches) else ""
