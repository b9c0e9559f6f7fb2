"""A basin's set-up: the fixed point its cells are measured against and the section they are put on.

Both depend only on the system, its parameters and (for the section) the integrator tolerances
and the two grid coordinates, never on the grid: a map redrawn at another resolution, or another
box of the same gait, needs the same ones. They are worked out once per such inputs in a process
and kept in a small table (:class:`amble.simulation.memo.Memo`): the fixed-point search and the section's chart cost
about as much as walking a 12 × 12 map, and they run before any cell can start, on one thread.

The table is keyed by the values the search reads — the parameter vector, whether parameters
were given (the search's fallbacks differ), the system's fixed-point guess, default starts and
step-time limit — and by the identity of the system and of its compiled kernels, both checked on
every hit (a changed model compiles to other kernels). A result is stored only when it was found;
an error is raised again on the next call.

Units: those of the model's states (angles in rad, angular velocities in rad/s).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from ..backend.kernels import compiled
from ..errors import StateError
from ..simulation.memo import Memo
from .section import Section

if TYPE_CHECKING:  # a compiled system (amble.backend.compiled) serves too, without SymPy
    from ..modelling.hybrid import HybridSystem

#: (transition index, event time (s), pre-impact state, section coordinates): what a basin task
#: needs to rebuild the section from the compiled kernels (:class:`~amble.analysis.section.Section`).
SectionSpec = tuple[int, float, list[float], list[int]]


#: Fixed points and sections of recent basins in this process.
_SETUPS = Memo(16)


def _floats(v: Any) -> tuple[float, ...] | None:
    return None if v is None else tuple(float(x) for x in np.asarray(v, float).ravel())


def _system_key(system: HybridSystem) -> tuple:
    """What the fixed-point search reads from the system besides its compiled kernels."""
    starts = tuple(sorted((str(m), _floats(x)) for m, x in dict(system.default_start).items()))
    return (_floats(system.fixed_point_guess), starts, float(system.max_step_time))


def setup(system: HybridSystem, params: Mapping[str, float] | None, pvec: np.ndarray, x_names: Sequence[str],
          snames: Sequence[str], rtol: float, atol: float, *, section: bool = True
          ) -> tuple[np.ndarray, SectionSpec | None]:
    """The period-1 fixed point of :func:`amble.analysis.poincare.find_fixed_point` at ``params``
    (``pvec``: their parameter vector; a new array on every call) and, with ``section``, the
    post-impact section through its image (integrator tolerances ``rtol``, ``atol``) charted by the
    coordinates ``x_names`` first (of the state names ``snames``): :class:`StateError` when the
    two are tied on it. Each from the table when the same inputs were seen before."""
    from .poincare import find_fixed_point
    from .return_map import ReturnMap

    k = compiled(system, derivatives=True)
    owners, base = (system, k), (id(system), id(k), np.asarray(pvec, float).tobytes(), _system_key(system))
    key = ("fixed point", *base, bool(params))
    xs = _SETUPS.get(key, *owners)
    if xs is None:
        xs = np.array(find_fixed_point(system, params=params).fixed_point, float)
        xs.flags.writeable = False
        _SETUPS.put(key, xs, *owners)
    if not section:
        return xs.copy(), None
    key = ("section", *base, xs.tobytes(), tuple(x_names), float(rtol), float(atol))
    spec = _SETUPS.get(key, *owners)
    if spec is None:
        sec = Section.of(ReturnMap(system, params, rtol=rtol, atol=atol), xs)
        try:
            S = sec.coordinates(prefer=[list(snames).index(nm) for nm in x_names])
        except StateError:
            free = ", ".join(snames[i] for i in sec.coordinates())
            raise StateError(f"basin: {x_names[0]} and {x_names[1]} are tied on the section (they cannot both be "
                             f"varied); section coordinates of this model: {free}") from None
        spec = (sec.tr, sec.t, tuple(sec.pre.tolist()), tuple(S.tolist()))
        _SETUPS.put(key, spec, *owners)
    return xs.copy(), (spec[0], spec[1], list(spec[2]), list(spec[3]))


def forget() -> None:
    """Empty the table: the next basin of every system works its set-up out again (a first call's
    cost, as benchmarks measure it; or the memory back)."""
    _SETUPS.clear()


__all__ = ["SectionSpec", "forget", "setup"]
