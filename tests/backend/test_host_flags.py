"""Native code by default: keyed by the processor, dropped for a compiler that refuses it, and
bitwise the same results as a build for the baseline instruction set."""

import numpy as np
import pytest

from amble.backend import cache, host, index, kernels
from amble.models import load
from amble.simulation.engine import Options, run
from amble.simulation.simulate import parameter_vector


def test_native_setting_carries_the_processor(monkeypatch):
    monkeypatch.delenv("AMBLE_CFLAGS", raising=False)
    assert "-march=native" in host.flags_setting()
    assert host.cpu_identity() in host.flags_setting()
    monkeypatch.setenv("AMBLE_CFLAGS", "-O2")
    assert host.flags_setting() == "-O2"  # portable code: the processor does not matter


def test_keys_change_with_the_processor_only_for_native_code(compass, monkeypatch):
    monkeypatch.delenv("AMBLE_CFLAGS", raising=False)
    a = kernels.structure_key(compass)
    ia = index.index_key("compass-gait", [])
    monkeypatch.setattr(host, "cpu_identity", lambda: "another processor")
    host._setting.cache_clear()
    assert kernels.structure_key(compass) != a
    assert index.index_key("compass-gait", []) != ia
    monkeypatch.setenv("AMBLE_CFLAGS", "-O2")
    b = kernels.structure_key(compass)
    monkeypatch.setattr(host, "cpu_identity", lambda: "a third processor")
    host._setting.cache_clear()
    assert kernels.structure_key(compass) == b
    host._setting.cache_clear()  # the real processor's setting for the tests after this one


def test_native_options_dropped_if_the_compiler_refuses_them(monkeypatch):
    monkeypatch.setenv("AMBLE_CFLAGS", "-O2 -march=native -ffp-contract=off")
    monkeypatch.setattr(host, "_accepts", lambda cc, flags: False)
    assert host.cflags("cc") == ["-O2", "-ffp-contract=off"]
    monkeypatch.setattr(host, "_accepts", lambda cc, flags: True)
    assert host.cflags("cc") == ["-O2", "-march=native", "-ffp-contract=off"]


def test_the_installed_compiler_accepts_or_refuses_cleanly():
    # a real probe: either answer is fine, but it must answer (no exception, no hang)
    assert host._accepts(cache.compiler(), ("-march=native",)) in (True, False)
    assert host._accepts(cache.compiler(), ("-this-flag-does-not-exist",)) is False


@pytest.mark.parametrize("tol", [1e-8, 1e-10])
def test_native_and_portable_builds_walk_bitwise_alike(monkeypatch, tmp_path, tol):
    """Contraction off: vector instructions change the speed, not one bit of the result."""
    system = load("compass-gait")
    x0 = np.array([-0.2168, 0.3168, 1.0839, 0.3981])
    finals = []
    for flags in (None, "-O2"):
        if flags is None:
            monkeypatch.delenv("AMBLE_CFLAGS", raising=False)
        else:
            monkeypatch.setenv("AMBLE_CFLAGS", flags)
        monkeypatch.setenv("AMBLE_CACHE_DIR", str(tmp_path / (flags or "native").strip("-")))
        k = kernels.compiled(system)
        p = parameter_vector(k, {})
        r = run(k, p, 0, x0, steps=20, opts=Options(rtol=tol, atol=tol))
        assert r.code == 2
        finals.append(np.asarray(r.x).tobytes())
    assert finals[0] == finals[1]
