"""The names of a model: coordinates and their velocities, parameters with defaults, and what
each name means — its unit, its description, a parameter's physical domain. One name stands for
one symbol (the time ``t`` is reserved)."""

from __future__ import annotations

from collections.abc import Sequence

import sympy as sp

from ..errors import ModelError
from .domain import REAL, Domain
from .geometry import t
from .revision import Revised, declaration


class Names(Revised):
    """Coordinates ``q`` (velocities ``qd``, named ``<coordinate>_dot``), parameters ``params``
    (symbol → default) and their ``units``, ``descriptions`` and ``domains`` (by name)."""

    def __init__(self, name: str, time_unit: str = "s") -> None:
        self.name = name
        self.q: list[sp.Symbol] = []
        self.qd: list[sp.Symbol] = []
        self.params: dict[sp.Symbol, float] = {}
        self.time_unit = time_unit
        #: unit of each coordinate and parameter by name (plots, tables and file headers read it)
        self.units: dict[str, str] = {}
        #: one-line description of a parameter by name
        self.descriptions: dict[str, str] = {}
        #: physical domain of a parameter by name (undeclared: any finite value)
        self.domains: dict[str, Domain] = {}

    # ------------------------------------------------------------------ symbols
    def symbol_table(self) -> dict[str, sp.Symbol]:
        """Every name of the model and its symbol: coordinates, velocities, parameters, the
        time ``t`` and (with actuators) the inputs — the names text may use (:meth:`parse`)."""
        inputs = list(getattr(self, "inputs", []) or [])
        return {str(s): s for s in [*self.q, *self.qd, *self.params, t, *inputs]}

    def parse(self, text: str, condition: bool = False) -> sp.Basic:
        """``text`` (e.g. ``"l*sin(q1) - y"``, or with ``condition`` ``"y_dot < 0"``) as a sympy
        expression in this model's symbols, read by :func:`amble.modelling.text.parse`: nothing
        in it is executed, an unknown name or construct is an :class:`~amble.errors.ExpressionError`.
        The way to read expressions that come back as text (JSON results, files, options)."""
        from .text import parse

        return parse(text, self.symbol_table(), what=f"model {self.name!r}", condition=condition)

    @declaration
    def coordinates(self, names: str | Sequence[str], unit: str = "rad") -> tuple[sp.Symbol, ...]:
        """Declare generalized coordinates (in ``unit``, default radians); returns their symbols
        (velocities: :meth:`dot`)."""
        if isinstance(names, str):
            names = names.replace(",", " ").split()
        out = []
        for n in names:
            self._check_new_name(n, "coordinate")
            self._check_new_name(f"{n}_dot", f"velocity of coordinate {n!r}")
            s = sp.Symbol(n, real=True)
            self.q.append(s)
            self.qd.append(sp.Symbol(f"{n}_dot", real=True))
            self.units[n] = unit
            out.append(s)
        return tuple(out)

    @declaration
    def parameters(self, **defaults: float) -> tuple[sp.Symbol, ...]:
        """Declare parameters with default values, in keyword order; returns their symbols."""
        return tuple(self.parameter(k, v) for k, v in defaults.items())

    @declaration
    def parameter(self, name: str, default: float, doc: str = "", unit: str = "", domain: Domain | None = None
                  ) -> sp.Symbol:
        """Declare one parameter with its default value, an optional one-line description, unit and
        physical :class:`~amble.modelling.domain.Domain` (values outside it are refused)."""
        self._check_new_name(name, "parameter")
        try:
            value = float(default)
        except (TypeError, ValueError):
            raise ModelError(
                f"model {self.name!r}: default of parameter {name!r} must be a number, got {default!r}"
            ) from None
        s = sp.Symbol(name, real=True)
        self.params[s] = value
        if doc:
            self.descriptions[name] = doc
        if unit:
            self.units[name] = unit
        if domain is not None:
            self.declare_domains(**{name: domain})
        return s

    @declaration
    def declare_domains(self, **domains: Domain) -> None:
        """Physical domains of declared parameters, e.g. ``declare_domains(m=POSITIVE, slope=interval(-1, 1))``;
        each default must lie in its domain."""
        for name, dom in domains.items():
            sym = next((s for s in self.params if str(s) == name), None)
            if sym is None:
                raise ModelError(f"model {self.name!r}: domain for unknown parameter {name!r}")
            if not isinstance(dom, Domain):
                raise ModelError(f"model {self.name!r}: domain of {name!r} must be a Domain, got {dom!r}")
            if self.params[sym] not in dom:
                raise ModelError(f"model {self.name!r}: default {self.params[sym]:g} of {name!r} is outside {dom}")
            self.domains[name] = dom

    @declaration
    def restrict(self, names: str | Sequence[str], domain: Domain) -> None:
        """Give several parameters one domain: ``restrict("mh m a b g", POSITIVE)``."""
        if isinstance(names, str):
            names = names.replace(",", " ").split()
        self.declare_domains(**dict.fromkeys(names, domain))

    def domain(self, name: str) -> Domain:
        """The declared domain of a parameter (any finite value if none was declared)."""
        return self.domains.get(name, REAL)

    def _check_new_name(self, name: str, what: str) -> None:
        """Every name of a model stands for one symbol: refuse one already taken — by a coordinate,
        a velocity (``<coordinate>_dot``), a parameter, or the time ``t``."""
        if not isinstance(name, str) or not name.isidentifier():
            raise ModelError(f"model {self.name!r}: {what} name {name!r} is not an identifier")
        if name == str(t):
            raise ModelError(f"model {self.name!r}: {what} name 't' is reserved for time")
        for s in (*self.q, *self.qd, *self.params):
            if str(s) == name:
                raise ModelError(f"model {self.name!r}: {what} name {name!r} is already taken")

    @declaration
    def declare_units(self, **units: str) -> None:
        """Units of declared coordinates or parameters by name, e.g. ``declare_units(mh="kg", a="m")``."""
        known = {str(s) for s in [*self.q, *self.params]}
        for name, unit in units.items():
            if name not in known:
                raise ModelError(f"model {self.name!r}: unit for unknown name {name!r}")
            self.units[name] = str(unit)

    def unit(self, name: str) -> str:
        """Unit of a coordinate, velocity (``<coordinate>_dot``) or parameter by name (``""`` if
        undeclared)."""
        if name in self.units:
            return self.units[name]
        base = name[: -len("_dot")] if name.endswith("_dot") else None
        if base is not None and base in self.units and base in {str(s) for s in self.q}:
            return f"{self.units[base]}/{self.time_unit}"
        return ""

    def dot(self, coordinate: sp.Symbol) -> sp.Symbol:
        """The velocity symbol of a coordinate (named ``<coordinate>_dot``)."""
        try:
            return self.qd[self.q.index(coordinate)]
        except ValueError:
            raise ModelError(f"model {self.name!r}: {coordinate} is not a coordinate") from None

    @property
    def parameter_names(self) -> list[str]:
        return [str(s) for s in self.params]

    @property
    def state_names(self) -> list[str]:
        """State order: all coordinates, then all velocities."""
        return [str(s) for s in self.q] + [str(s) for s in self.qd]

    def symbol(self, name: str) -> sp.Symbol:
        """Look up a coordinate, velocity or parameter symbol by name."""
        for s in [*self.q, *self.qd, *self.params]:
            if str(s) == name:
                return s
        raise ModelError(f"model {self.name!r}: no symbol named {name!r}")
