"""A system known by its compiled library and the numbers of its declaration, without SymPy.

A :class:`CompiledSystem` stands in for a :class:`~amble.modelling.hybrid.HybridSystem` where only
numbers are needed — simulating, return maps, fixed points and their multipliers, sweeps: its
names (modes, states, parameters, points, transitions), the parameters' defaults, domains and
units, the default start and fixed-point guess, the step-time limit, how each transition moves
the frame (``frame_change``), the walker's hip. :func:`amble.backend.kernels.compiled` returns its
kernels. It is made by the warm-start index (:mod:`amble.backend.index`) from a small JSON
(:func:`describe`) written when the model was last built.

It holds nothing symbolic and does not pretend to: asking it for what only the declaration has
(a mode's masses, a walker's slope expression) raises :class:`AttributeError` naming
:meth:`CompiledSystem.symbolic`, which builds the declared system from the same source (the
price is the SymPy import that the compiled system otherwise avoids).
:meth:`~amble.modelling.hybrid.HybridSystem.symbolic` is the same call on a declared system, so a
caller that needs the symbols asks any system the same way.

Units: those the model declares (``unit``); times in the model's time unit.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable, Mapping
from typing import TYPE_CHECKING, Any

from ..errors import AmbleError, ModelError, ParameterError
from ..modelling.domain import Domain

if TYPE_CHECKING:
    from ..modelling.hybrid import HybridSystem
    from .library import Kernels

#: version of the :func:`describe` layout; a description of another version is not used
FORMAT = 1


def describe(system: HybridSystem) -> dict[str, Any]:
    """The numbers of a system's declaration that runs and analyses read (JSON-ready)."""
    modes = system.modes
    names = {n for m in modes.values() for n in [*m.state_names, *map(str, m.params), *map(str, m.inputs)]}
    return {
        "format": FORMAT,
        "name": system.name,
        "doc": system.doc,
        "dims": system.dims,
        "time_unit": system.time_unit,
        "modes": {mode: {"state_names": list(m.state_names), "inputs": [str(u) for u in m.inputs],
                         "domains": {k: [d.low, d.high, d.low_open, d.high_open] for k, d in m.domains.items()},
                         "units": {k: m.unit(k) for k in sorted(names)}}
                  for mode, m in modes.items()},
        "parameters": {k: float(v) for k, v in system.parameters.items()},
        "points": list(system.point_names),
        "units": {k: system.unit(k) for k in sorted(names | {"mode"})},
        "transitions": [{"name": tr.name, "source": tr.source, "target": tr.target, "terminal": tr.terminal,
                         "step": bool(tr.step)} for tr in system.transitions],
        "frame_changes": {tr.name: [shift, [float(v) for v in flip]] for tr in system.transitions
                          for shift, flip in [system.frame_change(tr.name)]},
        "default_start": {k: [float(v) for v in x] for k, x in system.default_start.items()},
        "fixed_point_guess": (None if system.fixed_point_guess is None
                              else [float(v) for v in system.fixed_point_guess]),
        "max_step_time": float(system.max_step_time),
        "hip": getattr(system, "hip", None),
        "mirror": getattr(system, "mirror", None),
        "walker": hasattr(system, "slope_value"),
    }


def _missing(owner: str, name: str) -> AttributeError:
    return AttributeError(f"{owner} holds the compiled numbers only, not {name!r}: its .symbolic() "
                          "is the declared system, built from the same source")


class _Info:
    """The declared numbers of a mode or a transition (attributes from a dict)."""

    def __init__(self, what: str, values: Mapping[str, Any]) -> None:
        self.__dict__.update(values)
        self._what = what

    def __getattr__(self, name: str) -> Any:
        if name.startswith("_"):
            raise AttributeError(name)
        raise _missing(self._what, name)


