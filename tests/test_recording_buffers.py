"""Recording buffers are reused from run to run (per thread): a trajectory never shares memory
with them, and concurrent runs in threads record what each alone records."""

from concurrent.futures import ThreadPoolExecutor

import numpy as np

import amble
from amble.models import load


def test_a_later_run_leaves_an_earlier_trajectory_alone():
    system = load("compass-gait")
    a = amble.simulate(system, steps=3)
    kept = (a.t.copy(), a.x.copy(), [e.x_post.copy() for e in a.events])
    b = amble.simulate(system, [0.1, -0.05, -0.9, 0.3], steps=2)  # another start: other rows
    assert not np.array_equal(b.x[: len(a.x)], a.x[: len(b.x)])
    np.testing.assert_array_equal(a.t, kept[0])
    np.testing.assert_array_equal(a.x, kept[1])
    for e, post in zip(a.events, kept[2]):
        np.testing.assert_array_equal(e.x_post, post)


def test_threads_record_as_a_single_run_does():
    system = load("compass-gait")
    starts = [None, [0.1, -0.05, -0.9, 0.3]] * 3
    alone = [amble.simulate(system, x, steps=2) for x in starts[:2]]
    with ThreadPoolExecutor(2) as pool:
        together = list(pool.map(lambda x: amble.simulate(system, x, steps=2), starts))
    for i, tr in enumerate(together):
        ref = alone[i % 2]
        np.testing.assert_array_equal(tr.t, ref.t)
        np.testing.assert_array_equal(tr.x, ref.x)
