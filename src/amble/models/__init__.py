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

:func:`load` returns a new, independent system on every call: adding an actuator, a transition
or a mode to it changes no other caller's copy. The library module's ``build()`` runs once per
process; later calls copy its result (containers and amble's own objects are copied, SymPy
expressions, which are immutable, are shared).

:func:`source_files` and :func:`load_traced` tell the warm start of the command line
(:mod:`amble.backend.index`) which files a model is made from, so that a compiled model can be
found again without building the model.
"""

from __future__ import annotations

import contextlib
import importlib
import math
import os
import sys
from functools import cache, lru_cache
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ..errors import ModelError

if TYPE_CHECKING:  # the model library is listed and located without SymPy
    from ..modelling.hybrid import HybridSystem


@lru_cache(maxsize=1)
def registry() -> dict[str, str]:
    """Model name → module name, for every module of this package that defines ``NAME``, in the
    order the modules declare with ``POSITION`` (then by name)."""
    import pkgutil  # here, not at import: a warm start by name needs no listing of the library

    found: list[tuple[float, str, str]] = []
    for info in pkgutil.iter_modules(__path__):
        mod = importlib.import_module(f"{__name__}.{info.name}")
        name = getattr(mod, "NAME", None)
        if name:
            found.append((float(getattr(mod, "POSITION", math.inf)), name, info.name))
    return {name: module for _, name, module in sorted(found)}


def names() -> list[str]:
    return list(registry())


def load(name: str) -> HybridSystem:
    """A model of the library by name: a new system each call, independent of every other
    caller's (the module's ``build()`` runs once per process; see the module docstring)."""
    return _fresh(_built(name), {})


@cache
def _built(name: str) -> HybridSystem:
    reg = registry()
    if name not in reg:
        raise ModelError(f"unknown model {name!r}; available: {', '.join(reg)}")
    return importlib.import_module(f"{__name__}.{reg[name]}").build()


def _fresh(obj: Any, memo: dict[int, Any]) -> Any:
    """A copy of ``obj`` that shares nothing mutable of amble's with it: builtin containers and
    instances of amble's classes are copied, recursively (references between them keep their
    shape: a tree's link back to its model points at the copied model); everything else —
    SymPy expressions, numbers, strings, functions — is immutable or not amble's, and shared."""
    hit = memo.get(id(obj))
    if hit is not None:
        return hit
    kind = type(obj)
    if kind is list or kind is set:
        new: Any = kind()
        memo[id(obj)] = new
        (new.extend if kind is list else new.update)(_fresh(v, memo) for v in obj)
    elif kind is dict:
        new = {}
        memo[id(obj)] = new
        new.update((k, _fresh(v, memo)) for k, v in obj.items())
    elif kind is tuple:
        new = tuple(_fresh(v, memo) for v in obj)
        memo[id(obj)] = new
    elif kind.__module__.startswith("amble.") and hasattr(obj, "__dict__") and not isinstance(obj, type):
        new = object.__new__(kind)  # frozen dataclasses too: their fields are set through __dict__
        memo[id(obj)] = new
        new.__dict__.update((k, _fresh(v, memo)) for k, v in vars(obj).items())
    else:
        return obj
    return new


def source_files(spec: str) -> list[Path]:
    """The files a model is built from, as far as they are known before building it: every
    module of the library for a library model (one may extend another), the file itself for
    ``path.py[:callable]`` (what it reads while it runs is found by :func:`load_traced`)."""
    if is_file_spec(spec):
        return [Path(_split_spec(spec)[0]).resolve()]
    if is_robot_file(spec):
        if Path(spec).suffix.lower() in _MJCF:
            return _mjcf_files(Path(spec).resolve())
        return [Path(spec).resolve()]
    return sorted(f for d in __path__ for f in Path(d).resolve().glob("*.py"))


def _mjcf_files(path: Path, seen: list[Path] | None = None) -> list[Path]:
    """An MJCF file and the files it ``<include>``s (paths relative to the including file),
    recursively: an edit to any of them is an edit to the robot."""
    import xml.etree.ElementTree as ET

    seen = [] if seen is None else seen
    if path in seen:
        return seen
    seen.append(path)
    try:
        root = ET.parse(path).getroot()
    except (OSError, ET.ParseError):
        return seen  # the loader says what is wrong with it
    for inc in root.iter("include"):
        name = inc.get("file")
        if name:
            _mjcf_files((path.parent / name).resolve(), seen)
    return seen