class CompiledSystem:
    """A hybrid system as its compiled library and declared numbers (see the module docstring).

    ``info``: a :func:`describe` dictionary; ``libraries``: ``{derivatives: (library path,
    loader metadata)}`` of the compiled libraries at hand (one built with the derivative kernels
    serves plain runs too); ``loader``: builds the full system when it is needed (it is called at
    most once).
    """

    def __init__(self, info: dict[str, Any], libraries: Mapping[bool, tuple[Any, dict]],
                 loader: Callable[[], HybridSystem]) -> None:
        if info.get("format") != FORMAT:
            raise ModelError(f"compiled system description has format {info.get('format')!r}, expected {FORMAT}")
        self._state = (info, dict(libraries), loader)
        self._open(info, libraries, loader)

    def _open(self, info: dict, libraries: Mapping[bool, tuple[Any, dict]], loader: Callable[[], Any]) -> None:
        from .library import Kernels

        self._info, self._loader, self._system = info, loader, None
        self.name: str = info["name"]
        self.doc: str = info["doc"]
        self.dims: int = info["dims"]
        self.time_unit: str = info["time_unit"]
        self.parameters: dict[str, float] = dict(info["parameters"])
        self.default_start: dict[str, list[float]] = {k: list(v) for k, v in info["default_start"].items()}
        self.fixed_point_guess: list[float] | None = info["fixed_point_guess"]
        self.max_step_time: float = info["max_step_time"]
        self.hip: str | None = info["hip"]
        self.mirror: str | None = info["mirror"]
        self.modes = {mode: _Info(f"mode {mode!r} of compiled system {self.name!r}",
                                  {"inputs": m["inputs"], "state_names": m["state_names"]})
                      for mode, m in info["modes"].items()}
        self.transitions = [_Info(f"transition {tr['name']!r} of compiled system {self.name!r}", tr)
                            for tr in info["transitions"]]
        self._kernels: dict[bool, Kernels] = {}
        for derivatives, (so, meta) in libraries.items():
            k = Kernels(so, meta)
            defaults = [float(self.parameters[p]) for p in meta["params"]]
            k.meta = {**meta, "param_defaults": defaults}  # the defaults of this system, not of the build
            self._kernels[bool(derivatives)] = k

    # ------------------------------------------------------------------ what build() needs
    def compiled_kernels(self, derivatives: bool = False) -> Kernels | None:
        """The compiled kernels (with the derivative kernels if asked), or ``None`` if no library
        at hand has them."""
        return self._kernels.get(True) or (None if derivatives else self._kernels.get(False))

    def symbolic(self) -> HybridSystem:
        """The declared, symbolic system (built on first use, from the same source)."""
        if self._system is None:
            self._system = self._loader()
        return self._system

    def full(self) -> HybridSystem:
        """Deprecated name of :meth:`symbolic`."""
        warnings.warn("CompiledSystem.full() is now CompiledSystem.symbolic()", DeprecationWarning, stacklevel=2)
        return self.symbolic()

    # ------------------------------------------------------------------ HybridSystem's queries
    @property
    def mode_names(self) -> list[str]:
        return list(self._info["modes"])

    def state_names(self, mode: str | None = None) -> list[str]:
        """State names of a mode (default: the first): coordinates, then velocities."""
        return list(self._info["modes"][mode or self.mode_names[0]]["state_names"])

    @property
    def point_names(self) -> list[str]:
        return list(self._info["points"])

    def unit(self, name: str) -> str:
        """Unit of a state variable or parameter by name (``""`` if none is declared)."""
        units = self._info["units"]
        return units[name] if name in units else self.symbolic().unit(name)

    def frame_change(self, transition: str) -> tuple[str | None, tuple[float, float, float]]:
        """The point whose pre-event position becomes the new origin (or ``None``) and the
        diagonal of the axis reflection of a transition."""
        try:
            shift, flip = self._info["frame_changes"][transition]
        except KeyError:
            raise ModelError(f"system {self.name!r}: no transition named {transition!r}") from None
        return shift, (float(flip[0]), float(flip[1]), float(flip[2]))

    def check_parameters(self, values: Mapping[str, float]) -> None:
        """Raise :class:`ParameterError` for a value outside its parameter's declared domain."""
        for name, v in values.items():
            for m in self._info["modes"].values():
                d = m["domains"].get(name)
                if d is not None and v not in Domain(*d):
                    unit = f" {m['units'].get(name, '')}" if m["units"].get(name) else ""
                    raise ParameterError(f"parameter {name!r} = {v:g}{unit} is outside its domain {Domain(*d)}")

    def slope_value(self, params: Mapping[str, float]) -> float:
        """A walker's slope at these parameters (rad), from the full system."""
        return self.symbolic().slope_value(params)

    def __getattr__(self, name: str) -> Any:
        if name.startswith("_"):
            raise AttributeError(name)
        raise _missing(f"compiled system {self.name!r}", name)

    def __getstate__(self) -> tuple:
        return self._state  # a worker process reopens the libraries (ctypes handles do not travel)

    def __setstate__(self, state: tuple) -> None:
        self._state = state
        info, libraries, loader = state
        try:
            self._open(info, libraries, loader)
        except (AmbleError, OSError):  # a worker on another machine: no such library there; build it
            self._open(info, {}, loader)

    def __repr__(self) -> str:
        return f"CompiledSystem({self.name!r}, modes={self.mode_names})"
