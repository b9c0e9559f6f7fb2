"""amble: concise equation-based modeling of hybrid mechanical systems — walking robots first.

Write coordinates, positions, masses and energies; amble derives the equations of motion and
impact maps, compiles them, simulates with exact events, and finds limit cycles.

The names below are loaded on first use (:pep:`562`): ``import amble`` alone costs no SymPy,
SciPy or Matplotlib, so a command that finds its compiled model in the cache starts fast.
``from amble import Model`` works as usual.
"""

from __future__ import annotations

import importlib as _importlib
import sys as _sys
from typing import TYPE_CHECKING, Any

from .version import __version__  # noqa: F401  (amble.__version__)

#: public name → module (relative to this package) that defines it
_WHERE: dict[str, str] = {
    **dict.fromkeys(("Equations", "derive"), ".derivation.equations"),
    **dict.fromkeys(("contact_force", "holonomic_forces", "unilateral_contact"), ".derivation.contact"),
    **dict.fromkeys(("AmbleError", "CompileError", "ConvergenceError", "ExpressionError", "ModelError", "OutputError",
                     "ParameterError",
                     "SchedulerError", "SimulationError", "StateError"), ".errors"),
    **dict.fromkeys(("RoundFoot", "compliant_contact", "distance_along_slope", "heel_strike", "height_above_slope",
                     "rolling_centre", "round_foot"), ".modelling.contact"),
    **dict.fromkeys(("NONNEGATIVE", "POSITIVE", "Domain", "interval"), ".modelling.domain"),
    **dict.fromkeys(("R3", "R", "Rx", "Ry", "Rz", "t", "vector"), ".modelling.geometry"),
    **dict.fromkeys(("Explicit", "Guard", "HybridSystem", "Impact", "Lock"), ".modelling.hybrid"),
    "Model": ".modelling.model",
    **dict.fromkeys(("LimitGuard", "limit_of"), ".modelling.limits"),
    "sample_and_hold": ".modelling.sampled",
    "parse": ".modelling.text",
    **dict.fromkeys(("base_relabel", "stance_feet_walker"), ".modelling.stance_feet"),
    "Joint": ".modelling.bodies",
    **dict.fromkeys(("Walker", "joint_lock", "walker"), ".modelling.walker"),
    **dict.fromkeys(("Options", "run", "walk_many"), ".simulation.engine"),
    "parameter_vector": ".simulation.simulate",
    "compiled": ".backend.kernels",
    **dict.fromkeys(("ReturnMap", "find_fixed_point"), ".analysis.poincare"),
    "Section": ".analysis.section",
    "linearize": ".analysis.linearize",
    # sweeps: one entry point with a kind, and one period-doubling detector; the old names are
    # deprecated aliases (each warns, naming its replacement)
    "sweep": ".analysis.sweep",
    "period_doubling": ".analysis.doubling",
    "bifurcations": ".analysis.branch_bifurcations",
    "map_crossings": ".analysis.map_bifurcations",
    **dict.fromkeys(("sweep_fixed_points", "sweep_fixed_points_2d"), ".analysis.fixed_points"),
    **dict.fromkeys(("bifurcation", "poincare_iterates"), ".analysis.bifurcation"),
    **dict.fromkeys(("cascade", "continue_branch", "switch_at_flip"), ".analysis.continuation"),
    "locate_bifurcation": ".analysis.bifurcation_location",
    "basin": ".analysis.basin",
    "find_gaits": ".analysis.gaits",
    "period_doublings": ".analysis.doublings",
    **dict.fromkeys(("hybrid_invariance_error", "invariant_parameters", "restricted_map"), ".analysis.hzd"),
    "optimize_gait": ".analysis.gait_optimisation",
    "closed_loop_stability": ".analysis.gait_stability",
    **dict.fromkeys(("FirstPassage", "Terrain", "mfpt"), ".analysis.mfpt"),
    **dict.fromkeys(("MarkovPassage", "markov_mfpt"), ".analysis.markov"),
    **dict.fromkeys(("GaitSensitivity", "gait_sensitivity"), ".analysis.robustness"),
    **dict.fromkeys(("BasinMeasures", "basin_measures"), ".analysis.basin_measures"),
    "MujocoReplay": ".analysis.mujoco_drift",
    "planar_biped_mjcf": ".analysis.mujoco_biped",
    "replay_in_mujoco": ".analysis.mujoco_replay",
    "gait_gradients": ".analysis.gait_gradients",
    "check_gait": ".analysis.gait_check",
    "simulate": ".simulation.simulate",
    **dict.fromkeys(("Event", "Trajectory"), ".simulation.trajectory"),
    **dict.fromkeys(("animate", "plot_limit_cycle", "plot_trajectory"), ".viz"),
    **dict.fromkeys(("plot_metastable", "plot_mfpt_against"), ".viz.metastable"),
    "plot_parameter_map": ".viz.sweep_plots",
}

__all__ = sorted(_WHERE, key=lambda n: (not n.isupper(), n))


if "IPython" in _sys.modules:  # in a notebook, ``import amble`` registers the rich display, as before
    _importlib.import_module(".viz.notebook", __name__).register()


#: old public name → its new name (each kept, with a warning, for one release)
_RENAMED: dict[str, str] = {"build": "compiled"}


def __getattr__(name: str) -> Any:
    if name in _RENAMED:
        import warnings

        new = _RENAMED[name]
        warnings.warn(f"amble.{name} is now amble.{new}", DeprecationWarning, stacklevel=2)
        return __getattr__(new)
    where = _WHERE.get(name)
    if where is None:
        raise AttributeError(f"module 'amble' has no attribute {name!r}")
    value = getattr(_importlib.import_module(where, __name__), name)
    globals()[name] = value  # once loaded, an ordinary attribute
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_WHERE))


if TYPE_CHECKING:  # what static tools (type checkers, import graphs) see
    from .derivation.contact import contact_force, holonomic_forces, unilateral_contact  # noqa: F401
    from .derivation.equations import Equations, derive  # noqa: F401
    from .errors import (  # noqa: F401
        AmbleError,
        CompileError,
        ConvergenceError,
        ModelError,
        OutputError,
        ParameterError,
        SchedulerError,
        SimulationError,
        StateError,
    )
    from .modelling.bodies import Joint  # noqa: F401
    from .modelling.contact import (  # noqa: F401
        RoundFoot,
        compliant_contact,
        distance_along_slope,
        heel_strike,
        height_above_slope,
        rolling_centre,
        round_foot,
    )
    from .modelling.domain import NONNEGATIVE, POSITIVE, Domain, interval  # noqa: F401
    from .modelling.geometry import R3, R, Rx, Ry, Rz, t, vector  # noqa: F401
    from .modelling.hybrid import Explicit, Guard, HybridSystem, Impact, Lock  # noqa: F401
    from .modelling.limits import LimitGuard, limit_of  # noqa: F401
    from .modelling.model import Model  # noqa: F401
    from .modelling.sampled import sample_and_hold  # noqa: F401
    from .modelling.stance_feet import base_relabel, stance_feet_walker  # noqa: F401
    from .modelling.walker import Walker, joint_lock, walker  # noqa: F401
    from .simulation.engine import Options  # noqa: F401
    from .simulation.simulate import simulate  # noqa: F401
    from .simulation.trajectory import Event, Trajectory  # noqa: F401
    from .viz import animate, plot_limit_cycle, plot_trajectory  # noqa: F401
