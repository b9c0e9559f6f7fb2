"""Hybrid systems: modes, guards (witness functions) and resets, kept apart.

A :class:`HybridSystem` is a set of modes — each a :class:`~amble.modelling.model.Model` with its own
coordinates — and transitions between them. A transition has

* a :class:`Guard`: a witness function ``g(q, q̇, t)`` of the source mode; the transition fires
  where ``g`` crosses zero in the guard's direction (default: from positive to non-positive, the
  thesis' Eq. 14 ``h ≤ 0, ḣ ≤ 0``) and its optional enabling condition holds there;
* a reset, one of
  - :class:`Impact`: a perfectly plastic, non-sliding impact of a named point with the ground,
    derived from the model (floating-base impulse), followed by a relabelling of coordinates;
  - :class:`Lock`: an impulsive constraint ``c(q) = 0`` (a knee lock), followed by a change to a
    mode with fewer coordinates;
  - :class:`Explicit`: new ``q`` and ``q̇`` written out by the user (e.g. the thesis' ``J(q)`` and
    ``H_g``);
  or no reset and a terminal status (``fell``): the run ends there.

A unilateral contact with restitution (``amble.unilateral_contact``, derived in
:mod:`amble.derivation.contact`) adds a resting mode and three transitions declared by
:meth:`HybridSystem.resting_contact`: the impact, the rest transition the compiled loop takes
instead of a ``zeno`` end, and the lift-off.

Everything here is a declaration; :mod:`amble.codegen` turns it into compiled code.
"""

from __future__ import annotations

import dataclasses
import numbers
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import sympy as sp
from sympy.core.relational import Relational

from ..errors import ModelError, ParameterError
from .dag import free_symbols
from .expressions import checked_expr
from .geometry import t as _TIME
from .limits import STATUS, transition_name
from .model import Model
from .revision import Revised, declaration
from .text import expr_of, parse
from .transitions import Explicit, Guard, Impact, Lock, Reset, ResetVisitor, Transition

__all__ = ["Explicit", "Guard", "HybridSystem", "Impact", "Lock", "Reset", "ResetVisitor", "Transition",
           "target_exprs"]


