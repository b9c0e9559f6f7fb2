"""The model library: each module defines ``NAME`` and ``build() -> HybridSystem``, written with
the public API only. Modules in this package are discovered automatically."""

from __future__ import annotations

import importlib
import pkgutil
from functools import cache, lru_cache

from ..errors import ModelError
from ..modelling.hybrid import HybridSystem


@lru_cache(maxsize=1)
def registry() -> dict[str, str]:
    """Model name → module name, for every module of this package that defines ``NAME``."""
    out: dict[str, str] = {}
    for info in sorted(pkgutil.iter_modules(__path__), key=lambda i: i.name):
        mod = importlib.import_module(f"{__name__}.{info.name}")
        name = getattr(mod, "NAME", None)
        if name:
            out[name] = info.name
    order = ["compass-gait", "kneed-biped", "humanoid-2d", "humanoid-3d", "simplest-walker", "rimless-wheel"]
    rank = {n: i for i, n in enumerate(order)}
    return dict(sorted(out.items(), key=lambda kv: (rank.get(kv[0], len(order)), kv[0])))


def names() -> list[str]:
    return list(registry())


@cache
def load(name: str) -> HybridSystem:
    """Build a model of the library by name (cached per process)."""
    reg = registry()
    if name not in reg:
        raise ModelError(f"unknown model {name!r}; available: {', '.join(reg)}")
    return importlib.import_module(f"{__name__}.{reg[name]}").build()
