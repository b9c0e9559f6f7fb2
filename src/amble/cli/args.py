"""Command-line input: parsing of ``NAME=VALUE`` and ``NAME=START:STOP:COUNT`` options, output
paths and model names, each refused with a :class:`UsageError` (an output path: :class:`OutputError`;
exit code 2) before work starts."""

from __future__ import annotations

import argparse
import math
import os
from collections.abc import Sequence
from pathlib import Path

from ..errors import AmbleError, OutputError


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
    if count > 1 and start == stop:
        raise UsageError(f"empty range {start}:{stop} with {count} points")
    if start > stop:
        raise UsageError(f"reversed range {start}:{stop}: give START below STOP")
    return name.strip(), start, stop, count


def writable_path(path: str | None, suffixes: Sequence[str], what: str) -> Path | None:
    """``path`` as a :class:`Path` if it could be written, else :class:`OutputError`; creates nothing.

    The suffix must be one of ``suffixes``; the directory must exist and be writable, and an
    existing file must be a regular, writable file."""
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
        if not os.access(p, os.W_OK):
            raise OutputError(f"{what}: cannot write {path!r} (permission denied)")
    elif not os.access(parent, os.W_OK | os.X_OK):
        raise OutputError(f"{what}: cannot create {path!r} in {str(parent)!r} (permission denied)")
    return p


def load_model(name: str):
    """A library model by name, or the system of a model file ``path/to/file.py[:callable]``."""
    from ..models import is_file_spec, load, load_file

    return load_file(name) if is_file_spec(name) else load(name)
