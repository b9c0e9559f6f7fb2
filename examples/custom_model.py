"""A model written from scratch: a bouncing ball with K and V given outright and an Explicit reset.

Between bounces the ball falls freely, ``L = K − V`` with ``K = m ż²/2`` and ``V = m g z``. At
``z = 0`` (falling) the velocity is reversed and scaled by the coefficient of restitution ``e``.
The bounces come ever faster and accumulate at the finite time

    t∞ = sqrt(2 h / g) · (1 + e) / (1 − e)

(a Zeno execution). The simulator reports such a run as ``zeno`` instead of hanging; this
script compares where that happens with the closed form.

Run: ``python examples/custom_model.py``.
"""

import math

from amble import Explicit, Guard, HybridSystem, Model, simulate

ball = Model("ball")
(z,) = ball.coordinates("z")  # height above the floor, m
zd = ball.dot(z)  # vertical velocity, m/s
m, g, e = ball.parameters(m=1.0, g=9.81, e=0.5)
ball.K = m * zd**2 / 2  # energies written outright, no points needed
ball.V = m * g * z

system = HybridSystem("bouncing-ball", {"air": ball})
system.transition("bounce", "air", Guard(z, direction=-1), Explicit(q=[z], qd=[-e * zd]))

h = 1.0
run = simulate(system, [h, 0.0], t_end=10.0)
t_inf = math.sqrt(2 * h / 9.81) * (1 + 0.5) / (1 - 0.5)
print(f"status: {run.status} ({run.message})")
print(f"{len(run.events)} bounces, last at t = {run.events[-1].t:.6f} s; closed form t∞ = {t_inf:.6f} s")
energy = run.energy().sum(axis=1)
print(f"energy after the first bounce: {energy[run.t > run.events[0].t][0]:.6f} J "
      f"(closed form e² m g h = {0.25 * 9.81 * h:.6f} J)")