@dataclass
class HybridSystem(Revised):
    """Modes and transitions of a hybrid mechanical system.

    ``modes`` maps a mode name to its model (a single :class:`Model` makes one mode named after
    it). The first mode is the default initial mode.

    Declared, optional: ``default_start`` (mode name → full initial state, used when a run is
    given none), ``fixed_point_guess`` (a post-transition state where periodic-orbit searches
    start) and ``max_step_time`` (s; a run with no ``step`` transition for this long ends as
    ``fell``; 0 = no limit). Walker notions (hip, slope, mirrored legs) live in
    :class:`amble.modelling.walker.Walker`.
    """

    name: str
    modes: dict[str, Model]
    transitions: list[Transition] = field(default_factory=list)
    default_start: dict[str, Sequence[float]] = field(default_factory=dict)
    fixed_point_guess: Sequence[float] | None = None
    max_step_time: float = 0.0
    doc: str = ""

    def __post_init__(self) -> None:
        if isinstance(self.modes, Model):
            self.modes = {self.modes.name: self.modes}
        if not self.modes:
            raise ModelError(f"system {self.name!r} has no modes")
        dims = {m.dims for m in self.modes.values()}
        if len(dims) != 1:
            raise ModelError(f"system {self.name!r}: modes mix 2D and 3D models")
        if not (self.max_step_time >= 0):
            raise ModelError(f"system {self.name!r}: max_step_time must be ≥ 0 s, got {self.max_step_time!r}")
        _ = self.parameters  # validates consistent defaults

    # ------------------------------------------------------------------ declaring
    @declaration
    def transition(
        self,
        name: str,
        source: str,
        guard: Guard,
        reset: Reset,
        target: str | None = None,
        *,
        step: bool = False,
    ) -> Transition:
        """Add a transition ``source → target`` fired by ``guard``; ``step`` marks a footfall."""
        target = target or source
        self._check_mode(source)
        self._check_mode(target)
        guard = self._check_guard(source, guard)
        _check_reset(self.modes[source], self.modes[target], reset, name)
        tr = Transition(name, source, target, guard, reset, None, step)
        self.transitions.append(tr)
        return tr

    @declaration
    def terminal(self, name: str, source: str | Sequence[str], guard: Guard | Any, status: str = "fell"
                 ) -> Transition:
        """Add a guard that ends the run with ``status`` (e.g. the hip touching the ground).

        ``source`` may list several modes; ``guard`` is then a Guard or a function ``model →
        Guard`` evaluated per mode (each transition is named ``<name>_<mode>``).
        """
        sources = [source] if isinstance(source, str) else list(source)
        tr = None
        for src in sources:
            self._check_mode(src)
            g = guard if isinstance(guard, Guard) else guard(self.modes[src])
            g = self._check_guard(src, g)
            tr = Transition(name if len(sources) == 1 else f"{name}_{src}", src, src, g, None, status, False)
            self.transitions.append(tr)
        assert tr is not None
        return tr

    @declaration
    def stop_at_limits(self, modes: str | Sequence[str] | None = None, status: str = STATUS) -> list[Transition]:
        """End the run where a joint reaches a limit of its range: one terminal transition per
        finite bound of each limited coordinate (:meth:`Model.limit_guards`) in each of ``modes``
        (default: every mode), ending the run with ``status`` (default ``"joint_limit"``).

        Each is named ``<coordinate>_<bound>_limit`` (``<bound>``: ``lower`` or ``upper``;
        followed by ``@<mode>`` in a system of several modes); :func:`amble.limit_of` reads the
        coordinate and the bound back from the name of the run's last event. The event time is
        located like any guard's (to the run's event tolerance); the event's ``x_pre`` is the
        state at the limit. A joint started outside its range is stopped only if it comes back
        in and crosses a bound again; one started on a bound and moving out stops at once.
        Returns the transitions added (none, with a warning, if no mode has a limited joint)."""
        names = list(self.modes) if modes is None else [modes] if isinstance(modes, str) else list(modes)
        for mode in names:
            self._check_mode(mode)
        planned = [(transition_name(lg, None if len(self.modes) == 1 else mode), mode, lg.guard)
                   for mode in names for lg in self.modes[mode].limit_guards()]
        # every name checked before any is added: a refused call leaves the system as it was
        taken = {tr.name for tr in self.transitions}
        for name, _, _ in planned:
            if name in taken:
                raise ModelError(f"system {self.name!r}: a transition named {name!r} exists already")
            taken.add(name)
        if not planned:
            warnings.warn(f"system {self.name!r}: no joint has a limit, so no run stops at one", stacklevel=2)
        return [self.terminal(name, mode, guard, status=status) for name, mode, guard in planned]

    @declaration
    def add_mode(self, name: str, model: Model) -> None:
        """Add a mode (e.g. the constrained mode of a resting contact)."""
        if name in self.modes:
            raise ModelError(f"system {self.name!r}: a mode named {name!r} exists already")
        if model.dims != self.dims:
            raise ModelError(f"system {self.name!r}: mode {name!r} mixes 2D and 3D models")
        self.modes[name] = model
        _ = self.parameters  # validates consistent defaults

    @declaration
    def resting_contact(self, name: str, free: str, rest: str, gap: Any, impact: Reset, settle: Reset,
                        force: Any, leave: Reset) -> tuple[Transition, Transition, Transition]:
        """Declare the three transitions of a unilateral contact (usually built by
        :func:`amble.unilateral_contact`, which derives them):

        * ``name`` (``free → free``): the gap ``g(q, t)`` reaches zero falling; reset ``impact``;
        * ``<name>_rest`` (``free → rest``): no guard; taken instead of ending the run as
          ``zeno`` when the impacts accumulate (``Options.zeno_events`` of them closer than
          ``Options.zeno_dt``), or at once when an impact leaves no normal velocity while the
          flow presses into the contact (restitution 0, a point started on it); reset ``settle``;
        * ``<name>_liftoff`` (``rest → free``): the contact force ``force`` (N, ``≥ 0`` while
          held) falls through zero; reset ``leave``. ``force`` may be constant (it never lifts off).
        """
        self._check_mode(free)
        self._check_mode(rest)
        taken = {tr.name for tr in self.transitions}
        names = [name, f"{name}_rest", f"{name}_liftoff"]
        if taken & set(names):
            dup = sorted(taken & set(names))[0]
            raise ModelError(f"system {self.name!r}: a transition named {dup!r} exists already")
        hit_guard, lift = Guard(gap, -1), Guard(force, -1)
        self._check_guard(free, hit_guard)
        rest_model = self.modes[rest]
        force = expr_of(force, rest_model.symbol_table(), what=f"system {self.name!r}: contact force of {name!r}")
        if force.free_symbols & (set(rest_model.q) | set(rest_model.qd)):
            self._check_guard(rest, lift)
        else:  # a force of the parameters and time only (a point on a fixed floor: its weight)
            bad = sorted(str(s_) for s_ in force.free_symbols - set(rest_model.params) - {_TIME})
            if bad:
                raise ModelError(f"system {self.name!r}: the contact force of {name!r} uses unknown symbols "
                                 f"{', '.join(bad)}")
        _check_reset(self.modes[free], self.modes[free], impact, names[0])
        _check_reset(self.modes[free], rest_model, settle, names[1])
        _check_reset(rest_model, self.modes[free], leave, names[2])
        hit = Transition(names[0], free, free, hit_guard, impact, rest=names[1])
        settle_tr = Transition(names[1], free, rest, Guard(sp.Integer(1)), settle, forced=True)
        lift_tr = Transition(names[2], rest, free, lift, leave)
        self.transitions += [hit, settle_tr, lift_tr]
        return hit, settle_tr, lift_tr

    # ------------------------------------------------------------------ queries
    @property
    def dims(self) -> int:
        return next(iter(self.modes.values())).dims

    @property
    def mode_names(self) -> list[str]:
        return list(self.modes)

    @property
    def parameters(self) -> dict[str, float]:
        """All parameters of all modes (name → default), in declaration order."""
        out: dict[str, float] = {}
        for m in self.modes.values():
            for s, v in m.params.items():
                k = str(s)
                if k in out and out[k] != v:
                    raise ModelError(
                        f"system {self.name!r}: parameter {k!r} has defaults {out[k]} and {v} in different modes"
                    )
                out[k] = v
        return out

    def symbolic(self) -> HybridSystem:
        """The declared, symbolic system: this one. A system known only by its compiled library
        (:class:`~amble.backend.compiled.CompiledSystem`) builds it here on first use, so code that
        needs the symbols (a control law, contact forces) asks any system the same way."""
        return self

    def full(self) -> HybridSystem:
        """Deprecated name of :meth:`symbolic`."""
        warnings.warn("HybridSystem.full() is now HybridSystem.symbolic()", DeprecationWarning, stacklevel=2)
        return self.symbolic()

    def check_parameters(self, values: Mapping[str, float]) -> None:
        """Raise :class:`ParameterError` for a value outside its parameter's declared domain."""
        for name, v in values.items():
            for m in self.modes.values():
                dom = m.domains.get(name)
                if dom is not None and v not in dom:
                    unit = f" {m.unit(name)}" if m.unit(name) else ""
                    raise ParameterError(f"parameter {name!r} = {v:g}{unit} is outside its domain {dom}")

    @property
    def time_unit(self) -> str:
        return next(iter(self.modes.values())).time_unit

    def unit(self, name: str) -> str:
        """Unit of a state variable or parameter by name, as its mode declares it (``""`` if none)."""
        for m in self.modes.values():
            u = m.unit(name)
            if u:
                return u
        return ""

    def footfall_cycle(self, mode: str | None = None) -> list[str] | None:
        """The section modes of one cycle of footfalls from ``mode`` (default the first), or None
        where it is not unique (:func:`amble.modelling.footfall_cycle.footfall_cycle`)."""
        from .footfall_cycle import footfall_cycle

        return footfall_cycle(self, mode)

    def frame_change(self, transition: str) -> tuple[str | None, tuple[float, float, float]]:
        """How a transition re-expresses positions: the point whose pre-event position becomes the
        new origin (or ``None``) and the diagonal of the axis reflection (world-frame kinematics
        accumulate these over a run)."""
        tr = self._transition(transition)
        return (tr.reset.shift_point if tr.reset is not None else None), (1.0, 1.0, 1.0)

    def _transition(self, name: str) -> Transition:
        for tr in self.transitions:
            if tr.name == name:
                return tr
        raise ModelError(f"system {self.name!r}: no transition named {name!r}")

    def state_names(self, mode: str | None = None) -> list[str]:
        """State names of a mode (default: the first): coordinates, then velocities."""
        return self.modes[mode or self.mode_names[0]].state_names

    @property
    def point_names(self) -> list[str]:
        names: list[str] = []
        for m in self.modes.values():
            for p in m.points:
                if p not in names:
                    names.append(p)
        return names

    def _check_mode(self, mode: str) -> None:
        if mode not in self.modes:
            raise ModelError(f"system {self.name!r}: unknown mode {mode!r} (modes: {', '.join(self.modes)})")

    def _check_guard(self, source: str, guard: Any) -> Guard:
        """``guard`` checked against mode ``source`` and normalised for code generation: the
        expression and the enabling condition as sympy objects in the mode's symbols (text is
        read with them), the direction an ``int``, an enabling condition that always holds
        dropped. Anything the compiled code could not express is a :class:`ModelError` here
        rather than a C compiler's complaint about ``true``, ``I`` or ``Sum``."""
        m = self.modes[source]
        what = f"guard of mode {source!r}"
        if not isinstance(guard, Guard):
            raise ModelError(f"system {self.name!r}: a {what} must be a Guard, got {type(guard).__name__}")
        d = guard.direction
        # True == 1 in Python, but a flag where a direction belongs is a mistake (and reached C as 'True')
        if isinstance(d, bool) or not isinstance(d, numbers.Real) or d not in (-1, 0, 1):
            raise ModelError(f"system {self.name!r}: {what}: direction must be -1, 0 or +1, got {d!r}")
        names = {str(s_): s_ for s_ in [*m.q, *m.qd, *m.params, _TIME]}
        expr = checked_expr(self.name, _read(guard.expr, names, f"system {self.name!r}: {what}: "), what)
        allowed = set(m.q) | set(m.qd) | set(m.params) | {_TIME}
        # free symbols visited once per shared part: a tree's positions are DAGs (exponential otherwise)
        if not (free_symbols(expr) & (set(m.q) | set(m.qd))):
            raise ModelError(
                f"system {self.name!r}: a guard of mode {source!r} does not depend on the state: {expr}"
            )
        enabled = _condition(self.name, guard.enabled, names, f"{what}: enabling condition")
        for e in (expr, enabled if enabled is not None else sp.true):
            bad = sorted(str(s) for s in free_symbols(e) - allowed)
            if bad:
                raise ModelError(
                    f"system {self.name!r}: guard of mode {source!r} uses unknown symbols {', '.join(bad)}"
                )
        return dataclasses.replace(guard, expr=expr, direction=int(d), enabled=enabled)


