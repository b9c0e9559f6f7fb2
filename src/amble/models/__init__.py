"""The model library: each module defines ``NAME``, ``POSITION`` (its place in the listing) and
``build() -> HybridSystem``, written with the public API only. Modules in this package are
discovered automatically."""

from __future__ import annotations

import importlib
import math
import pkgutil
from functools import cache, lru_cache

from ..errors import ModelError
from ..modelling.hybrid import HybridSystem


@lru_cache(maxsize=1)
def registry() -> dict[str, str]:
    """Model name → module name, for every module of this package that defines ``NAME``, in the
    order the modules declare with ``POSITION`` (then by name)."""
    found: list[tuple[float, str, str]] = []
    for info in pkgutil.iter_modules(__path__):
        mod = importlib.import_module(f"{__name__}.{info.name}")
        name = getattr(mod, "NAME", None)
        if name:
            found.append((float(getattr(mod, "POSITION", math.inf)), name, info.name))
    return {name: module for _, name, module in sorted(found)}


def names() -> list[str]:
    return list(registry())


@cache
def load(name: str) -> HybridSystem:
    """Build a model of the library by name (cached per process)."""
    reg = registry()
    if name not in reg:
        raise ModelError(f"unknown model {name!r}; available: {', '.join(reg)}")
    return importlib.import_module(f"{__name__}.{reg[name]}").build()
