"""Parameter sweeps on Dask: one entry point, :func:`sweep`, with a kind.

``sweep(system, kind, over, ...)`` computes, over the grid ``over`` (name → values), one of

- ``"fixed-point"`` — the period-1 gait at every value of one parameter (a branch), each point
  warm-started from the one before, or on the grid of two (a map) (:mod:`.fixed_points`);
- ``"continuation"`` — the branch by pseudo-arclength from ``start`` to ``stop`` with its folds,
  flips and period-doubled branches, ``over = {param: (start, stop)}`` (:mod:`.continuation_sweep`);
- ``"bifurcation"`` — the return map's iterates after a transient, along one parameter
  (:mod:`.bifurcation`);
- ``"basin"`` — the basin of attraction over two post-impact coordinates (:mod:`.basin`).

The options every kind shares are the keywords of :func:`sweep` (the result file, where the tasks
run, the budget, the tolerances), gathered into one :class:`~.sweep_runner.RunOptions`; each kind
adds its own (its implementation's keyword-only arguments, listed in :data:`KINDS`). Where the
period-1 gait period-doubles is :func:`~.doubling.period_doubling` of any of these results.

Work is cut into chunks (consecutive parameter values, one row of a map or a basin), each one
Dask task; chunks depend only on the grid, so a result does not depend on how many processes
computed it. Every row is durable in the result file as soon as its chunk finishes; a sweep
interrupted at any moment (even killed) and run again with the same file computes only the
missing points, and its final file equals that of an uninterrupted run byte for byte. A point
whose computation fails is recorded with ``status`` ``failed`` and its reason, and the sweep
goes on. The other modules: :mod:`.store` (the resumable result file, :class:`SweepResult`),
:mod:`.runner` (Dask clients, :func:`open_client`), :mod:`.sweep_runner` (the one pipeline).

Units: angles in rad, angular velocities in rad/s, times in s; parameters in the model's units.
"""

from __future__ import annotations

import inspect
import os
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from ..errors import StateError
from .basin import BASIN_LABELS, BasinResult, basin, basin_kind
from .bifurcation import bifurcation, bifurcation_kind, first_period_doubling_iterates, poincare_iterates
from .continuation_sweep import continuation_kind, sweep_continuation
from .defaults import BASIN_TOL, BIFURCATION_TOL, FIXED_POINT_TOL
from .doubling import period_doubling
from .fixed_points import fixed_point_kind, sweep_fixed_points, sweep_fixed_points_2d
from .runner import open_client, sweep_values
from .store import ResultStore, SweepResult
from .sweep_runner import RunOptions, deprecated

if TYPE_CHECKING:  # a compiled system (amble.backend.compiled) serves too, without SymPy
    from ..modelling.hybrid import HybridSystem


@dataclass(frozen=True)
class Kind:
    """A sweep kind: its implementation ``run(system, over, params, run_options, **options)``, the
    default of ``rtol`` = ``atol``, how many entries ``over`` takes, whether they name state
    coordinates (else parameters) and whether it runs sequentially in this process (no scheduler,
    workers or budget)."""

    run: Callable[..., Any]
    tol: float
    axes: tuple[int, ...]
    coordinates: bool = False
    sequential: bool = False

    def options(self) -> dict[str, Any]:
        """The kind's own keywords and their defaults (its implementation's keyword-only arguments)."""
        return {n: p.default for n, p in inspect.signature(self.run).parameters.items()
                if p.kind is inspect.Parameter.KEYWORD_ONLY}


#: kind name (as ``amble sweep --kind``) → its implementation and defaults
KINDS: dict[str, Kind] = {
    "fixed-point": Kind(fixed_point_kind, FIXED_POINT_TOL, (1, 2)),
    "continuation": Kind(continuation_kind, FIXED_POINT_TOL, (1,), sequential=True),
    "bifurcation": Kind(bifurcation_kind, BIFURCATION_TOL, (1,)),
    "basin": Kind(basin_kind, BASIN_TOL, (2,), coordinates=True),
}

#: an old keyword → its new name (accepted for one release, with a DeprecationWarning)
RENAMED = {"continuation": "warm_start"}


