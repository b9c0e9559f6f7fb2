"""Command-line input: parsing of ``NAME=VALUE`` and ``NAME=START:STOP:COUNT`` options, output
paths and model names, each refused with a :class:`UsageError` (an output path: :class:`OutputError`;
exit code 2) before work starts."""

from __future__ import annotations

import argparse
import functools
import math
import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from ..errors import AmbleError, ModelError, OutputError

#: Most points of a sweep grid (all ranges together): a million rows of results take about a
#: gigabyte in memory, and the grid itself is allocated before any work.
MAX_GRID_POINTS = 1_000_000


class UsageError(AmbleError):
    """Bad command-line input."""


class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> None:  # one line, exit 2, no usage dump
        raise UsageError(message)


def _float(text: str, what: str) -> float:
    try:
        v = float(text)
    except ValueError:
        raise UsageError(f"{what}: {text!r} is not a number") from None
    if not math.isfinite(v):
        raise UsageError(f"{what}: {text!r} is not finite")
    return v


def check_tol(tol: float) -> float:
    """``--tol``: a positive finite number (the fixed-point residual), else :class:`UsageError`."""
    if not (tol > 0 and math.isfinite(tol)):
        raise UsageError(f"--tol must be a positive number, got {tol}")
    return float(tol)


def parse_sets(items: Sequence[str] | None) -> dict[str, float]:
    """``NAME=VALUE`` pairs → dict (values must be finite numbers)."""
    out: dict[str, float] = {}
    for item in items or []:
        name, eq, val = item.partition("=")
        if not eq or not name.strip():
            raise UsageError(f"--set expects NAME=VALUE, got {item!r}")
        out[name.strip()] = _float(val.strip(), f"--set {name.strip()}")
    return out


def parse_range(text: str) -> tuple[str, float, float, int]:
    """``NAME=START:STOP:COUNT`` → (name, start, stop, count)."""
    name, eq, rng = text.partition("=")
    parts = rng.split(":")
    if not eq or not name.strip() or len(parts) != 3:
        raise UsageError(f"--param expects NAME=START:STOP:COUNT, got {text!r}")
    start, stop = _float(parts[0], "range start"), _float(parts[1], "range stop")
    try:
        count = int(parts[2])
    except ValueError:
        raise UsageError(f"range count {parts[2]!r} is not an integer") from None
    if count < 1:
        raise UsageError(f"range count must be at least 1, got {count}")
    if count > MAX_GRID_POINTS:  # once an untyped MemoryError (or ValueError) allocating the grid
        raise UsageError(f"range count must be at most {MAX_GRID_POINTS}, got {count}")
    if count > 1 and start == stop:
        raise UsageError(f"empty range {start}:{stop} with {count} points")
    if start > stop:
        raise UsageError(f"reversed range {start}:{stop}: give START below STOP")
    return name.strip(), start, stop, count


def check_grid_size(counts: Sequence[int], what: str) -> None:
    """:class:`UsageError` if a grid of ``counts`` points per axis has more than
    :data:`MAX_GRID_POINTS` points."""
    total = math.prod(counts)
    if total > MAX_GRID_POINTS:
        raise UsageError(f"{what}: {' × '.join(map(str, counts))} = {total} points, more than the "
                         f"{MAX_GRID_POINTS} a sweep may have; split it into several sweeps")


def writable_path(path: str | None, suffixes: Sequence[str], what: str) -> Path | None:
    """``path`` as a :class:`Path` if it could be written, else :class:`OutputError`; leaves nothing
    behind.

    The suffix must be one of ``suffixes``; the directory must exist and a file must be creatable
    in it (outputs are written to a part file there and renamed, :mod:`amble.cli.output`; a probe
    file is created and removed to find out, which also catches a read-only file system and a
    process running as root, for whom permission bits say little), and an existing file must be a
    regular, writable file."""
    if path is None:
        return None
    p = Path(path)
    if p.suffix.lower() not in suffixes:
        raise OutputError(f"{what}: {path!r} must end with one of {', '.join(suffixes)}")
    parent = p.parent if str(p.parent) else Path(".")
    if not parent.is_dir():
        raise OutputError(f"{what}: directory {str(parent)!r} does not exist")
    if p.exists():
        if not p.is_file():
            raise OutputError(f"{what}: {path!r} exists and is not a file")
        try:
            open(p, "ab").close()  # opening to append changes nothing
        except OSError as e:
            raise OutputError(f"{what}: cannot write {path!r} ({e.strerror or e})") from None
    import tempfile  # here, not at import: a command without output files never needs it

    try:
        fd, probe = tempfile.mkstemp(prefix=f".{p.name}.", suffix=".probe", dir=parent)
        os.close(fd)
        os.unlink(probe)
    except OSError as e:
        raise OutputError(f"{what}: cannot create files in {str(parent)!r} ({e.strerror or e})") from None
    return p


def robot_options(args: Any) -> dict[str, Any]:
    """``--base`` and ``--fixed-base`` of a command, for :func:`load_model`; a :class:`UsageError`
    when they are given with a model that is not a robot file."""
    from ..models import is_robot_file

    base, fixed = getattr(args, "base", None), bool(getattr(args, "fixed_base", False))
    if (base is not None or fixed) and not is_robot_file(args.model):
        raise UsageError(f"--base and --fixed-base apply to a robot file (.urdf, .xml), not to {_shown(args.model)}")
    return {"base": base, "fixed_base": fixed}


