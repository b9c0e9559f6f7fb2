"""Bifurcation diagrams (the ``bifurcation`` kind of :func:`amble.sweep`) and Poincaré iterates:
where the period-1 gait gives way to period 2, 4...

Along a swept parameter the return map is iterated from the previous value's last post-impact
state (first put on the new value's section, :meth:`~amble.analysis.section.Section.project`): a
transient is dropped, then the iterates of one coordinate are kept and their period is read off. Unlike a fixed-point
branch this follows the *attractor*, so it shows the period-doubling cascade and where the
walker falls.

Units: angles in rad, angular velocities in rad/s, times in s; parameters in the model's units.
"""

from __future__ import annotations

import json
import os
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from ..backend.kernels import compiled
from ..errors import AmbleError, StateError
from ..simulation.engine import Options, run
from ..simulation.simulate import parameter_vector
from .defaults import BIFURCATION_TOL
from .doubling import period_doubling
from .runner import chunks, sweep_values
from .section import Section
from .store import ResultStore, SweepResult, state_columns
from .sweep_runner import RunOptions, deprecated, point_key, prepared, run_sweep, seed_before

if TYPE_CHECKING:  # a compiled system (amble.backend.compiled) serves too, without SymPy
    from ..modelling.hybrid import HybridSystem


def _onto_section(system: HybridSystem, params: Mapping[str, float], x: np.ndarray, rtol: float,
                  atol: float) -> np.ndarray:
    """A state carried from the previous parameter value, put on the section of ``params`` with
    its section coordinates kept (:meth:`Section.project`); unchanged when no footfall from it can
    be found (the transient then reports why)."""
    from .return_map import ReturnMap

    try:
        return Section.of(ReturnMap(system, params, rtol=rtol, atol=atol), x).project(x)
    except AmbleError:
        return x


def _bif_columns(param: str, snames: Sequence[str]) -> dict[str, str]:
    return {"i": "int", param: "float", "status": "str", "reason": "str", "coordinate": "str", "iterates": "json",
            "step_times": "json", "period": "int", **dict.fromkeys(state_columns(snames), "float")}


