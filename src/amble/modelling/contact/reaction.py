"""What the ground must supply: the contact force and impulse from the whole robot's momentum.

A model pinned at its stance foot says nothing about whether the ground can hold it there.
Newton's law for the whole robot answers it independently of the equations of motion: the
ground's force on the stance foot is the rate of the total linear momentum less gravity,

    F = d²/dt² (Σ mᵢ pᵢ) − (Σ mᵢ) g          (N, world axes of the step's frame)

and the ground's impulse at a footfall is the jump of the total linear momentum
``ΔP = Σ mᵢ (vᵢ⁺ − vᵢ⁻)`` (N·s). Rotational inertia carries no linear momentum, so the point
masses of the model (including the bodies of a rigid-body tree, at their centres of mass) are
all that enter. One definition serves the feasibility checks of a simulated gait
(:func:`amble.check_gait`) and the contact constraints of gait optimisation (the CasADi export).
"""

from __future__ import annotations

import sympy as sp

from ..model import Model


def total_mass(model: Model) -> sp.Expr:
    """``Σ mᵢ`` (kg) over the model's point masses."""
    return sum(model.masses.values(), sp.Integer(0))


def mass_moment(model: Model) -> sp.Matrix:
    """``Σ mᵢ pᵢ`` (kg·m; the total mass times the centre of mass), ``dims`` components."""
    moment = sp.zeros(model.dims, 1)
    for name, m in model.masses.items():
        moment += m * model.points[name]
    return moment


def linear_momentum(model: Model) -> sp.Matrix:
    """``P = Σ mᵢ vᵢ`` (kg·m/s) in the coordinates and their rates."""
    return model.jacobian(mass_moment(model)) * sp.Matrix(model.qd)


def accelerations(model: Model) -> list[sp.Symbol]:
    """Symbols ``<q>__ddot`` standing for the coordinates' accelerations in :func:`ground_force`."""
    return [sp.Symbol(f"{s}__ddot", real=True) for s in model.q]


def ground_force(model: Model) -> sp.Matrix:
    """The ground's force on the stance foot ``Ṗ − (Σ mᵢ) g`` (N, module docstring) in the
    coordinates, their rates and their accelerations (:func:`accelerations`)."""
    v = linear_momentum(model)
    qdd = sp.Matrix(accelerations(model))
    rate = v.jacobian(model.q) * sp.Matrix(model.qd) + v.jacobian(model.qd) * qdd
    return rate - total_mass(model) * model.gravity_vector
