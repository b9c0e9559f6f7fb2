"""The options of :func:`~amble.analysis.gait_optimisation.optimize_gait` checked before any work
(a :class:`~amble.errors.ParameterError` for one out of its domain), the parameter values of a
step, and the user's expressions (an objective, a phase) read in the model's names."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import sympy as sp

from ..errors import ParameterError
from ..modelling.hybrid import HybridSystem
from ..modelling.text import expr_of


def _check_options(system: HybridSystem, speed: float | None, step_length: float | None, mu: float | None,
                   step_time: float | None, clearance: float | None, nodes: Any, hzd: bool | None,
                   bezier_degree: int | None, max_iter: Any, steps: Any) -> tuple[bool, int]:
    """:class:`ParameterError` for an option out of its domain, before any work; returns ``hzd``
    and ``bezier_degree`` with their defaults filled in (the model's virtual constraints, if any)."""
    if speed is not None and step_length is not None:
        raise ParameterError("give speed or step_length, not both")
    for name, v in (("speed", speed), ("step_length", step_length), ("mu", mu), ("step_time", step_time)):
        if v is not None and not (np.isfinite(v) and v > 0):
            raise ParameterError(f"{name} must be a finite number > 0, got {v!r}")
    if clearance is not None and not (np.isfinite(clearance) and clearance >= 0):
        raise ParameterError(f"clearance must be a finite number ≥ 0, got {clearance!r}")
    sizes = [nodes] if isinstance(nodes, int) else list(nodes)
    if not sizes or not all(isinstance(k, int) and 2 <= k <= 2000 for k in sizes):
        raise ParameterError(f"nodes must be an integer in [2, 2000] (or a list of them), got {nodes!r}")
    vc = getattr(system.modes[system.mode_names[0]], "virtual", None)
    if hzd is None:
        hzd = vc is not None
    if bezier_degree is None:
        bezier_degree = vc.degree if vc is not None else 5
    if not (isinstance(bezier_degree, int) and 1 <= bezier_degree <= 20):
        raise ParameterError(f"bezier_degree must be an integer in [1, 20], got {bezier_degree!r}")
    if not (isinstance(max_iter, int) and max_iter >= 1):
        raise ParameterError(f"max_iter must be an integer ≥ 1, got {max_iter!r}")
    if not (isinstance(steps, int) and 1 <= steps <= 8):
        raise ParameterError(f"steps must be an integer in [1, 8], got {steps!r}")
    return bool(hzd), bezier_degree


def _check_stability_option(max_multiplier: float | None, hzd: bool, steps: int) -> None:
    if max_multiplier is None:
        return
    if not (isinstance(max_multiplier, (int, float)) and np.isfinite(max_multiplier) and 0 < max_multiplier < 1):
        raise ParameterError(f"max_multiplier must be a number in (0, 1), got {max_multiplier!r}")
    if not hzd:
        raise ParameterError("max_multiplier bounds the restricted Poincaré map of the hybrid zero dynamics: it "
                             "needs hzd=True (virtual constraints)")


def _parameters(system: HybridSystem, params: Mapping[str, float] | None) -> dict[str, float]:
    values = dict(system.parameters)
    for k, v in (params or {}).items():
        if k not in values:
            raise ParameterError(f"unknown parameter {k!r} (parameters: {', '.join(values)})")
        if not np.isfinite(v):
            raise ParameterError(f"parameter {k!r} must be finite, got {v!r}")
        values[k] = float(v)
    system.check_parameters(values)
    return values


def _integrand(model: Any, objective: Any) -> sp.Expr:
    return _expression(model, objective, "objective", [*model.qd, *(getattr(model, "inputs", []) or [])],
                       "objectives: effort, cot, or an expression in ")


def _expression(model: Any, text: Any, what: str, extra: Sequence[sp.Symbol] = (), hint: str = "") -> sp.Expr:
    """A user expression (text or sympy) in the coordinates, parameters and ``extra`` symbols."""
    known = {str(s): s for s in [*model.q, *model.params, *extra]}
    expr = expr_of(text, known, what=what)  # text is read, never evaluated
    bad = sorted(str(s) for s in expr.free_symbols if str(s) not in known or known[str(s)] != s)
    if bad:
        raise ParameterError(f"{what} {text!s} uses {', '.join(bad)}: not among the allowed names "
                             f"({hint}{', '.join(known)})")
    return expr
