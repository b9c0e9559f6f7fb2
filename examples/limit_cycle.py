"""Limit cycles of the compass gait at several slopes: fixed point, step time, Floquet multipliers.

The fixed point is the post-impact state (just after heel strike) that the one-step return map
sends back to itself; the multipliers are the eigenvalues of that map's Jacobian on the
post-impact section. All inside the unit circle: the gait is stable.

Run: ``python examples/limit_cycle.py``.
"""

import numpy as np

from amble import find_fixed_point
from amble.models import load

walker = load("compass-gait")
guess = None  # the first slope uses the model's own guess; each next one continues from the last
print(f"{'slope':>7} {'stance':>9} {'swing':>9} {'stance_dot':>11} {'swing_dot':>10} {'step [s]':>9}  |multipliers|")
for slope in (0.03, 0.04, 0.05, 0.06, 0.07):
    cycle = find_fixed_point(walker, guess, params={"slope": slope})
    guess = cycle.fixed_point
    mods = np.abs(cycle.multipliers)
    x = cycle.fixed_point
    print(f"{slope:7.3f} {x[0]:9.5f} {x[1]:9.5f} {x[2]:11.5f} {x[3]:10.5f} {cycle.step_time:9.5f}  "
          + ", ".join(f"{m:.4f}" for m in mods) + ("  stable" if cycle.stable else "  unstable"))