def load_traced(spec: str) -> tuple[HybridSystem, list[Path]]:
    """The system of ``spec`` (a library model or a model file) and the files outside amble and
    the Python installation that were read while it was built: the modules a model file imports
    from its own directory, the data (a URDF, a table) it opens."""
    if not is_file_spec(spec):
        return load(spec), []
    before = set(sys.modules)
    opened: set[str] = set()
    _install_audit()
    _TRACING.append(opened)
    try:
        system = load_file(spec)
    finally:
        _TRACING.remove(opened)
    for name in set(sys.modules) - before:
        f = getattr(sys.modules.get(name), "__file__", None)
        if f:
            opened.add(f)
    return system, sorted({p for f in opened for p in [_outside(f)] if p is not None})


#: the sets of paths being collected by :func:`load_traced` (the audit hook adds to each)
_TRACING: list[set[str]] = []
_AUDIT: list[bool] = []


def _install_audit() -> None:
    if not _AUDIT:
        _AUDIT.append(True)
        sys.addaudithook(_on_audit)  # once per process; it does nothing while no load is traced


def _on_audit(event: str, args: tuple) -> None:
    if event == "open" and _TRACING:
        path, mode = args[0], args[1] if len(args) > 1 else "r"
        if isinstance(path, (str, os.PathLike)) and not any(c in str(mode or "r") for c in "wax+"):
            for s in _TRACING:
                s.add(os.fspath(path))


def _outside(path: str) -> Path | None:
    """``path`` resolved, if it is a regular file outside amble, the Python installation and
    byte-code caches; else ``None``."""
    try:
        p = Path(path).resolve()
        if not p.is_file():
            return None
    except (OSError, ValueError):
        return None
    skip = {Path(__file__).resolve().parents[1], *(Path(d).resolve() for d in
            {sys.prefix, sys.base_prefix, sys.exec_prefix, sys.base_exec_prefix})}
    if "__pycache__" in p.parts or any(p.is_relative_to(d) for d in skip):
        return None
    return p


#: suffixes of robot description files the command line takes as a model (URDF, MuJoCo's MJCF)
ROBOT_SUFFIXES = (".urdf", ".xml", ".mjcf")
_MJCF = (".xml", ".mjcf")
#: suffixes of robot descriptions that are recognised but not read
_UNREAD = {".sdf": "SDF"}


def is_robot_file(spec: str) -> bool:
    """Whether ``spec`` names a robot description file (``….urdf``, MJCF ``….xml``/``….mjcf``;
    SDF is recognised and refused by :func:`load_robot`)."""
    return spec.lower().endswith(ROBOT_SUFFIXES + tuple(_UNREAD))


#: what a robot file's joint limits do in :func:`load_robot`: nothing, or end the run
LIMIT_ACTIONS = ("ignore", "stop")


