"""Actuators and control laws of a model: inputs ``u``, the input matrix ``B`` and ``u = k(q, q̇, t)``.

An actuator is declared on what it drives — a coordinate or any expression of ``q`` (a relative
joint angle ``swing − stance``, a length) — and by virtual work its generalized force is
``B u`` with column ``j`` of ``B`` equal to ``∂on_j/∂q``: a torque ``u`` between two absolute
leg angles acts with ``+u`` on the swing leg and ``−u`` on the stance leg. An input is a torque
(N·m) when what it drives is an angle and a force (N) when it is a length.

A control law gives inputs as expressions of the state, the time and the parameters. It may
also use the model's own dynamics, ``M, h = model.mass_and_bias()`` — matrices of placeholder
symbols that :func:`amble.derive` replaces by the derived ``M(q)`` and ``h(q, q̇)`` — so
computed torque is one line: ``model.control(dict(zip(u, Binv * (M * v + h))))``. Point
positions, Jacobians (``model.jacobian(model.points[name])``) and velocities
(``model.dt(model.points[name])``) are expressions of ``q`` and ``q̇`` already.

Inputs without a law are zero. ``saturate=True`` clips every input with a declared ``limit``
to ``[−limit, limit]`` (a ``Min``/``Max`` whose kinks the simulation locates as events).
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import sympy as sp

from ..errors import ModelError
from .expressions import checked_expr
from .geometry import t
from .names import Names
from .revision import declaration


@dataclass(frozen=True)
class Actuator:
    """One input: its symbol, what it drives (an expression of ``q``) and its bound (or None)."""

    symbol: sp.Symbol
    on: sp.Expr
    limit: float | None
    unit: str


class Actuators(Names):
    """The actuator part of a :class:`~amble.modelling.model.Model` (mixed in; see the module)."""

    def __init__(self, name: str, time_unit: str = "s") -> None:
        super().__init__(name, time_unit)
        self.actuators: list[Actuator] = []
        self._laws: dict[sp.Symbol, sp.Expr] = {}
        self._saturate = False
        #: placeholder symbol → ("M", i, j) or ("h", i, 0), replaced by derive()
        self.derived_placeholders: dict[sp.Symbol, tuple[str, int, int]] = {}
        #: virtual constraints of hybrid zero dynamics, if declared (:meth:`virtual_constraints`)
        self.virtual: Any = None

    def _check_new_name(self, name: str, what: str) -> None:
        super()._check_new_name(name, what)
        if any(str(a.symbol) == name for a in getattr(self, "actuators", ())):
            raise ModelError(f"model {self.name!r}: {what} name {name!r} is already taken by an input")

    # ------------------------------------------------------------------ declarations
    @declaration
    def actuator(self, name: str, on: Any, limit: float | None = None, unit: str | None = None) -> sp.Symbol:
        """Declare an input acting on ``on`` (a coordinate, or an expression of the coordinates
        such as ``swing - stance``), bounded by ``|u| ≤ limit`` (N·m or N; None: unbounded).

        Returns the input's real sympy symbol, named ``name``. ``unit`` defaults to ``N·m`` when
        ``on`` is in radians (every coordinate it uses is) and ``N`` otherwise."""
        self._check_new_name(name, "input")
        on_e = checked_expr(self, on, f"what input {name!r} acts on")
        used = on_e.free_symbols
        coords = [s for s in used if s in self.q]
        bad = sorted(str(s) for s in used - set(self.q) - set(self.params))
        if bad or not coords:
            raise ModelError(f"model {self.name!r}: input {name!r} must act on an expression of the "
                             f"coordinates, got {on!r}")
        if limit is not None:
            try:
                limit = float(limit)
            except (TypeError, ValueError):
                raise ModelError(f"model {self.name!r}: limit of input {name!r} must be a number, "
                                 f"got {limit!r}") from None
            if not limit > 0 or limit == float("inf"):
                raise ModelError(f"model {self.name!r}: limit of input {name!r} must be positive and finite, "
                                 f"got {limit}")
        if unit is None:
            unit = "N·m" if all(self.units.get(str(s), "rad") == "rad" for s in coords) else "N"
        sym = sp.Symbol(name, real=True)
        self.actuators.append(Actuator(sym, on_e, limit, unit))
        self.units[name] = unit
        return sym

    @property
    def inputs(self) -> list[sp.Symbol]:
        """The input symbols, in declaration order."""
        return [a.symbol for a in self.actuators]

    @property
    def input_limits(self) -> dict[str, float | None]:
        """Input name → bound of ``|u|`` (N·m or N), None where unbounded."""
        return {str(a.symbol): a.limit for a in self.actuators}

    def input_unit(self, name: str) -> str:
        """Unit of an input by name (``N·m`` or ``N``)."""
        for a in self.actuators:
            if str(a.symbol) == name:
                return a.unit
        raise ModelError(f"model {self.name!r}: no input named {name!r}")

    def input_matrix(self) -> sp.Matrix:
        """``B`` (n × nu): column ``j`` is ``∂on_j/∂q``, so the generalized force is ``B u``."""
        n = len(self.q)
        if not self.actuators:
            return sp.zeros(n, 0)
        return sp.Matrix([[sp.diff(a.on, qi) for a in self.actuators] for qi in self.q])

    def dynamics(self) -> tuple[sp.Matrix, sp.Matrix]:
        """Deprecated name of :meth:`mass_and_bias`."""
        warnings.warn("Model.dynamics() is now Model.mass_and_bias()", DeprecationWarning, stacklevel=2)
        return self.mass_and_bias()

    def mass_and_bias(self) -> tuple[sp.Matrix, sp.Matrix]:
        """``(M, h)`` for a control law: placeholder matrices (n × n and n × 1) that
        :func:`amble.derive` replaces by the mass matrix and the bias ``h = C q̇ + G`` of
        ``M q̈ + h = Γ + B u`` (the numbers at a state are ``Kernels.dynamics``)."""
        n = len(self.q)
        if not self.derived_placeholders:
            for i in range(n):
                for j in range(n):
                    self.derived_placeholders[sp.Symbol(f"M[{i},{j}]", real=True)] = ("M", i, j)
                self.derived_placeholders[sp.Symbol(f"h[{i}]", real=True)] = ("h", i, 0)
        by = {v: k for k, v in self.derived_placeholders.items()}
        return (sp.Matrix(n, n, lambda i, j: by[("M", i, j)]), sp.Matrix(n, 1, lambda i, _: by[("h", i, 0)]))

    @declaration
    def virtual_constraints(self, outputs: Any, phase: Any, alpha: Any, phase_range: tuple[float, float],
                            epsilon: float = 0.1, kp: float = 1.0, kd: float = 2.0, prefix: str = "") -> Any:
        """Control the inputs by hybrid zero dynamics: drive ``y = outputs(q) − h_d(phase(q), α)``
        to zero with ``ÿ = −kd ẏ/ε − kp y/ε²`` (see :mod:`amble.modelling.virtual`). ``alpha``
        holds one row of Bézier coefficients (rad) per output, ``phase_range`` the phase
        variable's values ``(θ⁺, θ⁻)`` just after and at a footfall. All become parameters
        (``alpha_<i>_<k>``, ``phase_start``, ``phase_end``, ``epsilon``, ``kp``, ``kd``; the
        first three names begin with ``prefix`` if given: modes of one system that each keep their
        own coefficients). Returns the :class:`~amble.modelling.virtual.VirtualConstraints`."""
        from .domain import POSITIVE
        from .virtual import declare

        vc = declare(self, outputs, phase, alpha, phase_range, epsilon, kp, kd, prefix)
        self.declare_domains(epsilon=POSITIVE)
        return vc

    @declaration
    def control(self, laws: Mapping[Any, Any], saturate: bool = False) -> None:
        """Set the closed-loop law ``{input: expression}`` (an input by symbol or name); the
        expressions may use ``q``, ``q̇``, ``t``, parameters and :meth:`dynamics`. Laws given
        earlier for other inputs are kept; inputs without one are zero. ``saturate``: clip
        inputs with a declared limit to ``[−limit, limit]``."""
        if not isinstance(laws, Mapping):
            raise ModelError(f"model {self.name!r}: control() takes a mapping {{input: expression}}, got {laws!r}")
        if self.virtual is not None:
            raise ModelError(f"model {self.name!r}: the virtual constraints set the control law already")
        by_name = {str(a.symbol): a.symbol for a in self.actuators}
        allowed = {*self.q, *self.qd, *self.params, *self.derived_placeholders, t}
        for key, law in laws.items():
            k = by_name.get(str(key))
            if k is None or (isinstance(key, sp.Symbol) and key != k):
                raise ModelError(f"model {self.name!r}: control law for {key!r}, which is not an input "
                                 f"(inputs: {', '.join(by_name) or 'none'})")
            if callable(law) and not isinstance(law, sp.Basic):
                raise ModelError(f"model {self.name!r}: the control law of {k} is a Python callable; give an "
                                 "expression of q, q̇, t and parameters instead")
            e = checked_expr(self, law, f"control law of {k}")
            bad = sorted(str(s) for s in e.free_symbols - allowed)
            if bad:
                raise ModelError(f"model {self.name!r}: control law of {k} uses {', '.join(bad)}, which "
                                 f"{'is' if len(bad) == 1 else 'are'} neither a coordinate, a velocity, a "
                                 "parameter nor t")
            self._laws[k] = e
        self._saturate = bool(saturate) or self._saturate

    @property
    def control_law(self) -> sp.Matrix:
        """The law of every input (nu × 1; zero where none is given), saturated if asked, still
        in terms of the :meth:`dynamics` placeholders."""
        out = []
        for a in self.actuators:
            e = self._laws.get(a.symbol, sp.Integer(0))
            if self._saturate and a.limit is not None and e != 0:
                e = sp.Max(-a.limit, sp.Min(a.limit, e))
            out.append(e)
        return sp.Matrix(len(out), 1, out)

    @property
    def saturated(self) -> bool:
        return self._saturate

    def _copy_actuators(self, out: Actuators, subs: Mapping, vsubs: Mapping) -> None:
        """Actuators and laws of a constrained copy (see ``Model.constrained``)."""
        out.actuators = [Actuator(a.symbol, a.on.subs(subs), a.limit, a.unit) for a in self.actuators]
        out._laws = {k: e.subs(vsubs) for k, e in self._laws.items()}
        out._saturate = self._saturate
        if self.virtual is not None:
            raise ModelError(f"model {self.name!r}: virtual constraints cannot be carried into a constrained "
                             "model; declare them on that model")
