"""amble: concise equation-based modeling of hybrid mechanical systems — walking robots first.

Write coordinates, positions, masses and energies; amble derives the equations of motion and
impact maps, compiles them, simulates with exact events, and finds limit cycles.
"""

from .derivation.equations import Equations, derive
from .derivation.resting import contact_force, unilateral_contact
from .errors import (
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
from .modelling.contact import RoundFoot, rolling_centre, round_foot
from .modelling.domain import NONNEGATIVE, POSITIVE, Domain, interval
from .modelling.geometry import R3, R, Rx, Ry, Rz, t, vector
from .modelling.hybrid import Explicit, Guard, HybridSystem, Impact, Lock
from .modelling.model import Model
from .modelling.sampled import sample_and_hold
from .modelling.stance_feet import base_relabel, stance_feet_walker
from .modelling.tree import Joint
from .modelling.walker import Walker, distance_along_slope, heel_strike, height_above_slope, joint_lock, walker
from .simulation.engine import Options
from .simulation.simulate import simulate
from .simulation.trajectory import Event, Trajectory
from .version import __version__  # noqa: F401  (amble.__version__)
from .viz import animate, plot_limit_cycle, plot_trajectory

__all__ = [
    "NONNEGATIVE", "POSITIVE", "R", "R3", "Rx", "Ry", "Rz", "AmbleError", "CompileError", "ConvergenceError",
    "Domain", "Equations",
    "Event", "Explicit", "Guard", "HybridSystem", "Impact", "Joint", "Lock", "Model", "ModelError", "Options",
    "OutputError",
    "ParameterError", "RoundFoot", "SchedulerError", "SimulationError", "StateError", "Trajectory", "Walker", "animate",
    "contact_force", "derive", "distance_along_slope", "heel_strike", "height_above_slope", "interval", "joint_lock",
    "plot_limit_cycle", "plot_trajectory", "rolling_centre", "round_foot", "sample_and_hold", "simulate",
    "base_relabel", "stance_feet_walker", "t",
    "unilateral_contact", "vector", "walker",
]
