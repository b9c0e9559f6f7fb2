"""Property-based tests: random chains, parameters and states obey the conservation laws, and
bad input only ever raises amble's typed errors."""

import contextlib
import errno
import io
import os
import tempfile
from pathlib import Path
from unittest import mock

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
    "99999999999999999999999", "slope=0.01:0.05:99999999999999999999999", "--period", "1", "x0=abcd",
]), max_size=6))
def test_cli_never_crashes(args):
    from amble.cli.main import main

    code = main(args)
    assert code in (0, 2)


# ---------------------------------------------------------------- hostile input and environment
# Each token stands for a class of mistake that once ended as an internal error or an untyped
# exception: huge counts (OverflowError, MemoryError), tolerances outside (0, 1) (IndexError),
# malformed states, foreign or damaged result files (ArrowInvalid, UnicodeDecodeError), a full
# disk (OSError 28, partial files) and a closed standard output (BrokenPipeError).
_FUZZ_DIR = Path(tempfile.mkdtemp(prefix="amble-fuzz-"))
_CORRUPT = _FUZZ_DIR / "corrupt.parquet"
_NONUTF8 = _FUZZ_DIR / "nonutf8.csv"
_COMMANDS = [
    ["simulate", "compass-gait"],
    ["limit-cycle", "compass-gait"],
    ["sweep", "compass-gait", "--param", "slope=0.04:0.05:2", "--scheduler", "synchronous"],
    ["sweep", "compass-gait", "--kind", "basin", "--x", "stance=-0.3:-0.2:2", "--x", "stance_dot=1:1.2:2",
     "--steps", "5", "--scheduler", "synchronous"],
]
_HOSTILE = [  # options with their values, so that most examples get past the argument parser
    ["--steps", "1"], ["--steps", "99999999999999999999999"], ["--period", "99999999999999999999"],
    ["--param", "slope=0.01:0.05:99999999999999999999999"], ["--param", "mh=9:10:600000"],
    ["--rtol", "1", "--atol", "1"], ["--rtol", "0"], ["--atol", "1e-300"], ["--start", "x0=abcd"],
    ["--start", "x0=-0.2,,0.3,1,0.3"], ["--guess", "x0=1e999,0,0,0"], ["--set", "g=0"], ["--set", "m=-5"],
    ["--out", str(_CORRUPT)], ["--out", str(_NONUTF8)], ["--out", "w.csv"], ["--out", "w.NPZ"],
    ["--out", "s.parquet"], ["--json"], ["--workers", "-1"], ["99999999999999999999999"],
]


class _ClosedPipe(io.StringIO):
    """Standard output whose reader has gone away."""

    def write(self, s: str) -> int:
        raise BrokenPipeError(32, "Broken pipe")


def _enospc(*args, **kwargs):
    raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))


@settings(max_examples=40, deadline=None, database=None, suppress_health_check=[HealthCheck.too_slow])
@given(command=st.sampled_from(_COMMANDS), extra=st.lists(st.sampled_from(_HOSTILE), max_size=3),
       full_disk=st.booleans(), closed_pipe=st.booleans())
def test_cli_hostile_input_and_environment(command, extra, full_disk, closed_pipe):
    from amble.analysis.store import ResultStore
    from amble.cli.main import main
    from amble.simulation.trajectory import Trajectory

    _CORRUPT.write_bytes(b"PAR1 but not really")
    _NONUTF8.write_bytes(b"i,j,slope\n0,0,\xff\n")
    here = os.getcwd()
    os.chdir(_FUZZ_DIR)
    try:
        with contextlib.ExitStack() as stack:
            if full_disk:
                stack.enter_context(mock.patch.object(Trajectory, "save", _enospc))
                stack.enter_context(mock.patch.object(ResultStore, "_write_compacted", _enospc))
            if closed_pipe:
                stack.enter_context(contextlib.redirect_stdout(_ClosedPipe()))
            stack.enter_context(contextlib.redirect_stderr(io.StringIO()))
            code = main(command + [token for option in extra for token in option])
    finally:
        os.chdir(here)
    assert code in (0, 2, 141)
    assert code != 141 or closed_pipe
    if command[0] == "sweep":  # a result file that cannot be read is never overwritten (simulate replaces its --out)
        assert _CORRUPT.read_bytes() == b"PAR1 but not really"
        assert _NONUTF8.read_bytes() == b"i,j,slope\n0,0,\xff\n"
    leftovers = [p.name for p in _FUZZ_DIR.iterdir() if any(t in p.name for t in (".part", ".tmp", ".probe"))]
    assert not leftovers, leftovers
