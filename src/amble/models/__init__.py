"""The model library: each module defines ``build() -> HybridSystem`` with the public API only."""

from __future__ import annotations

import importlib
from functools import cache, lru_cache

from ..errors import ModelError
from ..hybrid import HybridSystem

#: model name → module (in this package)
REGISTRY: dict[str, str] = {
    "compass-gait": "compass_gait",
}


def names() -> list[str]:
    return list(REGISTRY)


@cache
def load(name: str) -> HybridSystem:
    """Build a model of the library by name (cached per process)."""
    if name not in REGISTRY:
        raise ModelError(f"unknown model {name!r}; available: {', '.join(REGISTRY)}")
    mod = importlib.import_module(f"{__name__}.{REGISTRY[name]}")
    return mod.build()