def _options(name: str, kind: Kind, options: dict[str, Any]) -> dict[str, Any]:
    """The kind's own options, old names renamed; an option the kind does not take is refused."""
    own = kind.options()
    for old, new in RENAMED.items():
        if old in options and new in own:
            deprecated(f"the keyword {old}=", f"{new}=", stacklevel=4)
            if new in options:
                raise StateError(f"give {new}= only (its old name {old}= too is ambiguous)")
            options[new] = options.pop(old)
    wrong = sorted(set(options) - set(own))
    if wrong:
        raise StateError(f"sweep kind {name!r} takes no option {', '.join(wrong)}; its own options: "
                         f"{', '.join(own) or 'none'}")
    return options


def sweep(
    system: HybridSystem,
    kind: str,
    over: Mapping[str, Sequence[float]],
    *,
    params: Mapping[str, float] | None = None,
    out: str | os.PathLike | None = None,
    scheduler: Any = None,
    workers: int | None = None,
    progress: bool = True,
    max_points: int | None = None,
    rtol: float | None = None,
    atol: float | None = None,
    **options: Any,
) -> SweepResult | BasinResult:
    """A sweep of ``system`` of the given ``kind`` over the grid ``over`` (name → values).

    ``kind`` and ``over``:

    - ``"fixed-point"``: ``{param: values}`` — the branch of period-1 fixed points with step time
      and multipliers; ``{a: values_a, b: values_b}`` — the map over the grid of two parameters;
      options ``warm_start`` (default ``True``: each point's Newton guess is the fixed point
      before it in its chunk), ``chunk`` (values per task of a branch, default 32), ``tol``;
    - ``"continuation"``: ``{param: (start, stop)}`` — pseudo-arclength from ``start`` to
      ``stop`` with the folds and flips located and up to ``levels`` − 1 period-doubled branches;
      options ``steps`` (default 50: the parameter moves at most |stop − start| / steps per
      step), ``levels`` (3), ``guess``, ``tol``; sequential, in this process;
    - ``"bifurcation"``: ``{param: values}`` — the iterates of one ``coordinate`` after
      ``transient`` steps, ``keep`` of them; options ``coordinate``, ``transient`` (300),
      ``keep`` (64), ``chunk`` (16), ``period_tol`` (1e-6);
    - ``"basin"``: ``{coordinate_a: values_a, coordinate_b: values_b}`` — which post-impact states
      walk into the gait (:class:`BasinResult`); options ``steps`` (footfalls per cell, default
      60), ``check_every``, ``tol`` (1e-4), ``rows_per_task``, ``threads``, ``base_state``,
      ``to_state``.

    Every kind: ``params`` the other parameters; ``out`` the result file (.csv/.parquet), resumed
    if it exists; ``scheduler`` (``None``: local worker processes; ``"synchronous"``: this
    process; else a Dask scheduler's address) and ``workers``; ``progress`` a progress bar;
    ``max_points`` compute at most this many missing points in this call; ``rtol``, ``atol`` the
    integrator tolerances (default: the kind's, :data:`KINDS`, from :mod:`.defaults`). The rows
    and columns of each kind are those its implementation documents (:func:`fixed_point_kind`,
    :func:`continuation_kind`, :func:`bifurcation_kind`, :func:`basin_kind`).
    """
    spec = KINDS.get(kind)
    if spec is None:
        raise StateError(f"unknown sweep kind {kind!r}; known: {', '.join(KINDS)}")
    if not isinstance(over, Mapping) or len(over) not in spec.axes:
        want = " or ".join(map(str, spec.axes))
        raise StateError(f"sweep kind {kind!r} takes {want} entries in over (name → values), got "
                         f"{len(over) if isinstance(over, Mapping) else type(over).__name__}")
    if spec.sequential and (scheduler, workers, max_points) != (None, None, None):
        raise StateError(f"sweep kind {kind!r} runs in this process, in one piece: scheduler, workers and "
                         f"max_points do not apply")
    grid = {str(nm): sweep_values(v, str(nm), None if spec.coordinates else system) for nm, v in over.items()}
    run = RunOptions(out, scheduler, workers, progress, max_points, spec.tol if rtol is None else rtol,
                     spec.tol if atol is None else atol)
    return spec.run(system, grid, params, run, **_options(kind, spec, dict(options)))


__all__ = ["BASIN_LABELS", "KINDS", "BasinResult", "Kind", "ResultStore", "RunOptions", "SweepResult", "basin",
           "bifurcation", "first_period_doubling_iterates", "open_client", "period_doubling", "poincare_iterates",
           "sweep", "sweep_continuation", "sweep_fixed_points", "sweep_fixed_points_2d"]
