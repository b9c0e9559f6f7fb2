"""The model library: each module defines ``NAME``, ``POSITION`` (its place in the listing) and
``build() -> HybridSystem``, written with the public API only. Modules in this package are
discovered automatically.

:func:`load_file` loads a model from one's own file, ``path/to/file.py[:callable]``:

* with ``:callable``, that module-level name is called with no arguments and must return a
  :class:`~amble.HybridSystem` (a module-level system itself is accepted too);
* without it, the module's ``build()`` is called if it defines one; otherwise the module must
  define exactly one :class:`~amble.HybridSystem` at module level (a ``Walker`` is one).

Any error while the file runs is reported as a :class:`~amble.errors.ModelError` of one line that
names the file and the line of the file where it happened.
"""

from __future__ import annotations

import contextlib
import importlib
import importlib.util
import math
import pkgutil
import sys
import traceback
from functools import cache, lru_cache
from pathlib import Path

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


def is_file_spec(spec: str) -> bool:
    """Whether ``spec`` names a model file (``….py`` or ``….py:callable``) rather than a library model."""
    path, _, _ = _split_spec(spec)
    return path.endswith(".py")


def _split_spec(spec: str) -> tuple[str, str, str]:
    path, colon, attr = spec.rpartition(":")
    if not colon or not path.endswith(".py"):
        return spec, "", ""
    return path, colon, attr


def load_file(spec: str) -> HybridSystem:
    """The system of a model file ``path/to/file.py[:callable]`` (see the module docstring)."""
    path_text, _, attr = _split_spec(spec)
    path = Path(path_text)
    if not path.is_file():
        raise ModelError(f"model file {path_text!r} does not exist")
    mod_name = f"amble_user_model_{abs(hash(str(path.resolve())))}"
    loader_spec = importlib.util.spec_from_file_location(mod_name, path)
    module = importlib.util.module_from_spec(loader_spec)
    sys.modules[mod_name] = module  # dataclasses and pickling look modules up by name
    try:  # what the file prints goes to stderr, so that a command's --json output stays parseable
        with contextlib.redirect_stdout(sys.stderr):
            loader_spec.loader.exec_module(module)
            system = _system_of(module, path_text, attr)
    except ModelError as e:
        if str(e).startswith(path_text):
            raise
        raise ModelError(_where(e, path) + str(e).splitlines()[0]) from e
    except SyntaxError as e:
        raise ModelError(f"{path_text}:{e.lineno}: SyntaxError: {e.msg}") from None
    except Exception as e:  # anything the user's code raises: one line, with its place in the file
        first = str(e).splitlines()[0] if str(e) else ""
        raise ModelError(f"{_where(e, path)}{type(e).__name__}: {first}") from e
    if not isinstance(system, HybridSystem):
        raise ModelError(f"{spec}: returned {type(system).__name__}, not a HybridSystem")
    return system


def _system_of(module, path_text: str, attr: str):
    if attr:
        if not hasattr(module, attr):
            raise ModelError(f"{path_text}: defines no {attr!r}")
        obj = getattr(module, attr)
        return obj if isinstance(obj, HybridSystem) else _call(obj, f"{path_text}:{attr}")
    if callable(getattr(module, "build", None)):
        return _call(module.build, f"{path_text}:build")
    found = [k for k, v in vars(module).items() if isinstance(v, HybridSystem) and not k.startswith("_")]
    if len(found) != 1:
        what = "no HybridSystem" if not found else f"{len(found)} HybridSystems ({', '.join(found)})"
        raise ModelError(f"{path_text}: defines no build() and {what} at module level; "
                         f"name one with {path_text}:NAME")
    return getattr(module, found[0])


def _call(fn, what: str):
    if not callable(fn):
        raise ModelError(f"{what} is not callable")
    return fn()


def _where(e: BaseException, path: Path) -> str:
    """``file:line: `` of the innermost frame of the traceback that lies in ``path``."""
    target = str(path.resolve())
    line = None
    for frame in traceback.extract_tb(e.__traceback__):
        if str(Path(frame.filename).resolve()) == target:
            line = frame.lineno
    return f"{path}:{line}: " if line else f"{path}: "
