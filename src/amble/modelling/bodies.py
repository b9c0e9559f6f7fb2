"""The parts of a rigid-body tree: a :class:`Joint` (its type, axis, origin in the parent's frame,
limits, a mimic of another coordinate), a :class:`Body` (its mass, centre of mass and inertia,
and its world-frame kinematics once added), the joint types and what a composite joint
(spherical, floating) stands for.

Apart from :mod:`amble.modelling.tree`, which adds bodies to a model and builds their kinematics:
these are the declarations a user writes (``Joint(...)``) and the records the recursions fill.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import sympy as sp

JOINT_TYPES = ("revolute", "continuous", "prismatic", "fixed", "spherical", "floating")
#: the one-axis joints a spherical or floating joint stands for (suffix of the coordinate, type, axis):
#: translations along the joint frame's x, y, z, then the rotation ``Rz(yaw) Ry(pitch) Rx(roll)``
_COMPOSITE = {
    "spherical": (("yaw", "revolute", (0, 0, 1)), ("pitch", "revolute", (0, 1, 0)), ("roll", "revolute", (1, 0, 0))),
    "floating": (("x", "prismatic", (1, 0, 0)), ("y", "prismatic", (0, 1, 0)), ("z", "prismatic", (0, 0, 1)),
                 ("yaw", "revolute", (0, 0, 1)), ("pitch", "revolute", (0, 1, 0)), ("roll", "revolute", (1, 0, 0))),
}


@dataclass
class Joint:
    """A joint between a parent and a child body (see the module docstring for the types).

    ``xyz``/``rpy`` (or ``rotation``, a 3×3 matrix) place the joint frame in the parent's frame;
    ``post_xyz``/``post_rotation`` an optional fixed offset after the motion (a reversed joint,
    when a tree is re-rooted). ``lower``/``upper`` are limits (``None``: none). ``mimic`` names
    a model coordinate ``a`` that moves this joint by ``multiplier·a + offset`` (rad or m; a
    joint with a mimic has no coordinate of its own and its limits are not the model's).
    """

    type: str = "revolute"
    axis: Sequence[float] = (0.0, 0.0, 1.0)
    xyz: Sequence[float] = (0.0, 0.0, 0.0)
    rpy: Sequence[float] = (0.0, 0.0, 0.0)
    rotation: Any = None
    post_xyz: Sequence[float] | None = None
    post_rotation: Any = None
    lower: float | None = None
    upper: float | None = None
    mimic: str | None = None
    multiplier: float = 1.0
    offset: float = 0.0


@dataclass
class Body:
    """A rigid body of a tree, with its world-frame kinematics once added."""

    name: str
    parent: Body | None
    joint: Joint
    mass: sp.Expr
    com: sp.Matrix
    inertia: sp.Matrix
    #: the joint's angle or travel: a model coordinate, or ``k·a + c`` of one for a mimic joint
    #: (None for a fixed joint)
    coordinate: sp.Expr | None = None
    #: index in the model's q of the coordinate that moves the joint (None for a fixed joint)
    index: int | None = None
    #: ∂(the joint's angle)/∂q[index]: 1, or a mimic joint's multiplier
    multiplier: sp.Expr = field(default_factory=lambda: sp.Integer(1))
    #: the joint's rate, ``multiplier · q̇[index]`` (zero for a fixed joint)
    rate: sp.Expr = field(default_factory=lambda: sp.Integer(0))
    R: sp.Matrix = field(default_factory=lambda: sp.eye(3))      # body → world
    p: sp.Matrix = field(default_factory=lambda: sp.zeros(3, 1))  # body origin, world
    #: joint axis (world) and a point on it (world); zero axis for a fixed joint
    axis_w: sp.Matrix = field(default_factory=lambda: sp.zeros(3, 1))
    axis_point: sp.Matrix = field(default_factory=lambda: sp.zeros(3, 1))
    omega: sp.Matrix = field(default_factory=lambda: sp.zeros(3, 1))  # angular velocity, world
    vel: sp.Matrix = field(default_factory=lambda: sp.zeros(3, 1))    # velocity of the body origin

    @property
    def moving(self) -> bool:
        return self.coordinate is not None

    @property
    def com_world(self) -> sp.Matrix:
        return self.p + self.R * self.com
