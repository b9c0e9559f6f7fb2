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


# ---------------------------------------------------------------------- text of results
#: the gait checks of :class:`~amble.analysis.gait_check.GaitCheck` in the order they are printed:
#: (pass flag, worst value, what it is, unit (SI), scale to the printed unit, printed unit, bound)
_CHECKS = (
    ("normal_force_positive", "min_normal_force", "normal ground force, min", "N", 1.0, "N", "> 0"),
    ("friction_ok", "max_friction_ratio", "friction ratio |F_t|/F_n, max", "", 1.0, "", "< μ = {mu:g}"),
    ("swing_foot_clear", "min_swing_clearance", "swing-foot clearance, min", "m", 1e3, "mm", "> 0"),
    ("impulse_positive", "min_normal_impulse", "footfall normal impulse, min", "N·s", 1.0, "N·s", "> 0"),
    ("trailing_foot_leaves", "min_trailing_foot_lift_speed", "trailing-foot lift speed, min", "m/s", 1.0, "m/s",
     "> 0"),
    ("within_limits", "max_input_ratio", "input / limit, max", "", 1.0, "", "≤ 1"),
)


def number(value: Any, digits: int = 4) -> str:
    """A number for people: ``digits`` significant digits (``0.07769230769230769`` → ``0.07769``),
    ``—`` for a missing or non-finite value."""
    if value is None:
        return "—"
    try:
        v = float(value)
    except (TypeError, ValueError):
        return str(value)
    if v != v or v in (float("inf"), float("-inf")):
        return "—" if v != v else ("∞" if v > 0 else "-∞")
    return f"{v:.{digits}g}"


def gait_check_lines(checks: dict[str, Any], si: bool = True) -> list[str]:
    """The text report of :meth:`GaitCheck.to_json <amble.analysis.gait_check.GaitCheck.to_json>`:
    a headline naming the failed checks, then one line per check with its worst value (the margin
    to the bound) in its unit; ``si=False`` (a model whose time is not in seconds) drops units."""
    failed = [flag for flag, *_ in _CHECKS if checks.get(flag) is False]
    lines = ["gait checks: " + ("all passed" if not failed else "FAILED " + ", ".join(failed))]
    for flag, key, what, _, scale, unit, bound in _CHECKS:
        if flag not in checks:
            continue
        v = checks.get(key)
        shown = number(None if v is None else float(v) * (scale if si else 1.0))
        u = f" {unit}" if si and unit and v is not None else ""
        state = "FAILED" if checks[flag] is False else "ok"
        lines.append(f"  {state:<6} {what}: {shown}{u} ({bound.format(mu=checks.get('mu', float('nan')))})")
    return lines


__all__ += ["gait_check_lines", "number"]
