"""Compiled kernels of a system: :func:`compiled`, which loads them from the in-process cache,
the disk cache (:mod:`amble.backend.cache`, which also decides the cache key and compiles), or a
fresh build. The ctypes view of one loaded library is :class:`~amble.backend.library.Kernels`
(re-exported here, its documented import path).

A warm cache skips derivation, code generation and compilation: the shared library and its
metadata are loaded directly. A library whose Python↔C layout (:data:`amble.backend.abi.LAYOUT`)
differs from this loader's is refused.
"""

from __future__ import annotations

import copy
import weakref
from typing import TYPE_CHECKING, Any, Protocol, runtime_checkable

from ..errors import CompileError
from . import cache
from .c_args import address
from .cache import cache_dir, structure_key
from .library import Kernels

if TYPE_CHECKING:  # loading a cached library imports no SymPy
    from ..modelling.hybrid import HybridSystem

__all__ = ["Kernels", "address", "build", "cache_dir", "compiled", "structure_key"]

_LOADED: dict[str, Kernels] = {}



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

