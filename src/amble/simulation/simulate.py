"""Run a hybrid system: one compiled call integrates, locates events and applies resets.

:func:`simulate` is the user-facing entry; :func:`run` is the lean core used by analysis code
(return maps, sweeps) that only needs the final state and status.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..backend.kernels import CTX_X, Kernels, build
from ..errors import ParameterError, StateError
from ..modelling.hybrid import HybridSystem
from .trajectory import Event, Trajectory

_STATUS = {
    1: "end_time",
    2: "completed",
    3: "terminal",
    4: "fell",
    5: "zeno",
    6: "integrator_failure",
    7: "integrator_failure",
    8: "max_events",
    9: "singular_mass",
    10: "reset_failed",
}


@dataclass(frozen=True)
class Options:
    """Integration and outcome settings.

    rtol, atol: DOP853 tolerances (relative, absolute). max_step: largest step (s, 0 = none).
    max_step_time: a walker that makes no footfall for this long has ``fell`` (s, 0 = never).
    zeno_dt, zeno_events: this many consecutive events each closer than ``zeno_dt`` (s) to the
    previous one end the run as ``zeno``. max_events: hard cap on events. nsub: uniform guard
    samples per integration step, in addition to the extremum of the cubic through ``g`` and ``ġ``
    at both step ends (which already finds a guard dipping through zero and back inside a step).
    """

    rtol: float = 1e-10
    atol: float = 1e-10
    max_step: float = 0.0
    max_step_time: float = 0.0
    zeno_dt: float = 1e-6
    zeno_events: int = 5
    max_events: int = 1_000_000
    nsub: int = 1


def parameter_vector(k: Kernels, params: Mapping[str, float] | None) -> np.ndarray:
    """Defaults overridden by ``params``; unknown names and non-finite values are errors."""
    names = k.meta["params"]
    p = np.array(k.meta["param_defaults"], dtype=float)
    if params:
        for key, val in params.items():
            if key not in names:
                raise ParameterError(f"unknown parameter {key!r}; known: {', '.join(names)}")
            try:
                v = float(val)
            except (TypeError, ValueError):
                raise ParameterError(f"parameter {key!r} must be a number, got {val!r}") from None
            if not math.isfinite(v):
                raise ParameterError(f"parameter {key!r} must be finite, got {val!r}")
            p[names.index(key)] = v
    if p.size == 0:
        p = np.zeros(1)
    return p


def initial_state(system: HybridSystem, k: Kernels, x0: Sequence[float] | None, mode: str | None
                  ) -> tuple[int, np.ndarray]:
    mode = mode or k.meta["modes"][0]
    mi = k.mode_index(mode)
    names = k.meta["state_names"][mode]
    if x0 is None:
        if mode not in system.default_start:
            raise StateError(f"system {system.name!r} has no default start for mode {mode!r}; give x0")
        x0 = system.default_start[mode]
    x = np.asarray(x0, dtype=float).ravel()
    if x.size != len(names):
        raise StateError(
            f"initial state has {x.size} values, mode {mode!r} needs {len(names)}: {', '.join(names)}"
        )
    if not np.all(np.isfinite(x)):
        raise StateError(f"initial state is not finite: {x.tolist()}")
    return mi, x


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
) -> tuple[int, np.ndarray, dict[str, Any]]:
    """Core loop: returns (status code, ctx array, recorded buffers). ctx holds the final state."""
    nxm = k.nx_max
    ctx = np.zeros(CTX_X + nxm)
    ctx[0], ctx[1], ctx[5], ctx[6], ctx[9], ctx[11] = t0, mode, t0, -math.inf, t0, 1.0
    ctx[CTX_X : CTX_X + x0.size] = x0
    opt = np.array([t_end, opts.rtol, opts.atol, opts.max_step, opts.max_step_time, sample_dt if record else 0.0,
                    opts.zeno_dt], dtype=float)
    cap, ecap = (1024, 64) if record else (0, 0)
    buf = _Buffers(cap, ecap, nxm)
    while True:
        iopt = np.array([steps, opts.max_events, buf.cap, buf.ecap, opts.zeno_events, opts.nsub], dtype=np.int64)
        st = buf.call(k, p, ctx, opt, iopt)
        if st != 0:
            return st, ctx, buf.result()
        buf.grow()


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

    def call(self, k: Kernels, p, ctx, opt, iopt) -> int:
        arrays = (p, ctx, opt, iopt, self.t, self.mode, self.x, self.n, self.et, self.etr, self.epre, self.epost,
                  self.ne)
        return int(k.simulate_raw(*[a.ctypes.data for a in arrays]))

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

    def result(self) -> dict[str, Any]:
        n, ne = int(self.n[0]), int(self.ne[0])
        return {"t": self.t[:n].copy(), "mode": self.mode[:n].copy(), "x": self.x[:n].copy(),
                "et": self.et[:ne].copy(), "etr": self.etr[:ne].copy(), "epre": self.epre[:ne].copy(),
                "epost": self.epost[:ne].copy()}


def simulate(
    system: HybridSystem,
    x0: Sequence[float] | None = None,
    *,
    mode: str | None = None,
    params: Mapping[str, float] | None = None,
    steps: int | None = None,
    t_end: float | None = None,
    rtol: float = 1e-10,
    atol: float = 1e-10,
    sample_dt: float = 0.01,
    max_step_time: float | None = None,
    options: Options | None = None,
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
        Integrator tolerances.
    sample_dt:
        Output grid spacing (s); ``0`` records every integration step instead.
    max_step_time:
        A walker with no footfall for this long has fallen (s); default from the system.
    """
    k = build(system)
    p = parameter_vector(k, params)
    mi, x = initial_state(system, k, x0, mode)
    if steps is not None and steps < 1:
        raise StateError(f"steps must be at least 1, got {steps}")
    if t_end is not None and not (t_end > 0):
        raise StateError(f"end time must be positive, got {t_end}")
    if steps is None and t_end is None:
        t_end = 10.0
    for name, v in (("rtol", rtol), ("atol", atol)):
        if not (v > 0 and math.isfinite(v)):
            raise StateError(f"{name} must be a positive number, got {v}")
    base = options or Options()
    mst = max_step_time if max_step_time is not None else system.max_step_time
    opts = Options(rtol=rtol, atol=atol, max_step=base.max_step, max_step_time=mst, zeno_dt=base.zeno_dt,
                   zeno_events=base.zeno_events, max_events=base.max_events, nsub=base.nsub)
    st, ctx, rec = run(k, p, mi, x, t_end=t_end if t_end is not None else math.inf, steps=steps or 0,
                       opts=opts, sample_dt=sample_dt, record=True)
    traj = _trajectory(k, p, st, ctx, rec, opts)
    traj.system = system
    return traj


