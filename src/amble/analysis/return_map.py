"""The k-step Poincaré return map on the post-impact section (:class:`ReturnMap`), its exact
derivatives and its Jacobian in a chart of the section.

The section of a walker is the set of states just after a footfall. It is a manifold: the new
swing foot is on the ground, and after a mode change (knee locked → unlocked) more coordinates
are tied together. Its tangent space is the image, under the derivative of the reset, of the
tangent space of the guard surface just before impact. We pick the state coordinates that
chart it best (pivoted QR) and drop the dependent ones; the return map in those reduced
coordinates has a non-singular ``A − I`` at a hyperbolic fixed point, and the eigenvalues of
``A`` are the nontrivial Floquet multipliers.

Apart from :mod:`amble.analysis.poincare`, which finds fixed points with it: continuation,
sweeps, basins and robustness evaluate the map and its derivatives without a search.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

import numpy as np

from ..backend.kernels import compiled
from ..backend.library import Kernels
from ..errors import ModelError, SimulationError, StateError
from ..simulation.engine import Options, Sensitivity, run
from ..simulation.simulate import parameter_vector
from .defaults import FIXED_POINT_TOL
from .mode_cycle import footfall_cycle, section_period
from .section import Section
from .section import chart as _chart

if TYPE_CHECKING:
    from ..modelling.hybrid import HybridSystem

__all__ = ["CHART_GROWTH", "MAX_PERIOD", "ReturnMap"]

#: Longest period a k-step return map is built for.
MAX_PERIOD = 64
#: The kept chart coordinates of a section are picked again when the largest entry of ``E`` (the
#: state increment per unit chart increment) grows past this multiple of its size where they were
#: picked: they still chart the section, but worse than the pivoting would choose.
CHART_GROWTH = 4.0


class ReturnMap:
    """The k-step post-impact return map of a walker at fixed parameters.

    ``__call__(x)`` maps a post-impact state to the post-impact state ``k`` footfalls later and
    returns it with the elapsed time; a run that does not complete its steps raises
    :class:`SimulationError` with the outcome.

    ``period`` (k) counts footfalls. By default it is the length of the system's footfall cycle
    from ``mode`` (:func:`amble.analysis.mode_cycle.footfall_cycle`): 1 for a one-mode walker, 2
    for a walker whose stance feet are modes (left → right → left); a period that is not a
    multiple of that length raises :class:`StateError`, since the state it maps to lies in
    another mode.
    """

    def __init__(self, system: HybridSystem, params: Mapping[str, float] | None = None, *, period: int | None = None,
                 rtol: float = FIXED_POINT_TOL, atol: float = FIXED_POINT_TOL, mode: str | None = None) -> None:
        # footfalls until the system is back in the section's mode: the default period, and every
        # period a multiple of it (checked here, before anything is compiled or run)
        cycle = footfall_cycle(system, mode)
        period = section_period(system, period, mode)
        if period < 1:
            raise StateError(f"period must be at least 1, got {period}")
        if period > MAX_PERIOD:
            raise StateError(f"period must be at most {MAX_PERIOD}, got {period}")
        if not any(tr.step for tr in system.transitions):
            raise ModelError(f"system {system.name!r} has no step transition: a return map (fixed point, "
                             f"period-k orbit) needs a transition declared with step=True")
        self.system = system
        self.k: Kernels = compiled(system, derivatives=True)  # exact Jacobians, the section's chart
        self.p = parameter_vector(self.k, params, system)
        self.period = period
        #: the modes of the post-impact states of successive footfalls, this map's mode first
        #: (:func:`amble.analysis.mode_cycle.footfall_cycle`), or None when they are not one cycle
        self.cycle = cycle
        self.mode = mode or self.k.meta["modes"][0]
        self.mi = self.k.mode_index(self.mode)
        mst = system.max_step_time
        self.opts = Options(rtol=rtol, atol=atol, max_step_time=mst)
        self.n = self.k.meta["nx"][self.mi]
        #: the section's chart coordinates per (parameters, footfall transition), see _chart
        self._charts: dict[tuple[bytes, int], tuple[np.ndarray, float]] = {}

    def __call__(self, x: np.ndarray) -> tuple[np.ndarray, float]:
        r = run(self.k, self.p, self.mi, np.asarray(x, float), steps=self.period, opts=self.opts)
        if not r.completed:
            raise SimulationError(f"return map: the run did not complete {self.period} step(s) ({r.status})")
        if r.mode != self.mi:
            raise SimulationError("return map: the walker did not come back to the section's mode")
        return r.x, r.t

    def derivatives(self, x: np.ndarray, params: bool = False) -> tuple[np.ndarray, float, Sensitivity]:
        """``P(x)``, the elapsed time and the exact derivatives of both with respect to ``x`` and,
        with ``params``, the parameters (else ``dx_dp`` and ``dt_dp`` have no columns): one
        compiled run with the variational equations. Parameter columns are asked for only where
        they are used, since the parameters enter most of a model's expressions (they cost a
        kneed biped's run as much again as the state columns)."""
        Px, t, s, _ = self._sensitivity_run(x, params, impact=False)
        return Px, t, s

    def _sensitivity_run(self, x: np.ndarray, params: bool, impact: bool
                         ) -> tuple[np.ndarray, float, Sensitivity, tuple[int, float, np.ndarray] | None]:
        """:meth:`derivatives` and, with ``impact``, the last footfall of the same run (as
        :meth:`last_impact`): its events are recorded, not its samples."""
        r = run(self.k, self.p, self.mi, np.asarray(x, float), steps=self.period, opts=self.opts,
                sensitivities=True if params else "state", record=impact, events_only=impact)
        if not r.completed:
            raise SimulationError(f"return map: the run did not complete {self.period} step(s) ({r.status})")
        if r.mode != self.mi:
            raise SimulationError("return map: the walker did not come back to the section's mode")
        s = r.sensitivity
        assert s is not None
        if not (np.all(np.isfinite(s.dx_dx0)) and np.all(np.isfinite(s.dx_dp))):
            raise SimulationError("return map: an event grazes its guard (ġ = 0), the map is not differentiable here")
        return r.x, r.t, s, self._last_step(r.recorded) if impact else None

    def section_jacobian(self, x: np.ndarray, method: str = "exact") -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The map's Jacobian ``A`` in the section chart at ``x`` (its eigenvalues at a fixed
        point are the nontrivial multipliers), the chart's state coordinates ``S`` and ``E``,
        the map from chart increments to state increments. ``method``: ``"exact"`` or ``"fd"``.

        ``"exact"`` is one compiled run: the variational equations of the state columns, and the
        last footfall recorded in the same run, from which the section's tangent space is found.
        The chart's coordinates ``S`` are kept per parameters and footfall transition (the
        pivoting that picks them is most of the cost of a small model's chart); ``E`` is worked
        out at every state, and the coordinates are picked again when the kept ones chart the
        section here much worse than where they were picked."""
        if method != "exact":
            S, E = self._chart(Section.of(self, x))
            return _jacobian(self, x, E, S, method), S, E
        return self.map_and_section_jacobian(x)[2:]

    def map_and_section_jacobian(self, x: np.ndarray
                                 ) -> tuple[np.ndarray, float, np.ndarray, np.ndarray, np.ndarray]:
        """``P(x)``, the elapsed time and :meth:`section_jacobian` ``(A, S, E)`` (exact) from the
        same compiled run: the variational equations do not change the run's steps, so ``P(x)``
        is the plain map's to the bit and a Newton step needs no run of its own to evaluate it."""
        Px, t, s, impact = self._sensitivity_run(x, False, impact=True)
        assert impact is not None
        S, E = self._chart(Section(self.k, self.p, *impact))
        return Px, t, (s.dx_dx0 @ E)[S, :], S, E

    def _chart(self, sec: Section) -> tuple[np.ndarray, np.ndarray]:
        """``(S, E)`` of the section ``sec``: :func:`amble.analysis.section.chart` of its tangent
        space, ``S`` kept per (parameters, transition) as :meth:`section_jacobian` says."""
        key = (self.p.tobytes(), sec.tr)
        kept = self._charts.get(key)
        if kept is not None:
            E = sec.increments(kept[0])
            # (a NaN or infinite entry fails the comparison too)
            if E is not None and float(np.max(np.abs(E))) <= CHART_GROWTH * kept[1]:
                return kept[0], E
        S, E = _chart(sec.tangent())
        if len(self._charts) >= 16:  # a continuation moves the parameters at every point
            self._charts.clear()
        self._charts[key] = (S, float(np.max(np.abs(E))))
        return S, E

    def last_impact(self, x: np.ndarray) -> tuple[int, float, np.ndarray]:
        """(transition index, time, pre-event state) of the last footfall when mapping ``x``."""
        r = run(self.k, self.p, self.mi, np.asarray(x, float), steps=self.period, opts=self.opts, record=True,
                events_only=True)
        if not r.completed:
            raise SimulationError(f"return map: the run did not complete {self.period} step(s) ({r.status})")
        return self._last_step(r.recorded)

    def _last_step(self, rec: dict[str, Any]) -> tuple[int, float, np.ndarray]:
        """(transition index, time, pre-event state) of the last step transition recorded."""
        trs = self.k.meta["transitions"]
        i = [j for j, tr in enumerate(rec["etr"].tolist()) if trs[tr]["step"]][-1]
        tr = int(rec["etr"][i])
        nsrc = self.k.meta["nx"][self.k.mode_index(trs[tr]["source"])]
        return tr, float(rec["et"][i]), rec["epre"][i][:nsrc].copy()

    def section_basis(self, x: np.ndarray) -> np.ndarray:
        """Orthonormal basis (n × d) of the section's tangent space near the image of ``x``."""
        return Section.of(self, x).tangent()


def _jacobian(P: ReturnMap, x: np.ndarray, E: np.ndarray, S: np.ndarray, method: str = "exact",
              h: float = 1e-5) -> np.ndarray:
    """The return map's Jacobian in chart coordinates: increments ``E ξ`` of the state, the
    chart coordinates ``S`` of the image."""
    if method == "exact":
        return (P.derivatives(x, params=False)[2].dx_dx0 @ E)[S, :]
    cols = []
    for j in range(E.shape[1]):
        xp, _ = P(x + h * E[:, j])
        xm, _ = P(x - h * E[:, j])
        cols.append((xp - xm)[S] / (2 * h))
    return np.array(cols).T
