"""A periodic gait found as a fixed point of the return map (:class:`LimitCycle`): the fixed
point, its step time, Floquet multipliers and section chart, its orbit, and its simulation.

Apart from :mod:`amble.analysis.poincare`, which finds it: plots, robustness and basin measures
read a limit cycle without searching for one.

Units: states in the model's units, times in s.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..simulation.simulate import simulate

__all__ = ["LimitCycle"]


@dataclass
class LimitCycle:
    """A periodic gait: fixed point of the (k-step) return map and its stability."""

    system: str
    mode: str
    state_names: list[str]
    fixed_point: np.ndarray
    step_time: float
    multipliers: np.ndarray
    section_coordinates: list[str]
    residual: float
    iterations: int
    period: int
    parameters: dict[str, float]
    jacobian: np.ndarray = field(repr=False)
    hybrid_system: Any = field(default=None, repr=False)
    #: the k post-impact states of the orbit (the fixed point first) and the k step times (s)
    orbit: np.ndarray | None = field(default=None, repr=False)
    step_times: list[float] = field(default_factory=list)
    #: the period asked for, when the orbit found has a lower one (a period-k search converged to
    #: a period-d orbit repeated k/d times)
    requested_period: int | None = None
    #: how the gait was found: ``"guess"`` (Newton from the guess given), ``"walk"`` (Newton from
    #: a walk at these parameters), ``"continuation"`` (the model's gait followed from its default
    #: parameters) or ``"collocation"`` (Newton from a periodic step solved by collocation, when
    #: the others failed: :mod:`amble.analysis.collocation_guess`)
    found_by: str = "guess"
    #: for a gait found by collocation, in one line, why the other searches failed — where the
    #: model's gait's branch folds, this gait lies on another branch
    search_note: str = ""

    def trajectory(self, steps: int | None = None) -> Any:
        """Simulate the gait from the fixed point (default: two periods), samples every 5 ms."""
        return simulate(self.hybrid_system, self.fixed_point, params=self.parameters,
                        steps=steps or 2 * self.period, sample_dt=0.005)

    @property
    def stable(self) -> bool:
        """All nontrivial multipliers strictly inside the unit circle."""
        return bool(np.max(np.abs(self.multipliers)) < 1.0)

    def to_json(self) -> dict[str, Any]:
        return {
            "system": self.system,
            "mode": self.mode,
            "state_names": self.state_names,
            "fixed_point": self.fixed_point.tolist(),
            "step_time": self.step_time,
            "multipliers": [[float(m.real), float(m.imag)] for m in self.multipliers],
            "multiplier_moduli": [float(abs(m)) for m in self.multipliers],
            "stable": self.stable,
            "section_coordinates": self.section_coordinates,
            "residual": self.residual,
            "iterations": self.iterations,
            "period": self.period,
            "requested_period": self.requested_period or self.period,
            "orbit": self.orbit.tolist() if self.orbit is not None else [self.fixed_point.tolist()],
            "step_times": self.step_times or [self.step_time],
            "parameters": self.parameters,
            "found_by": self.found_by,
            "search_note": self.search_note,
        }
