"""Small systems for the event tests: a pendulum with a switching torque, a Coulomb-damped
pendulum, a pendulum with a guard at a chosen angle."""

import sympy as sp

from amble import Guard, HybridSystem, Model


def pendulum(name: str, torque=None, g: float = 9.81) -> tuple[Model, sp.Symbol]:
    """A unit point mass on a unit massless rod, angle ``theta`` from the downward vertical;
    ``torque(theta, theta_dot, model)`` adds a torque on ``theta``."""
    m = Model(name)
    (th,) = m.coordinates(["theta"])
    (grav,) = m.parameters(g=g)
    m.point("bob", sp.Matrix([sp.sin(th), -sp.cos(th)]), mass=1.0)
    m.gravity(grav)
    if torque is not None:
        m.torque(torque(th, m.dot(th), m), th)
    return m, th


def switching_pendulum(name: str = "ev-switching") -> HybridSystem:
    """A switching controller: τ = −20 if θ + 0.5 θ̇ > 0 else +20."""
    m, _ = pendulum(name, lambda th, thd, _: sp.Piecewise((-20, th + 0.5 * thd > 0), (20, True)))
    return HybridSystem(name, m)


def coulomb_pendulum(name: str = "ev-coulomb") -> HybridSystem:
    """Coulomb friction τ = −6 sign(θ̇)."""
    m, _ = pendulum(name, lambda th, thd, _: -6 * sp.sign(thd))
    return HybridSystem(name, m)


def guarded_pendulum(name: str = "ev-guarded") -> HybridSystem:
    """A pendulum whose terminal guard ``A − θ`` (falling) fires when θ exceeds the parameter A."""
    m, th = pendulum(name)
    (a,) = m.parameters(A=0.5)
    s = HybridSystem(name, m)
    s.terminal("past_A", name, Guard(a - th, -1), status="past_A")
    return s