def load_robot(path: str | os.PathLike, base: str | None = None, fixed_base: bool = False,
               limits: str = "ignore") -> HybridSystem:
    """The robot of a URDF or MJCF file as a system of one mode. No ground, no contact: a
    floating robot falls, a fixed one swings under gravity; the default start is every coordinate
    and rate zero.

    A URDF: its tree with ``base`` (default: the file's root link) attached to the world by a
    ``floating`` joint (six coordinates ``base_x``, ``base_y``, ``base_z`` (m) and ``base_yaw``,
    ``base_pitch``, ``base_roll`` (rad), zero: the base link at the world origin, upright), or
    fixed to it with ``fixed_base``; links without an inertial are massless.

    An MJCF file (``.xml``, ``.mjcf``, read by MuJoCo's compiler): its bodies hang from the world
    as the file writes them, a body with a free joint floats (coordinates named after the joint),
    or is welded where the file places it with ``fixed_base``; zero is the file's pose. ``base``
    is refused: the file's own tree is kept.

    ``limits``: ``"ignore"`` (default) lets joints pass their limits as if they had none;
    ``"stop"`` ends the run where a joint reaches one (:meth:`HybridSystem.stop_at_limits`:
    status ``joint_limit``, the last event ``<coordinate>_<bound>_limit``)."""
    from ..modelling.bodies import Joint
    from ..modelling.hybrid import HybridSystem
    from ..modelling.model import Model

    text = os.fspath(path)
    suffix = Path(text).suffix.lower()
    kind = _UNREAD.get(suffix)
    if kind is not None:
        raise ModelError(f"{text}: {kind} files are not read; give the robot as a URDF or MJCF file")
    if not Path(text).is_file():
        raise ModelError(f"robot file {text!r} does not exist")
    if suffix in _MJCF:
        if base is not None:
            raise ModelError(f"--base {base}: an MJCF file keeps its own tree (its free joints float; "
                             "--fixed-base welds them)")
        model = Model.from_mjcf(text, fixed_base=fixed_base)
        # a free joint is the tree's floating joint: its first frame hangs from the world
        floats = any(b.parent is None and b.name.endswith(".x") for b in model.tree.bodies)
        what = "floating base" if floats else "fixed base"
    else:
        model = Model.from_urdf(text, base=base, base_joint=None if fixed_base else Joint("floating"),
                                allow_massless=True)
        what = "fixed base" if fixed_base else "floating base"
    system = HybridSystem(model.name, model, doc=f"{Path(text).name}: {what}, {len(model.q)} coordinates")
    system.default_start[model.name] = [0.0] * (2 * len(model.q))
    if limits not in LIMIT_ACTIONS:
        raise ModelError(f"limits must be one of {', '.join(LIMIT_ACTIONS)}, got {limits!r}")
    if limits == "stop":
        import warnings

        with warnings.catch_warnings():  # a robot without limits: the caller says so (the command line does)
            warnings.simplefilter("ignore")
            system.stop_at_limits()
    return system


def load_walker(path: str | os.PathLike, feet: Any, **options: Any) -> Any:
    """A point-foot walker of the URDF at ``path``: the file loaded once per stance foot, each
    rooted at that foot and pivoting at its contact point, every other moving joint actuated
    (bounded by the file's ``effort``), the footfalls derived (plastic impacts of the contact
    points). ``feet``: ``{mode: (link, (x, y, z))}``, e.g. Bolt's
    ``{"left": ("FL_FOOT", (0, 0, -0.016)), "right": ("FR_FOOT", (0, 0, -0.016))}``; ``options``:
    ``hip``, ``pivot`` (``"spherical"`` or a revolute axis), ``slope``, ``name``,
    ``max_step_time``, ``virtual`` (:class:`~amble.modelling.point_feet.VirtualOutputs`: virtual
    constraints on the joints), ``parameters`` — see
    :func:`amble.modelling.point_feet.point_foot_walker`."""
    from ..modelling.point_feet import point_foot_walker

    text = os.fspath(path)
    if Path(text).suffix.lower() != ".urdf":
        raise ModelError(f"{text}: a walker is made from a URDF file")
    return point_foot_walker(text, feet, **options)


def __getattr__(name: str) -> Any:
    if name == "VirtualOutputs":  # with SymPy: imported when asked for, as the package root does
        from ..modelling.point_feet import VirtualOutputs

        return VirtualOutputs
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


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
    import importlib.util  # here, not at import: a library model is found without it

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
    except SystemExit as e:  # not an Exception: it would pass every handler up to the interpreter
        raise ModelError(f"model file {path_text!r} called sys.exit({e.code!r}) while it was loaded; "
                         "a model file builds a system and returns it") from None
    except Exception as e:  # anything the user's code raises: one line, with its place in the file
        first = str(e).splitlines()[0] if str(e) else ""
        raise ModelError(f"{_where(e, path)}{type(e).__name__}: {first}") from e
    from ..modelling.hybrid import HybridSystem

    if not isinstance(system, HybridSystem):
        raise ModelError(f"{spec}: returned {type(system).__name__}, not a HybridSystem")
    return system


def _system_of(module, path_text: str, attr: str):
    from ..modelling.hybrid import HybridSystem

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
    import traceback

    target = str(path.resolve())
    line = None
    for frame in traceback.extract_tb(e.__traceback__):
        if str(Path(frame.filename).resolve()) == target:
            line = frame.lineno
    return f"{path}:{line}: " if line else f"{path}: "
