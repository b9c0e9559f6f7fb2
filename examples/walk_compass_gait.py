"""Walk the compass gait down a slope: simulate, plot, and write an offline 3D animation.

Run: ``python examples/walk_compass_gait.py``; writes ``compass_walk.png`` and ``compass_walk.html``
into the current directory.
"""

from amble import simulate
from amble.models import load
from amble.viz import animate, plot_trajectory

walker = load("compass-gait")
# Start near the thesis' gait (state: stance, swing, stance_dot, swing_dot in rad, rad/s).
walk = simulate(walker, [-0.2, 0.3, 1.0, 0.3], steps=10, params={"slope": 0.05})

print(walk.status, "-", walk.message)
print("footfalls at t =", ", ".join(f"{e.t:.4f}" for e in walk.step_events[:5]), "... s")
print("post-impact state:", walk.final_post_impact_state)

plot_trajectory(walk, "compass_walk.png")  # angles and energies over time, footfalls marked
animate(walk, "compass_walk.html")  # open in a browser; works offline
print("wrote compass_walk.png and compass_walk.html")