def _period(vals: Sequence[float], tol: float) -> int:
    """Smallest p ≤ len/2 with v[n+p] ≈ v[n] for all n, else 0 (aperiodic / chaotic).

    A period-1 orbit approached slowly (a multiplier near −1 just before the flip) alternates
    with a shrinking amplitude and would pass as period 2: if the step-to-step differences
    shrink by half or more over the kept iterates, it is reported as period 1."""
    v = np.asarray(vals, float)
    for p in range(1, len(v) // 2 + 1):
        if np.all(np.abs(v[p:] - v[:-p]) < tol):
            d = np.abs(np.diff(v))
            if p > 1 and d.size >= 2 and d[-1] < 0.5 * d[0]:
                return 1
            return p
    return 0


def _bif_task(system: HybridSystem, base: dict[str, float], param: str, points: list[tuple[int, float]],
              seed: list[float] | None, coord: int, transient: int, keep: int, rtol: float, atol: float,
              period_tol: float) -> list[dict[str, Any]]:
    """Iterate the return map at each value of a chunk, starting from the previous value's last state."""
    from .poincare import default_guess, find_fixed_point

    k = compiled(system)
    mode = k.meta["modes"][0]
    snames = k.meta["state_names"][mode]
    mi = k.mode_index(mode)
    opts = Options(rtol=rtol, atol=atol, max_step_time=system.max_step_time)
    x = None if seed is None else np.asarray(seed, float)
    out = []
    for i, val in points:
        params = {**base, param: val}
        p = parameter_vector(k, params, system)
        if x is not None:  # the carried state must sit on the section of the new parameters
            x = _onto_section(system, params, x, rtol, atol)
        row: dict[str, Any] = {"i": i, param: val, "coordinate": snames[coord]}
        x0 = x
        if x0 is None:  # no state to carry: start on the period-1 fixed point (it exists past the flip)
            try:
                x0 = find_fixed_point(system, params=params, rtol=rtol, atol=atol, tol=1e-9).fixed_point
            except AmbleError:
                try:
                    x0 = np.asarray(default_guess(system, params), float)
                except AmbleError:
                    x0 = np.asarray(system.fixed_point_guess or system.default_start[mode], float)
        r = run(k, p, mi, x0, steps=transient, opts=opts) if transient > 0 else None
        kept, times, fail = [], [], ""
        if r is not None and not r.completed:
            fail = f"{r.status} during the transient"
        else:
            y = x0 if r is None else r.x
            for _ in range(keep):
                r = run(k, p, mi, y, steps=1, opts=opts)
                if not r.completed or r.mode != mi:
                    fail = f"{r.status} after {transient + len(kept)} steps"
                    break
                y = r.x
                kept.append(float(y[coord]))
                times.append(r.t)
        if fail:
            row.update(status="failed", reason=fail, iterates=json.dumps(kept), step_times=json.dumps(times),
                       period="")
            x = None  # the walker fell: the next value starts from the model's guess again
        else:
            row.update(status="ok", reason="", iterates=json.dumps(kept), step_times=json.dumps(times),
                       period=_period(kept, period_tol))
            row.update({c: float(v) for c, v in zip(state_columns(snames), y)})
            x = y
        out.append(row)
    return out


def bifurcation_kind(system: HybridSystem, over: Mapping[str, np.ndarray], params: Mapping[str, float] | None,
                     run: RunOptions, *, coordinate: str | int = 0, transient: int = 300, keep: int = 64,
                     chunk: int = 16, period_tol: float = 1e-6) -> SweepResult:
    """The ``bifurcation`` kind of :func:`amble.sweep`: post-transient return-map iterates of one
    coordinate along one parameter.

    At each value the walker takes ``transient`` steps from the previous value's last
    post-impact state, then ``keep`` more steps whose post-impact ``coordinate`` (name or state index; default the
    first, the stance angle of a walker, rad) is kept. A chunk (``chunk`` consecutive values, one
    Dask task)'s first value starts on its
    period-1 fixed point when one is found (else the model's guess walked in); a carried state
    is first put on the new section, its section coordinates kept (:mod:`amble.analysis.section`).
    ``period`` in a row: smallest p with iterates repeating within ``period_tol`` (0 = no period
    found: chaos or slow transient).
    A value where the walker falls is recorded ``failed`` with the reason.
    """
    (param, v), = over.items()
    _, _, snames = prepared(system, params, [param])
    if isinstance(coordinate, str):
        if coordinate not in snames:
            raise StateError(f"unknown coordinate {coordinate!r}; known: {', '.join(snames)}")
        coord = snames.index(coordinate)
    else:
        coord = int(coordinate)
        if not 0 <= coord < len(snames):
            raise StateError(f"coordinate index {coord} out of range 0..{len(snames) - 1}")
    if transient < 0 or keep < 1 or chunk < 1:
        raise StateError("need transient ≥ 0, keep ≥ 1 and chunk ≥ 1")
    keys = [[point_key(i, float(x))] for i, x in enumerate(v)]
    rtol, atol = run.rtol, run.atol

    def make_task(pts: list[int], grp: Sequence[int], store: ResultStore) -> tuple:
        seed = seed_before(store, keys, grp, pts[0], snames, back=1)  # previous value's last state, as stored
        return (system, dict(params or {}), param, [(g, float(v[g])) for g in pts], seed, coord, transient, keep,
                rtol, atol, period_tol)

    return run_sweep(kind="bifurcation", columns=_bif_columns(param, snames), key=["i", param], keys=keys,
                     groups=chunks(list(range(len(v))), chunk), make_task=make_task, fn=_bif_task, run=run,
                     params=[param], state_names=snames)


def bifurcation(
    system: HybridSystem,
    param: str,
    values: Sequence[float],
    *,
    params: Mapping[str, float] | None = None,
    coordinate: str | int = 0,
    transient: int = 300,
    keep: int = 64,
    chunk: int = 16,
    out: str | os.PathLike | None = None,
    scheduler: Any = None,
    workers: int | None = None,
    progress: bool = True,
    max_points: int | None = None,
    rtol: float = BIFURCATION_TOL,
    atol: float = BIFURCATION_TOL,
    period_tol: float = 1e-6,
) -> SweepResult:
    """Deprecated: ``amble.sweep(system, "bifurcation", {param: values}, ...)`` (the same rows)."""
    deprecated("bifurcation()", 'amble.sweep(system, "bifurcation", {param: values})')
    v = sweep_values(values, param, system)
    return bifurcation_kind(system, {param: v}, params, RunOptions(out, scheduler, workers, progress, max_points,
                                                                   rtol, atol),
                            coordinate=coordinate, transient=transient, keep=keep, chunk=chunk, period_tol=period_tol)


def first_period_doubling_iterates(result: SweepResult) -> float | None:
    """Deprecated: :func:`amble.period_doubling` of a bifurcation diagram (the same value: the
    first swept value whose post-transient iterates repeat with a period ≥ 2)."""
    deprecated("first_period_doubling_iterates()", "amble.period_doubling(result)")
    return period_doubling(result)


def poincare_iterates(system: HybridSystem, x0: Sequence[float] | None = None, *,
                      params: Mapping[str, float] | None = None, steps: int = 200, rtol: float = BIFURCATION_TOL,
                      atol: float = BIFURCATION_TOL) -> np.ndarray:
    """Successive post-impact states (steps+1 × n; row 0 = x0 or the model's guess); rows after
    a fall are absent (the array is shorter)."""
    k = compiled(system)
    p = parameter_vector(k, params, system)
    mode = k.meta["modes"][0]
    mi = k.mode_index(mode)
    x = np.asarray(x0 if x0 is not None else (system.fixed_point_guess or system.default_start[mode]), float)
    opts = Options(rtol=rtol, atol=atol, max_step_time=system.max_step_time)
    rows = [x]
    for _ in range(steps):
        r = run(k, p, mi, x, steps=1, opts=opts)
        if not r.completed:
            break
        x = r.x
        rows.append(x)
    return np.array(rows)


__all__ = ["bifurcation", "bifurcation_kind", "first_period_doubling_iterates", "poincare_iterates"]
