"""Property-based tests: random chains, parameters and states obey the conservation laws, and
bad input only ever raises amble's typed errors."""

import numpy as np
from chains import pendulum_chain
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import amble
from amble import HybridSystem

_SYSTEMS: dict[int, HybridSystem] = {}


def chain(n: int) -> HybridSystem:
    """An n-link planar pendulum (point masses at link ends, absolute angles), compiled once per n."""
    if n not in _SYSTEMS:
        m = pendulum_chain(n, f"fuzz-chain-{n}")
        _SYSTEMS[n] = HybridSystem(m.name, m)
    return _SYSTEMS[n]


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    n=st.integers(1, 4),
    masses=st.lists(st.floats(0.1, 10.0), min_size=4, max_size=4),
    lengths=st.lists(st.floats(0.1, 2.0), min_size=4, max_size=4),
    state=st.lists(st.floats(-3.0, 3.0), min_size=8, max_size=8),
)
def test_random_chains_conserve_energy(n, masses, lengths, state):
    sys_ = chain(n)
    params = {**{f"m{i}": masses[i] for i in range(n)}, **{f"l{i}": lengths[i] for i in range(n)}}
    x0 = state[:n] + state[4 : 4 + n]
    tr = amble.simulate(sys_, x0, params=params, t_end=0.5, rtol=1e-12, atol=1e-12, sample_dt=0.05)
    assert tr.status == "end_time", tr.message
    e = tr.energy().sum(axis=1)
    scale = max(1.0, float(np.max(np.abs(tr.energy()))))
    assert np.max(np.abs(e - e[0])) <= 1e-8 * scale


@settings(max_examples=40, deadline=None)
@given(args=st.lists(st.sampled_from([
    "simulate", "limit-cycle", "equations", "models", "sweep", "compass-gait", "nope", "--steps", "0", "-3",
    "--set", "slope=0.05", "slope=x", "=1", "--time", "-1", "nan", "--json", "--start", "x0=1", "fixed-point",
    "--out", "/nonexistent/x.csv", "x.txt", "--param", "slope=0.1:0.01:3", "slope=a:b:c", "--rtol", "inf",
]), max_size=6))
def test_cli_never_crashes(args):
    from amble.cli.main import main

    code = main(args)
    assert code in (0, 2)
