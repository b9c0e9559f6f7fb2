"""Recording a run changes nothing about the run: ``simulate()`` on its output grid ends where the
lean compiled call ends and sees the same events, bit for bit; its events are a sequence that
reads, compares and pickles as a list of :class:`Event`."""

import pickle

import numpy as np

import amble
from amble.simulation.engine import Options, run
from amble.simulation.simulate import parameter_vector
from amble.simulation.trajectory import Event


def test_recorded_run_ends_where_the_fast_path_ends(compass_built):
    system, k = compass_built
    p = parameter_vector(k, None)
    x0 = np.array(system.default_start[k.meta["modes"][0]], float)
    fast = run(k, p, 0, x0, steps=6, opts=Options(max_step_time=system.max_step_time))
    traj = amble.simulate(system, steps=6)
    assert traj.status == fast.status == "completed"
    np.testing.assert_array_equal(traj.final_state, fast.x)  # exactly: the grid only reads the dense output
    assert traj.t[-1] == fast.t
    # the events of the same run recorded without samples (events only) are the same, exactly
    lean = amble.simulate(system, steps=6, samples=False)
    assert len(traj.events) == len(lean.events) == 6
    for a, b in zip(traj.events, lean.events):
        assert (a.t, a.name, a.source, a.target) == (b.t, b.name, b.source, b.target)
        np.testing.assert_array_equal(a.x_pre, b.x_pre)
        np.testing.assert_array_equal(a.x_post, b.x_post)
    np.testing.assert_array_equal(traj.events[-1].x_post, fast.x)


def test_events_read_as_a_list(compass_built):
    system, _ = compass_built
    traj = amble.simulate(system, steps=3)
    ev = traj.events
    assert len(ev) == 3 and all(isinstance(e, Event) for e in ev)
    assert ev[-1] is ev[2] and list(ev[1:]) == [ev[1], ev[2]]
    assert ev == list(ev) and ev != list(ev)[:2]
    times = [e.t for e in ev]
    assert times == sorted(times) and times[0] > 0
    # each event's pre-event state lies on the guard row recorded at the same time
    for e in ev:
        row = np.flatnonzero(traj.t == e.t)[0]
        np.testing.assert_array_equal(traj.x[row, : e.x_pre.size], e.x_pre)
    back = pickle.loads(pickle.dumps(traj.events))
    assert isinstance(back, list) and [e.t for e in back] == times
