"""Sample-and-hold control: a law evaluated at a fixed rate and held between samples.

A digital controller reads the state every ``1/rate`` seconds and holds its output until the
next reading. :func:`sample_and_hold` makes that a hybrid system of the same modes, each
extended with

* a ``clock`` coordinate (s) with unit "mass" and no force, started at ``clock_dot = 1``: it is
  the time since the last sample;
* one coordinate ``held_<input>`` per input (N·m or N), constant between samples: the law acts
  through it (``u = held_<input>``);

and a transition ``sample`` per mode whose guard ``clock − 1/rate`` fires at the rate and whose
:class:`~amble.modelling.hybrid.Explicit` reset sets ``clock = 0`` and every held value to the
(saturated, if declared so) law at that instant. The new coordinates do not couple to the
mechanics (their block of the mass matrix is the identity), so footfalls leave them as they are.
A held value is part of the state — a sampled-data walker's return map includes it.

Laws written with :meth:`~amble.modelling.actuators.Actuators.dynamics` or virtual constraints
need derived quantities at the reset and are not supported here.
"""

from __future__ import annotations

import copy
import dataclasses
import math

import sympy as sp

from ..errors import ModelError
from .geometry import t
from .hybrid import Explicit, Guard, HybridSystem, Impact, Lock, Reset, ResetVisitor, Transition
from .model import Model


def _extend(m: Model) -> tuple[Model, sp.Symbol, list[sp.Symbol]]:
    if m.tree is not None or m.virtual is not None or any(
            e.free_symbols & set(m.derived_placeholders) for e in m._laws.values()):
        raise ModelError(f"model {m.name!r}: sample-and-hold needs a law of q, q̇, t and parameters only")
    out = copy.copy(m)
    out.q, out.qd, out.units = list(m.q), list(m.qd), dict(m.units)
    out.params, out.domains = dict(m.params), dict(m.domains)
    out._k_terms, out._k_added, out._spins = list(m._k_terms), list(m._k_added), list(m._spins)
    (clock,) = out.coordinates("clock", unit=m.time_unit)
    held = [out.coordinates(f"held_{a.symbol}", unit=a.unit)[0] for a in m.actuators]
    for c in (clock, *held):  # ½ ċ²: a unit "inertia" that the impact of a footfall leaves alone
        out.inertia(c, 1)
    extra = sp.zeros(len(held) + 1, 1)
    out._forces = [f.col_join(extra) for f in m._forces]
    law = m.control_law  # saturated as declared
    out._laws = {a.symbol: h for a, h in zip(m.actuators, held)}
    out._saturate = False
    out._sample_law = law  # type: ignore[attr-defined]
    return out, clock, held


class _KeepHeld(ResetVisitor[Reset]):
    """An impulsive reset that also carries the clock and the held inputs across unchanged."""

    def __init__(self, keep: dict, what: str) -> None:
        self.keep, self.what = keep, what

    def impulsive(self, reset: Impact | Lock) -> Reset:
        return dataclasses.replace(reset, relabel={**dict(reset.relabel), **self.keep})


def sample_and_hold(system: HybridSystem, rate: float) -> HybridSystem:
    """The system under its control laws sampled at ``rate`` (Hz) and held (see the module).

    States gain ``clock`` and ``held_<input>`` after the coordinates and ``clock_dot``,
    ``held_<input>_dot`` after the velocities; the default start begins with a sample
    (``clock = 0``, held values = the law at the start)."""
    try:
        rate = float(rate)
    except (TypeError, ValueError):
        raise ModelError(f"sample rate must be a number, got {rate!r}") from None
    if not (rate > 0 and math.isfinite(rate)):
        raise ModelError(f"sample rate must be positive and finite, got {rate}")
    modes, extra = {}, {}
    for name, m in system.modes.items():
        out, clock, held = _extend(m)
        modes[name], extra[name] = out, (clock, held)
    transitions = []
    for tr in system.transitions:
        reset = tr.reset
        src_extra, dst_extra = extra[tr.source], extra[tr.target]
        keep = dict(zip([dst_extra[0], *dst_extra[1]], [src_extra[0], *src_extra[1]]))
        if reset is not None:
            reset = reset.accept(_KeepHeld(keep, f"system {system.name!r}: sample-and-hold of {tr.name!r}"))
        transitions.append(Transition(tr.name, tr.source, tr.target, tr.guard, reset, tr.terminal, tr.step))
    out = dataclasses.replace(system, modes=modes, transitions=transitions, default_start={},
                              fixed_point_guess=None)
    for name, m in modes.items():
        clock, held = extra[name]
        law = m._sample_law  # type: ignore[attr-defined]
        n0 = len(m.q) - 1 - len(held)
        qmap = {**{str(q): q for q in m.q[:n0]}, str(clock): sp.Integer(0),
                **{str(h): law[j] for j, h in enumerate(held)}}
        vmap = {**{str(v): v for v in m.qd[:n0]}, str(m.dot(clock)): sp.Integer(1),
                **{str(m.dot(h)): sp.Integer(0) for h in held}}
        label = "sample" if len(modes) == 1 else f"sample_{name}"
        out.transition(label, name, Guard(clock - 1 / rate, +1), Explicit(qmap, vmap), name)
        start = system.default_start.get(name)
        if start is not None:
            subs = {**dict(zip([*m.q[:n0], *m.qd[:n0]], start)), **m.params}
            u0 = [float(sp.sympify(e).subs(subs).subs(t, 0)) for e in law]
            out.default_start[name] = [*start[:n0], 0.0, *u0, *start[n0:], 1.0, *[0.0] * len(held)]
    return out

