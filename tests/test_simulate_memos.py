"""What simulate() works out once and reuses — parameter vectors, laid-out options — gives what a
fresh computation gives, hands every caller its own arrays, and still refuses what it refused."""

import numpy as np
import pytest

import amble
from amble import ParameterError
from amble.backend.kernels import compiled
from amble.models import load
from amble.simulation.engine import Options, run
from amble.simulation.simulate import parameter_vector


def test_a_parameter_vector_is_the_defaults_with_the_overrides(compass_built):
    system, k = compass_built
    names, defaults = k.meta["params"], k.meta["param_defaults"]
    for _ in range(3):  # the first call works it out, the next ones reuse it
        p = parameter_vector(k, {"slope": 0.06, "m": 4}, system)
        expected = [0.06 if n == "slope" else 4.0 if n == "m" else d for n, d in zip(names, defaults)]
        assert p.tolist() == expected and p.dtype == np.float64
    a, b = parameter_vector(k, None), parameter_vector(k, None)
    assert a is not b and a.tolist() == b.tolist() == list(defaults)
    a[0] = -1.0  # each caller owns its array: the next call is not affected
    assert parameter_vector(k, None).tolist() == list(defaults)
    tr = amble.simulate(system, steps=1)
    tr.params[:] = 0.0
    assert amble.simulate(system, steps=1).params.tolist() == list(defaults)


def test_a_value_refused_once_is_refused_every_time(compass_built):
    system, k = compass_built
    for _ in range(2):
        with pytest.raises(ParameterError, match="outside its domain"):
            parameter_vector(k, {"m": -5.0}, system)
        with pytest.raises(ParameterError, match="must be finite"):
            parameter_vector(k, {"m": float("nan")}, system)
        with pytest.raises(ParameterError, match="unknown parameter"):
            parameter_vector(k, {"nope": 1.0}, system)


def test_a_domain_is_checked_on_every_call(compass_built):
    """A vector worked out without a system (no domain check) is still checked when a system comes."""
    system, k = compass_built
    parameter_vector(k, {"slope": 100.0})  # no system: no domain to check
    with pytest.raises(ParameterError, match="outside its domain"):
        parameter_vector(k, {"slope": 100.0}, system)


def test_a_new_domain_is_seen_by_the_next_call():
    system = load("compass-gait")
    k = compiled(system)
    parameter_vector(k, {"a": 0.4}, system)  # inside the default domain
    mode = system.modes[system.mode_names[0]]
    saved = dict(mode.domains)
    try:
        mode.domains["a"] = amble.interval(0.45, 1.0)
        with pytest.raises(ParameterError, match="outside its domain"):
            parameter_vector(k, {"a": 0.4}, system)
    finally:
        mode.domains.clear()
        mode.domains.update(saved)


def test_new_options_per_call_give_the_run_of_equal_options(compass_built):
    system, k = compass_built
    x0 = np.array(system.default_start[system.mode_names[0]], float)
    fast = run(k, parameter_vector(k, None), 0, x0, steps=2,
               opts=Options(rtol=1e-8, atol=1e-9, max_step_time=system.max_step_time))
    for _ in range(3):  # a new Options object each time, and one kept
        tr = amble.simulate(system, steps=2, options=Options(rtol=1e-8, atol=1e-9))
        np.testing.assert_array_equal(tr.final_state, fast.x)
    kept = Options(rtol=1e-8, atol=1e-9)
    for _ in range(2):
        np.testing.assert_array_equal(amble.simulate(system, steps=2, options=kept).final_state, fast.x)
    # the tolerances of the call win over those of the options, as before
    loose = amble.simulate(system, steps=2, options=kept, rtol=1e-5, atol=1e-5)
    assert not np.array_equal(loose.final_state, fast.x)