def load_model(name: str, *, compiled: bool = False, derivatives: bool = False, base: str | None = None,
               fixed_base: bool = False, limits: str = "ignore"):
    """A library model by name, the system of a model file ``path/to/file.py[:callable]``, or the
    robot of a URDF file (``base``, ``fixed_base``: :func:`amble.models.load_robot`).

    ``compiled``: a :class:`~amble.backend.compiled.CompiledSystem` when the warm-start index
    (:mod:`amble.backend.index`) holds the model's compiled library (with the derivative kernels
    if ``derivatives``) — no SymPy is imported; otherwise the model is built and its index entry
    refreshed, so that the next run starts warm.

    A model file that calls ``sys.exit()`` while it is loaded, or a path the operating system
    cannot look up (too long, a NUL byte), is a :class:`~amble.errors.ModelError`: the command
    would otherwise end with the file's exit code and no output, or with an internal error.

    ``limits="stop"``: the run ends where a joint reaches a limit of its range
    (:meth:`~amble.modelling.hybrid.HybridSystem.stop_at_limits`); a system without any is
    loaded as it is, with a warning."""
    from ..modelling.limits import limit_of  # no SymPy: a warm start stays light
    from ..models import is_file_spec, is_robot_file

    if is_robot_file(name):
        _check_model_path(name)
        system = _load_robot(name, base, fixed_base, compiled, derivatives, limits)
    else:
        if is_file_spec(name):
            _check_model_path(name)
        # the limits' terminals change the system: built from its declaration, not the warm index
        system = _load(name, compiled and limits == "ignore", derivatives)  # a file's sys.exit() is a ModelError
        if limits == "stop":
            import warnings

            with warnings.catch_warnings():  # said once below, for a robot file and a model alike
                warnings.simplefilter("ignore")
                system.stop_at_limits()
    if limits == "stop" and not any(limit_of(tr.name) for tr in system.transitions):
        import warnings

        warnings.warn(f"--limits stop: {_shown(name)} has no joint with a limit; the run is not stopped at any",
                      stacklevel=2)
    return system


def _load_robot(path: str, base: str | None, fixed_base: bool, compiled: bool, derivatives: bool,
                limits: str = "ignore"):
    from ..models import load_robot, source_files

    build = functools.partial(load_robot, path, base=base, fixed_base=fixed_base, limits=limits)
    if not compiled:
        return build()
    from ..backend import index

    # the options shape the system: each choice of base (and of what limits do) is an index entry of its own
    stop = "" if limits == "ignore" else f"&limits={limits}"
    spec, sources = f"{path}?base={base or ''}&fixed={int(fixed_base)}{stop}", source_files(path)
    hit = index.lookup(spec, sources, build, derivatives)
    if hit is not None:
        return hit
    system = build()
    index.record(spec, sources, system, sources)
    return system


def _load(name: str, compiled: bool, derivatives: bool):
    from ..models import is_file_spec, load, load_file, load_traced, source_files

    if not compiled:
        return load_file(name) if is_file_spec(name) else load(name)
    from ..backend import index

    sources = source_files(name)
    hit = index.lookup(name, sources, functools.partial(load_model, name), derivatives)
    if hit is not None:
        return hit
    system, read = load_traced(name)
    index.record(name, sources, system, read)
    return system


def _shown(name: str, most: int = 80) -> str:
    """``name`` quoted for a one-line message, shortened past ``most`` characters."""
    return repr(name) if len(name) <= most else f"{name[:most]!r}… ({len(name)} characters)"


def _check_model_path(spec: str) -> None:
    """:class:`ModelError` if the path of the model file ``spec`` (``path.py[:callable]``) cannot
    be looked up at all; a path that names no file is left to the loader (which says so)."""
    path = spec if spec.endswith(".py") or not spec.rpartition(":")[0].endswith(".py") else spec.rpartition(":")[0]
    try:
        os.stat(path)
    except FileNotFoundError:
        return
    except (OSError, ValueError) as e:  # ENAMETOOLONG, ELOOP, EACCES …; ValueError: a NUL byte
        why = e.strerror if isinstance(e, OSError) and e.strerror else str(e)
        raise ModelError(f"model file {_shown(path)}: cannot be opened ({why})") from None


def parse_start(system: Any, text: str | None, params: dict[str, float], option: str) -> Any:
    """A state given on the command line: ``'x0=V1,V2,...'`` (read with ``float``, never
    evaluated) or ``'fixed-point'`` (the gait at ``params``); ``None`` for no text."""
    if text is None:
        return None
    if text == "fixed-point":
        from ..analysis.poincare import find_fixed_point

        return find_fixed_point(system, params=params).fixed_point
    if text.startswith("x0="):
        vals = text[3:].split(",")
        if vals and not vals[-1].strip():
            vals = vals[:-1]  # a trailing comma is harmless
        if any(not v.strip() for v in vals):  # an empty field between commas is a missing value
            raise UsageError(f"x0: empty value at position {[v.strip() for v in vals].index('') + 1} in {text!r}")
        return [_float(v, "x0") for v in vals]
    raise UsageError(f"{option} expects 'fixed-point' or 'x0=V1,V2,...', got {text!r}")
