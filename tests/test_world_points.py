"""World positions of a run recorded without samples: only its ends are rows, and every footfall
between them still moves the frame (each from its own pre-impact state), so the ends agree with
the same run recorded densely, whose pre- and post-impact rows carry the frame changes."""

import numpy as np
import pytest

from amble import find_fixed_point, simulate
from amble.models import load


@pytest.mark.parametrize("name, steps", [("compass-gait", 3), ("slip-biped-runner", 2), ("kneed-biped", 2)])
def test_a_run_without_samples_ends_where_the_sampled_run_ends(name, steps):
    s = load(name)
    x0 = find_fixed_point(s).fixed_point
    dense = simulate(s, x0, steps=steps)
    ends = simulate(s, x0, steps=steps, samples=False)
    assert len(ends.t) == 2 and len(ends.events) >= steps
    wd, we = dense.world_points(), ends.world_points()
    travel = 0.0
    for p in wd:
        np.testing.assert_allclose(we[p][0], wd[p][0], rtol=0, atol=1e-12)
        np.testing.assert_allclose(we[p][-1], wd[p][-1], rtol=0, atol=1e-9)
        travel = max(travel, abs(wd[p][-1, 0] - wd[p][0, 0]))
    assert travel > 0.1 * steps  # the walker went somewhere: the check is not of a standing frame
