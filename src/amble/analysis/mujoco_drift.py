"""How far MuJoCo's run of a gait drifts from amble's: amble's reference run per step
(``_Reference``), each step of both compared (:class:`StepDrift`) and the outcome of a replay
(:class:`MujocoReplay`).

Apart from :mod:`amble.analysis.mujoco_replay`, which walks the robot in MuJoCo: these hold and
measure the numbers a replay reports, with nothing of MuJoCo in them.

Units: times in s, lengths in m, angles in rad, inputs in N·m.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .mujoco_biped import COORDINATES

__all__ = ["MujocoReplay", "StepDrift"]


def _number(v: float) -> float | None:
    return float(v) if np.isfinite(v) else None


@dataclass
class StepDrift:
    """One step of both runs: MuJoCo's and amble's step time (s) and step length (m, foot to
    foot at the footfall), the RMS difference of the five angles over the step (rad, at equal
    time since the step began, over the shorter of the two steps), MuJoCo's stance foot: how
    far it slid along the ground (m) and how deep it sank at most (m), and — for a law of virtual
    constraints — the largest output error ``|y|`` over the step in MuJoCo (rad; amble's gait
    keeps ``y = 0``: it measures how far the soft footfall throws the robot off the zero
    dynamics), NaN without them."""

    step: int
    step_time: float
    amble_step_time: float
    step_length: float
    amble_step_length: float
    angle_rms: float
    stance_slip: float
    penetration: float
    max_output: float

    def to_json(self) -> dict[str, Any]:
        """The fields as JSON numbers (NaN, where amble's run has no such step, as null)."""
        return {k: (int(v) if k == "step" else _number(v)) for k, v in self.__dict__.items()}


@dataclass
class MujocoReplay:
    """The outcome of :func:`replay_in_mujoco`: ``status`` ``completed`` (all steps walked) or
    ``fell`` (hip below half its height at the start, the torso beyond horizontal, or no footfall
    in three amble step times),
    the steps walked, their drift from amble's run, the largest input the law asked for (N·m;
    MuJoCo clips it to the declared limits), how long any input was clipped in all (s; the law
    meets each soft footfall with the velocities before the impact, for a few ms), the time
    walked (s) and the MJCF."""

    status: str
    steps: int
    drift: list[StepDrift]
    max_input: float
    saturated_time: float
    time: float
    mjcf: str = field(repr=False)

    def summary(self) -> dict[str, float]:
        """The largest drift over the steps: ``|Δ step time|`` (s), ``|Δ step length|`` (m), angle
        RMS (rad), stance-foot slip and penetration (m), output error ``|y|`` (rad)."""

        def worst(values: Any) -> float:  # NaN where amble's run has no such step
            return max((v for v in values if np.isfinite(v)), default=float("nan"))

        d = self.drift
        if not d:
            return {}
        return {"max_step_time_error": worst(abs(s.step_time - s.amble_step_time) for s in d),
                "max_step_length_error": worst(abs(s.step_length - s.amble_step_length) for s in d),
                "max_angle_rms": worst(s.angle_rms for s in d),
                "max_stance_slip": worst(s.stance_slip for s in d),
                "max_output": worst(s.max_output for s in d),
                "max_penetration": worst(s.penetration for s in d)}

    def to_json(self) -> dict[str, Any]:
        return {"status": self.status, "steps": self.steps, "time": self.time, "max_input": self.max_input,
                "saturated_time": self.saturated_time, "drift": {k: _number(v) for k, v in self.summary().items()},
                "per_step": [s.to_json() for s in self.drift]}


class _Reference:
    """amble's own run from the same state: per step its start time, step time, step length
    (swing foot less stance foot at the footfall, m) and its sampled angles."""

    def __init__(self, system: Any, x0: np.ndarray, values: Mapping[str, float], steps: int, dt: float) -> None:
        from ..simulation.simulate import simulate

        tr = self.tr = simulate(system, x0, params=dict(values), steps=steps, sample_dt=dt)
        events = tr.step_events
        self.starts = np.array([0.0] + [e.t for e in events])
        self.times = np.diff(self.starts)
        names = tr.kernels.meta["points"]
        pre = np.array([e.x_pre for e in events]).reshape(len(events), len(x0))
        pos, _ = tr.kernels.kinematics_rows(self.starts[1:], np.zeros(len(events), dtype=np.int64), pre, tr.params)
        self.lengths = pos[:, names.index("swing_foot"), 0] - pos[:, names.index("stance_foot"), 0]

    def mean_step_time(self) -> float:
        return float(np.mean(self.times)) if len(self.times) else 1.0

    def step(self, k: int) -> tuple[float, float]:
        """Step ``k``'s time (s) and length (m); NaN after amble's run ended."""
        if k >= len(self.times):
            return float("nan"), float("nan")
        return float(self.times[k]), float(self.lengths[k])

    def angle_rms(self, k: int, t: np.ndarray, q: np.ndarray) -> float:
        """RMS difference (rad) of angles ``q`` sampled at ``t`` since step ``k`` began from amble's
        at the same times, over the shorter of the two steps."""
        if k >= len(self.times):
            return float("nan")
        tr, t0, t1 = self.tr, self.starts[k], self.starts[k + 1]
        # from the post-impact row at t0 to the pre-impact row at t1 (events give a row on both sides)
        i0 = int(np.searchsorted(tr.t, t0, side="right")) - 1
        i1 = int(np.searchsorted(tr.t, t1, side="left"))
        ta, qa = tr.t[i0 : i1 + 1] - t0, tr.x[i0 : i1 + 1, : len(COORDINATES)]
        keep = t <= min(ta[-1], t[-1])
        qi = np.column_stack([np.interp(t[keep], ta, qa[:, j]) for j in range(qa.shape[1])])
        return float(np.sqrt(np.mean((q[keep] - qi) ** 2)))