def _trajectory(k: Kernels, p: np.ndarray, st: int, ctx: np.ndarray, rec: dict, opts: Options) -> Trajectory:
    meta = k.meta
    trs = meta["transitions"]
    events = []
    for t, tr, pre, post in zip(rec["et"], rec["etr"], rec["epre"], rec["epost"]):
        info = trs[int(tr)]
        ns, nt = meta["nx"][meta["modes"].index(info["source"])], meta["nx"][meta["modes"].index(info["target"])]
        events.append(Event(float(t), info["name"], info["source"], info["target"], pre[:ns].copy(), post[:nt].copy()))
    status = _STATUS.get(st, "integrator_failure")
    t_fin = float(ctx[0])
    fmode = int(ctx[1])
    xf = ctx[CTX_X : CTX_X + meta["nx"][fmode]].copy()
    if status == "terminal":
        info = trs[int(ctx[10])]
        status = info["terminal"]
        message = f"{info['name']} at t = {t_fin:.6g} s"
    else:
        message = _message(status, st, t_fin, ctx, opts, trs)
    steps = int(ctx[3])
    return Trajectory(t=rec["t"], mode=rec["mode"], x=rec["x"], events=events, status=status, message=message,
                      steps=steps, params=p, kernels=k, final_state=xf, final_mode=meta["modes"][fmode])


def _message(status: str, code: int, t: float, ctx: np.ndarray, opts: Options, trs: list) -> str:
    if status == "completed":
        return f"{int(ctx[3])} steps in {t:.6g} s"
    if status == "end_time":
        return f"reached t = {t:.6g} s after {int(ctx[3])} steps"
    if status == "fell":
        return f"no footfall within {opts.max_step_time:g} s (t = {t:.6g} s)"
    if status == "zeno":
        return f"{opts.zeno_events} events less than {opts.zeno_dt:g} s apart near t = {t:.9g} s"
    if code == 6:
        return f"step size underflow at t = {t:.9g} s"
    if code == 7:
        return f"state became non-finite near t = {t:.9g} s"
    if status == "singular_mass":
        return f"mass matrix singular or ill-conditioned at t = {t:.9g} s, state {ctx[CTX_X:].tolist()}"
    if status == "reset_failed":
        return f"reset of {trs[int(ctx[10])]['name']!r} failed at t = {t:.9g} s"
    return f"stopped at t = {t:.6g} s"