def _read(value: Any, names: Mapping[str, sp.Symbol], where: str = "", condition: bool = False) -> Any:
    """Text read with the mode's own symbols (``"x > 0"`` means the real coordinate ``x``) by
    :func:`amble.modelling.text.parse`, which runs nothing; anything else unchanged. Unreadable
    text is an :class:`~amble.errors.ExpressionError` (a :class:`ModelError`)."""
    if not isinstance(value, str):
        return value
    return parse(value, names, what=where.rstrip(": ") or "expression", condition=condition)


def _condition(system: str, value: Any, names: Mapping[str, sp.Symbol], what: str) -> Any:
    """An enabling condition as a sympy boolean of comparisons, or ``None`` if it always holds.

    Comparisons (``<``, ``>``, ``Eq`` ...) of checked expressions, joined by ``&``, ``|``, ``~``,
    are accepted; a condition that is always false (the guard could never fire), a number, a
    bare symbol or anything else is a :class:`ModelError`."""
    if value is None:
        return None
    # text is read as a condition; a number or Python bool becomes sympy's, refused below if not a comparison
    e = expr_of(_read(value, names, f"system {system!r}: {what}", condition=True), what=f"system {system!r}: {what}")
    if e is sp.true:
        return None
    if e is sp.false:
        raise ModelError(f"system {system!r}: {what} is always false, so the guard could never fire: {value!r}")
    _check_condition(system, e, what)
    return e


