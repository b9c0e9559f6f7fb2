"""A designed gait (``gait.json`` of ``amble optimize-gait``) as the start of another command:
its fixed point and the parameter values it was designed with, the controller's among them."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

from .args import UsageError


def gait_start(system: Any, path: str) -> tuple[list[float], dict[str, float]]:
    """The post-impact state and the parameters of the gait in ``path``: its ``parameters``, with
    the values of the model's own virtual-constraint parameters (``bezier.params``) over them,
    so that the model's controller walks the designed gait. The state must be the system's first
    mode's (its state names, in order); a :class:`UsageError` in one line otherwise."""
    p = Path(path)
    try:
        data = json.loads(p.read_text())
    except OSError as e:
        raise UsageError(f"--gait {path}: cannot be read ({e.strerror or e})") from None
    except (UnicodeDecodeError, json.JSONDecodeError) as e:
        raise UsageError(f"--gait {path}: not a gait file (JSON: {e})") from None
    if not isinstance(data, dict) or not isinstance(data.get("fixed_point"), list):
        raise UsageError(f"--gait {path}: not a gait file (no fixed_point; write one with amble optimize-gait --out)")
    names = system.state_names(system.mode_names[0])
    if data.get("state_names") != names:
        raise UsageError(f"--gait {path}: its states {data.get('state_names')} are not those of {system.name!r} "
                         f"({names})")
    x0 = data["fixed_point"]
    params = {**(data.get("parameters") or {}), **((data.get("bezier") or {}).get("params") or {})}
    values = [*x0, *params.values()]
    if not all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in values):
        raise UsageError(f"--gait {path}: its fixed point and parameters must be finite numbers")
    known = system.parameters
    return [float(v) for v in x0], {k: float(v) for k, v in params.items() if k in known}
