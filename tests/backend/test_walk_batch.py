"""Many walks in one compiled call (basin maps, sweeps): each walk as the one-at-a-time loop
over ``engine.run`` walks it, the fixed point converging at once and a hopeless start falling."""

import math

import numpy as np
import pytest

from amble.analysis.poincare import find_fixed_point
from amble.backend.abi import CODE
from amble.backend.kernels import compiled
from amble.errors import StateError
from amble.models import load
from amble.simulation.engine import Options, run


@pytest.fixture(scope="module")
def walker():
    system = load("compass-gait")
    k = compiled(system)
    p = np.array(k.meta["param_defaults"], float)
    xs = find_fixed_point(system).fixed_point
    return system, k, p, xs


def _one_at_a_time(k, p, x, xs, opts, steps, check_every, tol):
    done, dist, code = 0, math.nan, CODE["STEPS_DONE"]
    while done < steps:
        m = min(check_every, steps - done)
        r = run(k, p, 0, x, steps=m, opts=opts)
        x = r.x
        if not r.completed:
            return r.code, done + r.steps, dist, x
        done += m
        dist = float(np.max(np.abs(x - xs)))
        if dist < tol:
            break
    return code, done, dist, x


def test_batch_walks_as_the_python_loop_does(walker):
    system, k, p, xs = walker
    opts = Options(rtol=1e-8, atol=1e-8, max_step_time=system.max_step_time)
    rng = np.random.default_rng(3)
    x0 = xs + rng.normal(0, [0.05, 0.05, 0.3, 0.3], size=(12, 4))
    x0[:, 1] = 2 * p[k.meta["params"].index("slope")] - x0[:, 0]  # on the section
    out = k.walk_batch(0, x0, p, _opt(opts), opts._iopt, xs, 30, 5, 1e-4)
    for r in range(len(x0)):
        code, done, dist, x = _one_at_a_time(k, p, x0[r], xs, opts, 30, 5, 1e-4)
        assert out["code"][r] == code and out["steps"][r] == done
        assert out["distance"][r] == dist or (math.isnan(dist) and math.isnan(out["distance"][r]))
        np.testing.assert_array_equal(out["x"][r, :4], x)
    assert set(out["code"].tolist()) >= {CODE["STEPS_DONE"]}


def _opt(opts):
    o = opts._opt.copy()
    o[0] = math.inf  # no end time: the walks end by footfalls
    return o


def test_fixed_point_converges_and_a_bad_start_falls(walker):
    system, k, p, xs = walker
    opts = Options(rtol=1e-10, atol=1e-10, max_step_time=system.max_step_time)
    bad = xs.copy()
    bad[2] = -2.0  # thrown backwards: it falls
    out = k.walk_batch(0, np.vstack([xs, bad]), p, _opt(opts), opts._iopt, xs, 20, 5, 1e-6)
    assert out["code"][0] == CODE["STEPS_DONE"] and out["steps"][0] == 5 and out["distance"][0] < 1e-6
    assert out["code"][1] != CODE["STEPS_DONE"] and out["steps"][1] < 20


def test_batch_refuses_states_of_the_wrong_length(walker):
    system, k, p, xs = walker
    opts = Options()
    with pytest.raises(StateError):
        k.walk_batch(0, np.zeros((3, 5)), p, _opt(opts), opts._iopt, xs, 5, 5, 1e-6)


def test_threads_share_the_walks_and_change_none(walker):
    """Two and three threads taking rows from one counter give every walk exactly as one thread
    does (each row is walked whole by whichever thread takes it), with walks of very unequal
    length (some fall at once, some walk all their steps)."""
    system, k, p, xs = walker
    opts = Options(rtol=1e-8, atol=1e-8, max_step_time=system.max_step_time)
    rng = np.random.default_rng(7)
    x0 = xs + rng.normal(0, [0.08, 0.08, 0.5, 0.5], size=(40, 4))
    x0[:, 1] = 2 * p[k.meta["params"].index("slope")] - x0[:, 0]
    one = k.walk_batch(0, x0, p, _opt(opts), opts._iopt, xs, 25, 5, 1e-4)
    assert len(set(one["steps"].tolist())) > 2  # unequal walks
    for threads in (2, 3):
        many = k.walk_batch(0, x0, p, _opt(opts), opts._iopt, xs, 25, 5, 1e-4, threads=threads)
        for f in ("code", "info", "steps", "distance", "x"):
            np.testing.assert_array_equal(many[f], one[f])


@pytest.mark.parametrize("bad", [0, -1, 1.5, True, "2"])
def test_threads_must_be_a_positive_integer(walker, bad):
    system, k, p, xs = walker
    opts = Options()
    with pytest.raises(StateError, match="threads"):
        k.walk_batch(0, xs[None, :], p, _opt(opts), opts._iopt, xs, 5, 5, 1e-6, threads=bad)


def test_batch_walks_with_every_run_option_as_the_loop_does(walker):
    """Every field of the run options reaches each walk: the implicit integrator (the last field)
    and a finer guard screening give the loop's results bit for bit, not the defaults'."""
    system, _, p, xs = walker
    k = compiled(system, derivatives=True)  # Radau needs the Jacobian kernels
    x0 = np.array([xs, xs + np.array([0.02, -0.02, 0.1, 0.0])])
    for opts in (Options(rtol=1e-8, atol=1e-8, max_step_time=system.max_step_time, method="radau"),
                 Options(rtol=1e-8, atol=1e-8, max_step_time=system.max_step_time, nsub=3)):
        out = k.walk_batch(0, x0, p, _opt(opts), opts._iopt, xs, 6, 3, 1e-12)
        for r in range(len(x0)):
            code, done, dist, x = _one_at_a_time(k, p, x0[r], xs, opts, 6, 3, 1e-12)
            assert out["code"][r] == code and out["steps"][r] == done
            np.testing.assert_array_equal(out["x"][r, :4], x)
    # and the two integrators do differ here, so the comparison above can tell them apart
    dop = run(k, p, 0, x0[1], steps=3, opts=Options(rtol=1e-8, atol=1e-8, max_step_time=system.max_step_time))
    rad = run(k, p, 0, x0[1], steps=3, opts=Options(rtol=1e-8, atol=1e-8, max_step_time=system.max_step_time,
                                                      method="radau"))
    assert not np.array_equal(dop.x, rad.x)