def _check_condition(system: str, e: Any, what: str) -> None:
    if isinstance(e, (sp.And, sp.Or, sp.Not, sp.Xor)):
        for a in e.args:
            _check_condition(system, a, what)
    elif isinstance(e, Relational):
        for side in (e.lhs, e.rhs):
            checked_expr(system, side, what)
    else:
        raise ModelError(f"system {system!r}: {what} must be a comparison such as foot_x > 0 (or several joined "
                         f"by &, |, ~), got {e!r}")


def target_exprs(target: Model, mapping: Any, what: str, velocities: bool = False,
                 source: Model | None = None) -> list[sp.Expr]:
    """Order a relabel mapping (or sequence) by the target mode's coordinates. With a mapping, a
    target coordinate that the source mode also has and the mapping omits is kept as it is.

    Each value is a checked expression (:func:`~amble.modelling.expressions.checked_expr`: no
    ``I``, ``zoo``, unevaluated ``Sum`` or undefined function reaches the compiler); text is read
    with the source mode's symbols."""
    names = [str(s) for s in (target.qd if velocities else target.q)]
    known = {str(s_): s_ for s_ in [*source.q, *source.qd, *source.params, _TIME]} if source is not None else {}
    model = source.name if source is not None else target.name

    def value(v: Any) -> sp.Expr:
        return checked_expr(model, _read(v, known, f"{what}: "), what)

    if isinstance(mapping, Mapping):
        given = {str(k): value(v) for k, v in mapping.items()}
        unknown = sorted(set(given) - set(names))
        if unknown:
            raise ModelError(f"{what}: {', '.join(unknown)} not among the target coordinates {names}")
        if source is not None:
            for s_ in (source.qd if velocities else source.q):
                given.setdefault(str(s_), s_)
        missing = [n for n in names if n not in given]
        if missing:
            raise ModelError(f"{what}: no value for target coordinate(s) {', '.join(missing)}")
        return [given[n] for n in names]
    if isinstance(mapping, (str, bytes)) or not isinstance(mapping, (Sequence, sp.MatrixBase)):
        raise ModelError(f"{what}: expected a mapping or a sequence of {len(names)} values, got {mapping!r}")
    seq = [value(v) for v in list(mapping)]
    if len(seq) != len(names):
        raise ModelError(f"{what}: {len(seq)} values for {len(names)} target coordinates")
    return seq


