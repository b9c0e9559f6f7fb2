"""amble: concise equation-based modeling of hybrid mechanical systems — walking robots first.

Write coordinates, positions, masses and energies; amble derives the equations of motion and
impact maps, compiles them, simulates with exact events, and finds limit cycles.
"""

__version__ = "0.1.0"

from .equations import Equations, derive
from .errors import (
    AmbleError,
    CompileError,
    ConvergenceError,
    ModelError,
    ParameterError,
    SimulationError,
    StateError,
)
from .hybrid import Explicit, Guard, HybridSystem, Impact, Lock
from .model import R3, Model, R, t, vector
from .simulate import Options, simulate
from .trajectory import Event, Trajectory
from .walker import distance_along_slope, heel_strike, height_above_slope, joint_lock, walker

__all__ = [
    "AmbleError", "CompileError", "ConvergenceError", "Equations", "Event", "Explicit", "Guard",
    "HybridSystem", "Impact", "Lock", "Model", "ModelError", "Options", "ParameterError", "R", "R3",
    "SimulationError", "StateError", "Trajectory", "derive", "distance_along_slope", "heel_strike",
    "height_above_slope", "joint_lock", "simulate", "t", "vector", "walker",
]
