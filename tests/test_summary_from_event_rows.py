"""The post-impact state a summary reports is read from the run's event rows without making the
Event objects: it is the state just after the last footfall, as the fast path ends a walk and as
the events themselves say, also when later events (a knee lock) are not footfalls."""

import numpy as np
import pytest

import amble
from amble.backend.kernels import compiled
from amble.models import load
from amble.simulation.engine import Options, run
from amble.simulation.simulate import parameter_vector


@pytest.mark.parametrize("samples", [True, False])
def test_post_impact_state_is_where_the_fast_path_ends(samples):
    system = load("compass-gait")
    k = compiled(system)
    x0 = np.array(system.default_start[k.meta["modes"][0]], float)
    fast = run(k, parameter_vector(k, None), 0, x0, steps=5, opts=Options(max_step_time=system.max_step_time))
    traj = amble.simulate(system, steps=5, samples=samples)
    post = traj.final_post_impact_state
    np.testing.assert_array_equal(post, fast.x)  # a walk of whole steps ends just after its last footfall
    assert traj.summary()["final_post_impact_state"] == fast.x.tolist()
    post[0] += 1.0  # a copy: the trajectory's own rows stay as they were
    np.testing.assert_array_equal(traj.final_post_impact_state, fast.x)


def test_a_knee_lock_after_the_last_footfall_is_not_the_post_impact_state():
    system = load("kneed-biped")
    walk = amble.simulate(system, steps=2)
    steps = {tr.name for tr in system.transitions if tr.step}
    last_step = [e for e in walk.events if e.name in steps][-1]
    # end the run after the next knee lock (a transition that is not a footfall), before its footfall
    lock = next(e for e in walk.events if e.t > walk.events[0].t and e.name not in steps)
    cut = amble.simulate(system, t_end=lock.t + 1e-3, samples=False)
    first_step = [e for e in walk.events if e.name in steps][0]
    # the last event is the knee lock, with a shorter post-event state (one coordinate fewer)
    assert cut.events[-1].name not in steps and cut.events[-1].x_post.size < first_step.x_post.size
    np.testing.assert_array_equal(cut.final_post_impact_state, first_step.x_post)
    np.testing.assert_array_equal(walk.final_post_impact_state, last_step.x_post)


def test_a_run_without_a_footfall_has_no_post_impact_state():
    system = load("compass-gait")
    traj = amble.simulate(system, t_end=0.05)
    assert len(traj.events) == 0 and traj.final_post_impact_state is None
    assert traj.summary()["final_post_impact_state"] is None