def _check_reset(src: Model, dst: Model, reset: Reset, name: str) -> None:
    what = f"reset of transition {name!r}"
    if not isinstance(reset, Reset):
        raise ModelError(f"{what}: expected Impact, Lock or Explicit, got {type(reset).__name__}")
    reset.accept(_ResetCheck(src, dst, what))


class _ResetCheck(ResetVisitor[None]):
    """A reset checked against its source and target modes when it is declared."""

    def __init__(self, src: Model, dst: Model, what: str) -> None:
        self.src, self.dst, self.what = src, dst, what

    def impact(self, reset: Impact) -> None:
        if reset.point not in self.src.points:
            raise ModelError(f"{self.what}: impact point {reset.point!r} is not a point of mode {self.src.name!r}")
        self.impulsive(reset)

    def lock(self, reset: Lock) -> None:
        c = checked_expr(self.src.name, reset.constraint, f"{self.what}: lock constraint")
        if not (c.free_symbols & set(self.src.q)):
            raise ModelError(f"{self.what}: lock constraint {c} does not depend on the coordinates")
        self.impulsive(reset)

    def impulsive(self, reset: Impact | Lock) -> None:
        src = self.src
        exprs = target_exprs(self.dst, reset.relabel, self.what, source=src)
        _check_free(exprs, set(src.q) | set(src.params), self.what, "source coordinates")

    def explicit(self, reset: Explicit) -> None:
        src, dst, what = self.src, self.dst, self.what
        exprs = target_exprs(dst, reset.q, what, source=src) + target_exprs(dst, reset.qd, what, True, src)
        allowed = set(src.q) | set(src.qd) | set(src.params) | {sp.Symbol("t", real=True)}
        _check_free(exprs, allowed, what, "source state")
        if reset.shift is not None and reset.shift not in src.points:
            raise ModelError(f"{what}: shift point {reset.shift!r} is not a point of mode {src.name!r}")


def _check_free(exprs: list[sp.Expr], allowed: set, what: str, label: str) -> None:
    for e in exprs:
        bad = sorted(str(s) for s in free_symbols(e) - allowed)
        if bad:
            raise ModelError(f"{what}: uses {', '.join(bad)}, not among the {label} or parameters")
