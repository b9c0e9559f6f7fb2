"""Output files of the command line, written atomically: a file is either complete or absent.

Every writer (samples, plots, animations) writes a hidden part file beside the target, which is
renamed over the target when it is complete. A write that fails — a full disk (``ENOSPC``), a
quota, a permission lost during the run — removes the part file and is an
:class:`~amble.errors.OutputError` naming the file and the reason (exit code 2), instead of an
internal error and a truncated file.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path
from typing import Any

from ..errors import OutputError


def part_path(path: Path) -> Path:
    """The part file of ``path``: hidden, in the same directory (so the rename is atomic), unique to
    this process, and with the same suffix (writers choose the format by it)."""
    return path.with_name(f".{path.stem}.{os.getpid()}.part{path.suffix}")


def write_output(path: Path, write: Callable[[Path], Any], what: str) -> Path:
    """Call ``write(part)`` and rename the part file to ``path``; :class:`OutputError` (``what``
    names the option, e.g. ``--out``) if writing or renaming fails, with no file left behind."""
    part = part_path(path)
    try:
        write(part)
        if not part.exists():  # a writer that chose its own name would leave the target missing
            raise OutputError(f"{what}: {str(path)!r} was not written")
        os.replace(part, path)
    except OSError as e:
        if isinstance(e, OutputError):  # the writer's own words, about the target rather than the part
            raise OutputError(str(e).replace(str(part), str(path))) from None
        reason = e.strerror or (os.strerror(e.errno) if e.errno else "") or str(e) or type(e).__name__
        raise OutputError(f"{what}: cannot write {str(path)!r}: {reason}") from None
    finally:
        try:
            part.unlink()
        except OSError:  # renamed (the usual case) or never created
            pass
    return path


__all__ = ["part_path", "write_output"]
