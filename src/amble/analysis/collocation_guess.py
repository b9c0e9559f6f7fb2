"""A global start for the fixed-point search: the periodic gait solved by collocation.

When neither Newton from a walk at the requested parameters nor the model's own gait followed
there by continuation (:mod:`amble.analysis.homotopy`) finds a gait,
:func:`amble.analysis.poincare.find_fixed_point` asks the gait optimiser
(:func:`amble.analysis.gait_optimisation.optimize_gait`) for a periodic step with a zero
objective: for a walker without inputs the problem is one of feasibility — the equations of
motion, the footfall, the impact and periodicity — so its solution is a passive gait, wherever
it lies, with no path from a known gait needed. Its post-impact state is then only a start:
Newton on the exact return map polishes it to the usual accuracy.

Only the system's own dynamics are solved: a system with inputs is skipped, because the
optimiser would choose those inputs (design a gait) rather than find the gait of the system as
it is. A system the optimiser does not accept (a step of several domains) or CasADi missing
(the ``optimise`` extra) also ends the search with the earlier failures.

A gait found so need not lie on the branch of the model's gait: where that branch folds, any
gait found lies on another branch, and where the continuation lost it, nothing connects the two.
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import TYPE_CHECKING, Any

import numpy as np

from ..errors import ConvergenceError, ModelError, ParameterError, SolverError, StateError
from .global_starts import register

if TYPE_CHECKING:
    from ..modelling.hybrid import HybridSystem

#: collocation intervals of the solve: a start for Newton, not the gait itself (30 intervals put
#: the compass gait's post-impact state within ~1e-4 of the map's fixed point)
NODES = 30
#: IPOPT's tolerance: loose, since Newton on the return map polishes. A passive walker's problem
#: without a pace has as many equations as unknowns (plus inequalities: contact, the footfall's
#: enabling condition), where IPOPT often ends in a failed restoration at a point that already
#: holds every constraint; a loose tolerance lets more of its solves end as solved
TOL = 1e-6
#: IPOPT iterations per solve
MAX_ITER = 300
#: the optimiser's starts, in order: the passive walk (which falls back to an interpolated stride
#: when the passive step falls), then an interpolated stride in the model's posture
STARTS = ("passive", "interpolate")


def has_inputs(system: HybridSystem) -> bool:
    """Whether any mode of ``system`` declares inputs (actuators)."""
    return any(getattr(m, "inputs", None) for m in system.modes.values())


def collocation_starts(system: HybridSystem, params: dict[str, float], period: int
                       ) -> Iterator[tuple[str, np.ndarray | None, str]]:
    """For each of the optimiser's :data:`STARTS`: its name, the post-impact state (the first
    mode's state order) of the periodic gait of ``period`` steps solved by collocation at
    ``params`` (``None`` when the solve failed) and, then, why in one line. Raises
    :class:`ConvergenceError` in one line when the method does not apply (inputs, a system the
    optimiser does not take, no CasADi)."""
    if has_inputs(system):
        raise ConvergenceError("skipped: the system has inputs, and collocation would choose them rather than "
                               "solve the system's own gait")
    from .gait_optimisation import optimize_gait

    try:
        sym = system.symbolic()
    except (ModelError, AttributeError) as e:
        raise ConvergenceError(f"skipped: no symbolic model ({e})") from None
    for start in STARTS:
        try:
            g = optimize_gait(sym, params=params, objective="0", guess=start, nodes=NODES, tol=TOL,
                              max_iter=MAX_ITER, steps=period)
        except SolverError as e:
            yield start, None, _first_line(e)
            continue
        except (ModelError, ParameterError, StateError) as e:
            # the optimiser does not take this system (several domains per step, no CasADi, ...)
            raise ConvergenceError(f"not applicable: {_first_line(e)}") from None
        yield start, np.asarray(g.fixed_point, float), ""


def _first_line(e: Any) -> str:
    return str(e).splitlines()[0] if str(e) else type(e).__name__


register("collocation", collocation_starts)


__all__ = ["MAX_ITER", "NODES", "STARTS", "TOL", "collocation_starts", "has_inputs"]
